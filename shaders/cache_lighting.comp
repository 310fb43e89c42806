#version 460
// Cache lighting (paper 000 Figure 2 step 4, eq. 3): per cache, L = Σ over its nL links of
// the node's radiance Φ / (π·A) (RGBE8, §4.7) times its transport, in YCoCg, Y with lY bands
// and Co, Cg with lC bands, stored as half floats; and a light-map cache's RGB irradiance
// along its normal, every colour through the luma's lY bands, for the next bounce. The CPU twin
// (render/cpu/cache_lighting.cpp) takes Φ times the bake's factor V / (π·A): the same product.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#extension GL_EXT_shader_16bit_storage : require
#extension GL_EXT_shader_explicit_arithmetic_types_float16 : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_basic : require
#include "shared/bake_layout.h"
#include "shared/cache_lighting.h"
#include "shared/pull.h"
#include "shared/sh_tables.h"

layout(local_size_x = 64) in;
layout(constant_id = 0) const uint kBandsY = 3u;
layout(constant_id = 1) const uint kBandsC = 2u;
layout(constant_id = 2) const uint kLinksPerCache = 128u;
layout(constant_id = 3) const uint kLinkForm = 1u;
layout(constant_id = 4) const uint kMapping = 0u;
layout(constant_id = 5) const uint kTexelWords = 1u;  // words per texel of `links`
const uint kCountY = kBandsY * kBandsY;
const uint kCountC = kBandsC * kBandsC;
const uint kShPairs = (kCountY + 1u) / 2u;
const uint kShWords = (3u + kShPairs + 3u) / 4u * 4u;  // shared/cache_lighting.h shLinkWords
const uint kLinkWords = kLinkForm == kLinkFormRtp ? 4u : kShWords;
const uint kLinkTexels = kLinkWords / kTexelWords;  // the host picks a divisor

// Uniform texel buffers of uint words (shared/cache_lighting.h says why).
layout(binding = 0) uniform usamplerBuffer nodeLight;  // RGBA32UI per node (shared/pull.h)
layout(binding = 1) uniform usamplerBuffer links;  // the chunk's links, kTexelWords per texel
layout(std430, binding = 2) writeonly buffer CacheY { float16_t cacheY[]; };
layout(std430, binding = 3) writeonly buffer CacheCo { float16_t cacheCo[]; };
layout(std430, binding = 4) writeonly buffer CacheCg { float16_t cacheCg[]; };
layout(std140, binding = 5) uniform Sh { ShTables sh; };
// Per cache: packSnorm4x8(normal, 1) for light-map caches, 0 for grid caches.
layout(binding = 6) uniform usamplerBuffer cacheNormals;
// Per cache: RGB irradiance along a light-map cache's normal (0 for grid caches), read by the
// next bounce's surfel lighting (core/cache_values.h CacheValues::irradiance).
layout(std430, binding = 7) writeonly buffer CacheIrradiance { vec4 cacheIrradiance[]; };
layout(push_constant) uniform Push { CacheLightingPush pc; };

#include "lib/rgbe8.glsl"
#include "lib/sh.glsl"

float y[kCountY];
float co[kCountC];
float cg[kCountC];
vec3 alongNormal;   // YCoCg irradiance along the cache's normal
vec4 cacheNormal;   // of the cache being lit: xyz its normal, w 1 for a light-map cache

float16_t toHalf(float value) {
    return float16_t(clamp(value, -kHalfMax, kHalfMax));
}

/// core/color.h decodeLinkTint: three unorm10 channels.
vec3 decodeLinkTint(uint code) {
    return vec3(uvec3(code, code >> 10u, code >> 20u) & 0x3FFu) * (1.0 / 1023.0);
}

