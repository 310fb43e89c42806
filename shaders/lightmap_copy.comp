#version 460
// Light-map copy (paper 000 Figure 2 step 5): each grid vertex or light-map texel takes its
// cache's coefficients, one layer per coefficient; no cache → 0. CPU twin:
// copyCachesToTextures in core/cache_textures.cpp (core/cache_textures.h documents the layout).
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#extension GL_EXT_shader_16bit_storage : require
#extension GL_EXT_shader_explicit_arithmetic_types_float16 : require
#include "shared/bake_layout.h"
#include "shared/lightmap_copy.h"

layout(local_size_x = 256) in;
layout(constant_id = 0) const uint kBandsY = 3u;
layout(constant_id = 1) const uint kBandsC = 2u;
const uint kCountY = kBandsY * kBandsY;
const uint kCountC = kBandsC * kBandsC;

layout(std430, binding = 0) readonly buffer CacheIndex { uint cacheIndex[]; };
layout(std430, binding = 1) readonly buffer CacheY { float16_t cacheY[]; };
layout(std430, binding = 2) readonly buffer CacheCo { float16_t cacheCo[]; };
layout(std430, binding = 3) readonly buffer CacheCg { float16_t cacheCg[]; };
layout(std430, binding = 4) writeonly buffer LayersY { float16_t layersY[]; };
layout(std430, binding = 5) writeonly buffer LayersCo { float16_t layersCo[]; };
layout(std430, binding = 6) writeonly buffer LayersCg { float16_t layersCg[]; };
layout(push_constant) uniform Push { LightmapCopyPush pc; };

void main() {
    const uint t = gl_GlobalInvocationID.x;
    const uint texels = pc.texelCount;
    if (t >= texels) return;
    const uint c = cacheIndex[t];
    const bool none = c == kNoCache;
    [[unroll]] for (uint k = 0u; k < kCountY; ++k)
        layersY[k * texels + t] = none ? float16_t(0.0) : cacheY[c * kCountY + k];
    [[unroll]] for (uint k = 0u; k < kCountC; ++k) {
        layersCo[k * texels + t] = none ? float16_t(0.0) : cacheCo[c * kCountC + k];
        layersCg[k * texels + t] = none ? float16_t(0.0) : cacheCg[c * kCountC + k];
    }
}
