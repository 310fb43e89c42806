#ifndef PIC_SHADERS_SHARED_CACHE_SHADING_H
#define PIC_SHADERS_SHARED_CACHE_SHADING_H
// Shading a G-buffer from the caches on the GPU (render/passes/cache_shading_pass.h; CPU twin
// render/cpu/cache_shading.cpp): direct light through the shadow maps, the cache term from
// the light map (bilinear) or the grid (trilinear), emission. Specialization constants:
// 0 lY, 1 lC.
#include "glue.h"

PIC_NAMESPACE_BEGIN

PIC_CONST(uint, kCacheShadingGroup, 64u);
PIC_CONST(uint, kShadeFull, 0u);      // emission + direct + indirect
PIC_CONST(uint, kShadeDirect, 1u);    // punctual lights, shadow-mapped
PIC_CONST(uint, kShadeIndirect, 2u);  // the cache term
PIC_CONST(uint, kShadeGlossy, 3u);    // the cache term's glossy lobe alone

struct CacheShadingPush {
    vec3 eye;             // metres: the camera (the glossy lobe's view direction)
    uint component;       // kShadeFull, kShadeDirect, kShadeIndirect, kShadeGlossy
    vec3 gridOrigin;      // metres, grid vertex (0, 0, 0)
    float gridCellSize;   // metres; 0: no grid (the grid term is zero)
    uvec3 gridDims;       // grid vertices per axis
    uint lightCount;      // lights to sum (0 for the indirect component)
    uint width;           // pixels
    uint height;          // pixels
    uint lightmapWidth;   // texels (0: no light map; every surface reads the grid)
    uint lightmapHeight;  // texels
    float epsilon;        // metres: the CPU twin's ray offset along the normal
    uint accumulate;      // 0: write the pixel's radiance, 1: add to it (subsamples)
    float glossyWeight;   // factor on the glossy lobe (0: diffuse only)
    uint firstPixel;      // pixel of invocation 0 (large images take several dispatches)
    vec4 glossyLobe[2];   // s_l(n) of band l at [l / 4][l % 4] (core/sh.h cosineLobeFactor)
    float yScale;         // on the cache term's luma (core/light_set.h IndirectScale)
    float cocgScale;      // on its chroma
    uint pad1;
    uint pad2;
};
PIC_STRUCT_CHECK(CacheShadingPush, 128);
PIC_OFFSET_CHECK(CacheShadingPush, component, 12);
PIC_OFFSET_CHECK(CacheShadingPush, gridCellSize, 28);
PIC_OFFSET_CHECK(CacheShadingPush, lightCount, 44);
PIC_OFFSET_CHECK(CacheShadingPush, epsilon, 64);
PIC_OFFSET_CHECK(CacheShadingPush, glossyLobe, 80);

PIC_NAMESPACE_END

#endif