/// The YCoCg radiance a link carries: its node's spread at the link's box point u
/// (shared/pull.h), radiance·(1 + slopes·u) per channel (≥ 0 for u in the box) for a linear
/// node, radiance·exp(slopes·u − (1 − ρ)·ln Z) for an exponential one, ρ the link's spread
/// share (concentrationWeight = 1 − ρ); times its tint.
vec3 linkRadiance(uint node, vec3 tint, uint point, float concentrationWeight) {
    const uvec4 light = texelFetch(nodeLight, int(node));
    const vec3 u = unpackSnorm4x8(point).xyz;
    const vec4 a = unpackSnorm4x8(light.x);
    const vec4 b = unpackSnorm4x8(light.y);
    const vec3 slopesB = vec3(b.zw, unpackSnorm4x8(light.z & 0xFFu).x);
    const vec3 exponent = vec3(dot(a.xyz, u), dot(vec3(a.w, b.xy), u), dot(slopesB, u));
    vec3 spread;
    if ((light.z & kNodeLightExponentialBit) != 0u) {
        const vec3 concentration =
            vec3(uvec3(light.z >> 8u, light.z >> 15u, light.z >> 22u) & 0x7Fu) *
            (kConcentrationRange / 127.0);
        spread = exp(kExponentialSpreadCap * exponent - concentrationWeight * concentration);
    } else {
        spread = vec3(1.0) + exponent;
    }
    return rgbToYCoCg(unpackRgbe8(light[kNodeLightRadianceWord]) * tint * spread);
}

/// 1 − the spread share of its 6-bit code (core/bake_data.h decodeSpreadShare).
float concentrationWeightOf(uint code) {
    return 1.0 - float(code & 0x3Fu) * (1.0 / float(kSpreadShareSteps));
}

/// Adds link `slot` (within the chunk) to y, co, cg.
void addLink(uint slot) {
    uint words[4 + 64 / 2];  // kLinkWords at most, for lY ≤ 8 as basis[64] below
    [[unroll]] for (uint t = 0u; t < kLinkTexels; ++t) {
        const uvec4 texel = texelFetch(links, int(slot * kLinkTexels + t));
        [[unroll]] for (uint c = 0u; c < kTexelWords; ++c) words[t * kTexelWords + c] = texel[c];
    }
    if (kLinkForm == kLinkFormRtp) {
        // §4.6: the node's cone projected at runtime, V·K_l(α)·y_lm(direction).
        const GpuRtpLink link = GpuRtpLink(words[0], words[1], words[2], words[3]);
        const vec2 visibleAndCone = unpackHalf2x16(link.visibleAndCone);
        const float visible = visibleAndCone.x;
        if (visible == 0.0) return;  // padding
        const vec3 tint =
            vec3(link.nodeAndRed >> 24u, link.directionAndGreen >> 24u, link.pointAndBlue >> 24u) *
            (1.0 / 255.0);
        const vec3 radiance = linkRadiance(link.nodeAndRed & 0xFFFFFFu, tint, link.pointAndBlue,
                                           concentrationWeightOf(link.directionAndGreen >> 18u));
        float cone[kBandsY];
        coneZonal(visibleAndCone.y, cone);
        const vec3 direction = decodeOctahedral9(link.directionAndGreen);
        if (cacheNormal.w > 0.0) {
            // The cone's projection convolved with the clamped cosine at the cache's normal,
            // Σ_l K_l·K_l(α)·(2l + 1)/(4π)·P_l(n·d) (render/link_irradiance.h
            // linkIrradiance).
            const float x = dot(cacheNormal.xyz, direction);
            float legendre = 1.0, previous = 0.0, w = 0.0;
            [[unroll]] for (uint l = 0u; l < kBandsY; ++l) {
                const float band = float(2u * l + 1u) / (4.0 * kPi);
                w += PIC_SH_TABLE(sh.clampedCosine, l) * cone[l] * band * legendre;
                const float next = (float(2u * l + 1u) * x * legendre - float(l) * previous) *
                                   (1.0 / float(l + 1u));
                previous = legendre;
                legendre = next;
            }
            alongNormal += radiance * (visible * w);
        }
        float basis[64];
        shEvaluate(direction, basis);
        [[unroll]] for (uint i = 0u; i < kCountY; ++i) {
            const float w = visible * cone[kShBandOf[i]] * basis[i];
            y[i] += radiance.x * w;
            if (i < kCountC) {
                co[i] += radiance.y * w;
                cg[i] += radiance.z * w;
            }
        }
    } else {
        // SH-projected links: the node, its tint, its box point, then lY² half coefficients
        // two per word, scaled by π·A at upload to take the node's radiance; chroma takes the
        // first lC². The half after them is the link's irradiance along a light-map cache's
        // normal (0 for grid caches).
        if (words[0] == kNoNode) return;
        const vec3 radiance = linkRadiance(words[0], decodeLinkTint(words[1]), words[2],
                                           concentrationWeightOf(words[2] >> 24u));
        alongNormal += radiance * unpackHalf2x16(words[3u + kCountY / 2u])[kCountY % 2u];
        [[unroll]] for (uint p = 0u; p < kShPairs; ++p) {
            const vec2 pair = unpackHalf2x16(words[3u + p]);
            [[unroll]] for (uint h = 0u; h < 2u; ++h) {
                const uint i = 2u * p + h;
                if (i >= kCountY) break;
                const float k = pair[h];
                y[i] += radiance.x * k;
                if (i < kCountC) {
                    co[i] += radiance.y * k;
                    cg[i] += radiance.z * k;
                }
            }
        }
    }
}

