#ifndef PIC_SHADERS_SHARED_SURFEL_LIGHTING_H
#define PIC_SHADERS_SHARED_SURFEL_LIGHTING_H
// Surfel lighting (paper 000 Figure 2 step 2): push constants and the per-surfel cache
// stencil of the bounce part (core/cache_values.h CacheStencil, computed once per bake).
#include "glue.h"

PIC_NAMESPACE_BEGIN

PIC_CONST(uint, kSurfelLightingGroup, 64u);
// The pass's mode (specialization constant 2):
PIC_CONST(uint, kSurfelModeDirect, 0u);  // directFlux = lights + emission; leaves = directFlux
PIC_CONST(uint, kSurfelModeBounce, 1u);  // leaves = directFlux + ρ·A·E(previous caches)
PIC_CONST(uint, kSurfelModeDirectRays, 2u);  // as Direct, V from host-traced rays, not shadow maps

// Up to 8 caches and weights; unused slots have weight 0 (and cache 0).
struct SurfelStencil {
    uvec4 cacheLow;   // caches 0–3
    uvec4 cacheHigh;  // caches 4–7
    vec4 weightLow;
    vec4 weightHigh;
};
PIC_STRUCT_CHECK(SurfelStencil, 64);
#ifndef __cplusplus
// Stencil i of a uniform texel buffer of RGBA32UI texels, four per record (as fetchSurfel in
// bake_layout.h).
SurfelStencil fetchStencil(usamplerBuffer records, uint i) {
    const int t = int(i) * 4;
    return SurfelStencil(texelFetch(records, t), texelFetch(records, t + 1),
                         uintBitsToFloat(texelFetch(records, t + 2)),
                         uintBitsToFloat(texelFetch(records, t + 3)));
}
#endif

struct SurfelLightingPush {
    uint surfelCount;  // nS
    uint lightCount;
    float epsilon;     // metres: the CPU twin's ray offset along the normal
    uint sumSlot;      // 0 or 1: which half of groupFlux takes this pass's workgroup sums
    vec4 tail;         // bounce: xyz per channel, leaves = S' + tail·max(S' − S, 0) (BounceSchedule)
    uint sky;          // direct: 1 adds the sky through each surfel's transfer
    uint pad0;
    uint pad1;
    uint pad2;
};
PIC_STRUCT_CHECK(SurfelLightingPush, 48);

PIC_NAMESPACE_END

#endif
