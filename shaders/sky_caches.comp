#version 460
// Sky caches (core/sky.h, paper 000's environment light through precomputed transfer): after
// the last bounce every cache adds the direct sky, c_i += Σ_k W_ik v_k per YCoCg channel, W
// the sky folded with the Gaunt coefficients for this update (SkyCacheWeights) and v the
// cache's sky visibility from the bake. The bounces never read it: the surfels' direct flux
// already holds the sky they see. CPU twin: render/cpu/sky_caches.cpp.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#extension GL_EXT_shader_16bit_storage : require
#extension GL_EXT_shader_explicit_arithmetic_types_float16 : require
#include "shared/cache_lighting.h"
#include "shared/sky_caches.h"

layout(local_size_x = 64) in;
layout(constant_id = 0) const uint kBandsY = 3u;
layout(constant_id = 1) const uint kBandsC = 2u;
layout(constant_id = 2) const uint kBandsV = 5u;
const uint kCountY = kBandsY * kBandsY;
const uint kCountC = kBandsC * kBandsC;
const uint kCountV = kBandsV * kBandsV;

layout(std430, binding = 0) readonly buffer CacheSky { float cacheSky[]; };  // nC·nV
// W: Y's lY² rows, then Co's and Cg's lC² rows, nV each.
layout(std430, binding = 1) readonly buffer Weights { float weights[]; };
layout(std430, binding = 2) buffer CacheY { float16_t cacheY[]; };
layout(std430, binding = 3) buffer CacheCo { float16_t cacheCo[]; };
layout(std430, binding = 4) buffer CacheCg { float16_t cacheCg[]; };
layout(push_constant) uniform Push { SkyCachesPush pc; };

float16_t toHalf(float value) {
    return float16_t(clamp(value, -kHalfMax, kHalfMax));
}

/// Σ_k W[row]_k v_k.
float folded(uint row, const float v[kCountV]) {
    float sum = 0.0;
    [[unroll]] for (uint k = 0u; k < kCountV; ++k) sum += weights[row * kCountV + k] * v[k];
    return sum;
}

void main() {
    const uint c = gl_GlobalInvocationID.x;
    if (c >= pc.cacheCount) return;
    float v[kCountV];
    [[unroll]] for (uint k = 0u; k < kCountV; ++k) v[k] = cacheSky[c * kCountV + k];
    [[unroll]] for (uint i = 0u; i < kCountY; ++i)
        cacheY[c * kCountY + i] = toHalf(float(cacheY[c * kCountY + i]) + folded(i, v));
    [[unroll]] for (uint i = 0u; i < kCountC; ++i) {
        cacheCo[c * kCountC + i] = toHalf(float(cacheCo[c * kCountC + i]) + folded(kCountY + i, v));
        cacheCg[c * kCountC + i] =
            toHalf(float(cacheCg[c * kCountC + i]) + folded(kCountY + kCountC + i, v));
    }
}