void store(uint local) {
    // Band 0 of each RGB channel never below 0 (the CPU twin's CacheSh::store says why).
    const vec3 band0 = yCoCgToRgb(vec3(y[0], co[0], cg[0]));
    if (any(lessThan(band0, vec3(0.0)))) {
        const vec3 raised = rgbToYCoCg(max(band0, vec3(0.0)));
        y[0] = raised.x;
        co[0] = raised.y;
        cg[0] = raised.z;
    }
    const uint cache = pc.firstCache + local;
    cacheIrradiance[cache] = vec4(max(yCoCgToRgb(alongNormal), vec3(0.0)), 0.0);
    [[unroll]] for (uint i = 0u; i < kCountY; ++i) cacheY[cache * kCountY + i] = toHalf(y[i]);
    [[unroll]] for (uint i = 0u; i < kCountC; ++i) {
        cacheCo[cache * kCountC + i] = toHalf(co[i]);
        cacheCg[cache * kCountC + i] = toHalf(cg[i]);
    }
}

void clear(uint local) {
    cacheNormal = unpackSnorm4x8(texelFetch(cacheNormals, int(pc.firstCache + local)).x);
    alongNormal = vec3(0.0);
    [[unroll]] for (uint i = 0u; i < kCountY; ++i) y[i] = 0.0;
    [[unroll]] for (uint i = 0u; i < kCountC; ++i) { co[i] = 0.0; cg[i] = 0.0; }
}

void main() {
    if (kMapping == kCachePerInvocation) {
        const uint local = gl_GlobalInvocationID.x;  // cache within the chunk
        if (local >= pc.cacheCount) return;
        clear(local);
        for (uint j = 0u; j < kLinksPerCache; ++j) addLink(local * kLinksPerCache + j);
        store(local);
    } else {
        // Subgroups stride over the chunk's caches, so that however many subgroups the device
        // launches per workgroup, every cache is lit once. The loop condition is uniform in
        // a subgroup, as subgroupAdd needs.
        const uint stride = gl_NumWorkGroups.x * gl_NumSubgroups;
        for (uint local = gl_WorkGroupID.x * gl_NumSubgroups + gl_SubgroupID; local < pc.cacheCount;
             local += stride) {
            clear(local);
            for (uint j = gl_SubgroupInvocationID; j < kLinksPerCache; j += gl_SubgroupSize)
                addLink(local * kLinksPerCache + j);
            alongNormal = subgroupAdd(alongNormal);
            [[unroll]] for (uint i = 0u; i < kCountY; ++i) y[i] = subgroupAdd(y[i]);
            [[unroll]] for (uint i = 0u; i < kCountC; ++i) {
                co[i] = subgroupAdd(co[i]);
                cg[i] = subgroupAdd(cg[i]);
            }
            if (subgroupElect()) store(local);
        }
    }
}
