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

// What a lane reads at its own cache's index comes through uniform texel buffers (on lavapipe
// a storage-buffer load at a per-lane index is a branch and a scalar load per lane, a texel
// fetch a gather).
layout(binding = 0) uniform samplerBuffer cacheSky;  // R32F, nC·nV
// W: Y's lY² rows, then Co's and Cg's lC² rows, nV each, four to a vec4. A uniform buffer:
// every lane reads the same weight, a constant-buffer load (as a storage buffer on lavapipe,
// a load per lane: 16 ms instead of 3 for the atrium's 8,186 caches). At most
// (64 + 2·64)·64 floats, 48 KiB, for lY = lC = 8.
layout(std140, binding = 1) uniform Weights { vec4 weights[kMaxSkyWeightVec4s]; };
layout(std430, binding = 2) writeonly buffer CacheY { float16_t cacheY[]; };
layout(std430, binding = 3) writeonly buffer CacheCo { float16_t cacheCo[]; };
layout(std430, binding = 4) writeonly buffer CacheCg { float16_t cacheCg[]; };
// The same caches as R16F texels, read before the lane writes its own.
layout(binding = 5) uniform samplerBuffer cacheYIn;
layout(binding = 6) uniform samplerBuffer cacheCoIn;
layout(binding = 7) uniform samplerBuffer cacheCgIn;
layout(push_constant) uniform Push { SkyCachesPush pc; };

float16_t toHalf(float value) {
    return float16_t(clamp(value, -kHalfMax, kHalfMax));
}

void main() {
    const uint c = gl_GlobalInvocationID.x;
    if (c >= pc.cacheCount) return;
    // Row by row of W against the lane's visibility, one visibility coefficient at a time.
    const uint rows = kCountY + 2u * kCountC;
    float sum[kCountY + 2u * kCountC];
    [[unroll]] for (uint i = 0u; i < rows; ++i) sum[i] = 0.0;
    for (uint k = 0u; k < kCountV; ++k) {
        const float v = texelFetch(cacheSky, int(c * kCountV + k)).x;
        [[unroll]] for (uint i = 0u; i < rows; ++i) {
            const uint w = i * kCountV + k;
            sum[i] += weights[w >> 2u][w & 3u] * v;
        }
    }
    [[unroll]] for (uint i = 0u; i < kCountY; ++i) {
        const uint at = c * kCountY + i;
        cacheY[at] = toHalf(texelFetch(cacheYIn, int(at)).x + sum[i]);
    }
    [[unroll]] for (uint i = 0u; i < kCountC; ++i) {
        const uint at = c * kCountC + i;
        cacheCo[at] = toHalf(texelFetch(cacheCoIn, int(at)).x + sum[kCountY + i]);
        cacheCg[at] = toHalf(texelFetch(cacheCgIn, int(at)).x + sum[kCountY + kCountC + i]);
    }
}
