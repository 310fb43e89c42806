#ifndef PIC_SHADERS_SHARED_SHADOW_MAP_H
#define PIC_SHADERS_SHARED_SHADOW_MAP_H
// Shadow maps (paper 000 Figure 2 step 1): the lights as the surfel-lighting pass reads them,
// and the rasteriser's push constants. Every light owns consecutive layers of one depth
// array: 6 cube faces (+x, −x, +y, −y, +z, −z) for point lights and wide spots, 1 layer for
// narrow spots (perspective) and directional lights (orthographic over the scene).
#include "glue.h"

PIC_NAMESPACE_BEGIN

PIC_CONST(uint, kLightPoint, 0u);
PIC_CONST(uint, kLightSpot, 1u);
PIC_CONST(uint, kLightDirectional, 2u);
PIC_CONST(uint, kShadowCube, 0u);         // 6 perspective faces of 90°
PIC_CONST(uint, kShadowPerspective, 1u);  // one perspective layer (spot)
PIC_CONST(uint, kShadowOrthographic, 2u); // one orthographic layer (directional)

struct GpuLight {
    vec3 position;       // metres (point, spot)
    uint type;           // kLightPoint, kLightSpot, kLightDirectional
    vec3 direction;      // unit, the direction light travels (spot, directional)
    float range;         // metres; 0 = no cut-off
    vec3 radiant;        // intensity × colour: W/sr (point, spot) or W/m² (directional)
    float cosOuter;      // spot: cos of the outer half-angle
    float cosInner;      // spot: cos of the inner half-angle
    uint shadowKind;     // kShadowCube, kShadowPerspective, kShadowOrthographic
    uint firstLayer;     // its first layer in the depth array
    float depthNear;     // metres: perspective near plane, or orthographic depth of z = 0
    float depthFar;      // metres: perspective far plane, or orthographic depth of z = 1
    uint hardCone;       // spot: 1 when inner ≥ outer (hard edge)
    uint pad0;
    uint pad1;
};
PIC_STRUCT_CHECK(GpuLight, 80);
#ifndef __cplusplus
// Light k of a uniform texel buffer of RGBA32UI texels, five per record (as fetchSurfel in
// bake_layout.h).
GpuLight fetchLight(usamplerBuffer records, uint k) {
    const int t = int(k) * 5;
    const uvec4 a = texelFetch(records, t);
    const uvec4 b = texelFetch(records, t + 1);
    const uvec4 c = texelFetch(records, t + 2);
    const uvec4 d = texelFetch(records, t + 3);
    const uvec4 e = texelFetch(records, t + 4);
    return GpuLight(uintBitsToFloat(a.xyz), a.w, uintBitsToFloat(b.xyz), uintBitsToFloat(b.w),
                    uintBitsToFloat(c.xyz), uintBitsToFloat(c.w), uintBitsToFloat(d.x), d.y, d.z,
                    uintBitsToFloat(d.w), uintBitsToFloat(e.x), e.y, e.z, e.w);
}
#endif

// One layer of the depth array as the passes that sample it read it. Layers of one light
// may differ in side: each is as wide as its own receivers need (footprint sides).
struct GpuShadowLayer {
    mat4 clipFromWorld;
    float texelSlope;  // perspective: texel width per metre of depth; ortho: texel width (m)
    uint side;         // texels per side: the layer uses its top-left side × side texels
    uint pad0;
    uint pad1;
};
PIC_STRUCT_CHECK(GpuShadowLayer, 80);

// Push constants of the rasteriser: one layer's clip-from-world matrix and its side.
struct ShadowMapPush {
    mat4 clipFromWorld;
    vec2 viewport;  // texels: the layer's side, twice (lib/subpixel.glsl snapToSubpixels)
    vec2 pad0;
};
PIC_STRUCT_CHECK(ShadowMapPush, 80);

PIC_NAMESPACE_END

#endif
