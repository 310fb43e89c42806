#version 460
// Surfel lighting (paper 000 Figure 2 step 2): each leaf surfel's outgoing flux in W per RGB
// channel. Direct mode: Φ = ρ·A·(Σ E_light·V + E_sky) + π·L_e·A·emissiveScale, V from the
// shadow maps or, in the rays mode, one bit per surfel and light traced on the host
// (RayVisibilityPass), E_sky the sky through the surfel's precomputed transfer (core/sky.h);
// bounce mode: Φ = Φ_direct + ρ·A·E with E the irradiance the previous bounce's caches deliver
// at the surfel (its precomputed interpolation stencil: light-map caches on its surface through
// their irradiance along their normal, others through their SH, cut at 0), plus on the last bounce
// tail·max(Φ − Φ_previous, 0), the light of the bounces not computed (render/runtime.h
// BounceSchedule). Each workgroup also writes
// its summed flux for the progressive stop, in one of two slots so that consecutive passes
// of one submission keep both sums. CPU twin: render/cpu/surfel_lighting.cpp.
//
// The mode is a specialization constant, not a push constant: lavapipe runs both sides of a
// branch under a lane mask, so a uniform branch on a push constant cost the direct pass the
// bounce part's loads and SH arithmetic (4.6 of 6.6 ms for 32k surfels, atrium).
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "shared/bake_layout.h"
#include "shared/shadow_map.h"
#include "shared/sh_tables.h"
#include "shared/surfel_lighting.h"

layout(local_size_x = 64) in;
layout(constant_id = 0) const uint kBandsY = 3u;
layout(constant_id = 1) const uint kBandsC = 2u;
layout(constant_id = 2) const uint kMode = kSurfelModeDirect;
const uint kCountY = kBandsY * kBandsY;
const uint kCountC = kBandsC * kBandsC;

// Records read by index are uniform texel buffers: on lavapipe a storage-buffer load at a
// per-lane index is a branch and a scalar load per lane, a texel fetch a gather. Mixed
// records are RGBA32UI texels, their floats bit casts.
layout(binding = 0) uniform usamplerBuffer surfelTexels;  // Surfel: 4 texels
layout(binding = 1) uniform usamplerBuffer lightTexels;   // GpuLight: 5 texels
layout(std430, binding = 2) readonly buffer ShadowLayers { GpuShadowLayer shadowLayers[]; };
layout(binding = 3) uniform samplerBuffer emissiveScale;  // per material
layout(binding = 4) uniform sampler2DArray shadowMaps;
layout(std430, binding = 5) writeonly buffer DirectFlux { vec4 directFlux[]; };  // nS
layout(std430, binding = 6) buffer NodeFlux { vec4 nodeFlux[]; };  // leaves [0, nS): the previous bounce's in bounce mode
layout(binding = 7) uniform usamplerBuffer stencilTexels;  // SurfelStencil: 4 texels
layout(binding = 8) uniform samplerBuffer cacheY;          // half texels, nC·lY²
layout(binding = 9) uniform samplerBuffer cacheCo;         // nC·lC²
layout(binding = 10) uniform samplerBuffer cacheCg;
layout(std140, binding = 11) uniform Sh { ShTables sh; };
layout(std430, binding = 12) writeonly buffer GroupFlux { vec4 groupFlux[]; };
// Rays mode: bit i % 32 of word light·⌈nS/32⌉ + i/32 is set where light reaches surfel i.
layout(binding = 13) uniform usamplerBuffer visibility;
layout(std430, binding = 14) writeonly buffer NodeLight { uvec4 nodeLight[]; };  // leaves (shared/pull.h)
layout(binding = 15) uniform samplerBuffer directFluxTexels;  // binding 5, read by the bounce
// Per cache: RGB irradiance along a light-map cache's normal (cache lighting writes it).
layout(binding = 16) uniform samplerBuffer cacheIrradiance;
// The sky: each surfel's transfer T (kSkyCoefficients floats, BakeData::surfelSky) and the
// sky's RGB radiance SH s, so that E_sky = max(0, Σ_k s_k T_k) per channel.
layout(binding = 17) uniform samplerBuffer surfelSky;
layout(std430, binding = 18) readonly buffer SkySh { vec4 skySh[9]; };
layout(push_constant) uniform Push { SurfelLightingPush pc; };

#include "lib/sh.glsl"
#include "lib/lights.glsl"
#include "lib/rgbe8.glsl"

shared vec3 partial[kSurfelLightingGroup];  // per subgroup

void main() {
    const uint i = gl_GlobalInvocationID.x;
    vec3 flux = vec3(0.0);
    if (i < pc.surfelCount) {
        const Surfel surfel = fetchSurfel(surfelTexels, i);
        if (kMode != kSurfelModeBounce) {
            const uint words = (pc.surfelCount + 31u) / 32u;
            vec3 irradiance = vec3(0.0);
            for (uint k = 0u; k < pc.lightCount; ++k) {
                const GpuLight light = fetchLight(lightTexels, k);
                vec3 toLight;
                float distance;
                const vec3 e = lightIrradiance(light, surfel.position, surfel.normal, toLight, distance);
                // Surfels facing away, outside the cone or past the range need no shadow test.
                if (!(e.r > 0.0 || e.g > 0.0 || e.b > 0.0)) continue;
                const bool visible =
                    kMode == kSurfelModeDirectRays
                        ? (texelFetch(visibility, int(k * words + (i >> 5u))).x & (1u << (i & 31u))) != 0u
                        : shadowVisible(light, surfel.position, surfel.normal,
                                        dot(surfel.normal, toLight), pc.epsilon);
                if (visible) irradiance += e;
            }
            if (pc.sky != 0u) {
                vec3 sky = vec3(0.0);
                [[unroll]] for (uint k = 0u; k < 9u; ++k)
                    sky += skySh[k].xyz * texelFetch(surfelSky, int(i * 9u + k)).x;
                irradiance += max(sky, vec3(0.0));
            }
            flux = surfel.albedo * (surfel.area * irradiance) +
                   (kPi * surfel.area * texelFetch(emissiveScale, int(surfel.material)).x) * surfel.emission;
            directFlux[i] = vec4(flux, 0.0);
        } else {
            // Light-map caches on the surfel's surface (negative stencil weights) give their
            // irradiance along their normal; the others are interpolated in YCoCg, then
            // convolved with the clamped cosine about the surfel's normal.
            const SurfelStencil s = fetchStencil(stencilTexels, i);
            float y[kCountY];
            float co[kCountC];
            float cg[kCountC];
            [[unroll]] for (uint c = 0u; c < kCountY; ++c) y[c] = 0.0;
            [[unroll]] for (uint c = 0u; c < kCountC; ++c) { co[c] = 0.0; cg[c] = 0.0; }
            vec3 alongNormal = vec3(0.0);
            [[unroll]] for (uint k = 0u; k < 8u; ++k) {
                const float w = k < 4u ? s.weightLow[k] : s.weightHigh[k - 4u];
                if (w == 0.0) continue;
                const uint cache = k < 4u ? s.cacheLow[k] : s.cacheHigh[k - 4u];
                if (w < 0.0) {
                    alongNormal -= w * texelFetch(cacheIrradiance, int(cache)).xyz;
                    continue;
                }
                [[unroll]] for (uint c = 0u; c < kCountY; ++c)
                    y[c] += w * texelFetch(cacheY, int(cache * kCountY + c)).x;
                [[unroll]] for (uint c = 0u; c < kCountC; ++c) {
                    co[c] += w * texelFetch(cacheCo, int(cache * kCountC + c)).x;
                    cg[c] += w * texelFetch(cacheCg, int(cache * kCountC + c)).x;
                }
            }
            // YCoCg irradiance Σ K_l L_lm y_lm(n), the chroma of the bands above lC predicted
            // from their luma (core/cache_values.h blendCaches).
            const vec2 chroma = chromaPerLuma(vec3(y[0], co[0], cg[0]));
            float basis[64];
            shEvaluate(surfel.normal, basis);
            vec3 e = vec3(0.0);
            [[unroll]] for (uint c = 0u; c < kCountY; ++c) {
                const float w = PIC_SH_TABLE(sh.clampedCosine, kShBandOf[c]) * basis[c];
                e.x += y[c] * w;
                if (c < kCountC) {
                    e.y += co[c] * w;
                    e.z += cg[c] * w;
                } else {
                    e.yz += chroma * (y[c] * w);
                }
            }
            // SH ringing can make irradiance negative on the dark side; cut at zero per channel.
            const vec3 irradiance = alongNormal + max(yCoCgToRgb(e), vec3(0.0));
            flux = texelFetch(directFluxTexels, int(i)).xyz + surfel.albedo * (surfel.area * irradiance);
            // The light of the bounces not computed (BounceSchedule); tail is 0 but on the last.
            flux += pc.tail.xyz * max(flux - nodeFlux[i].xyz, vec3(0.0));
        }
        nodeFlux[i] = vec4(flux, 0.0);
        // Cache lighting reads the leaf's radiance Φ / (π·A) (paper 000 §4.7).
        nodeLight[i] = uvec4(0u, 0u, 0u, packRgbe8(flux / (kPi * surfel.area)));
    }

    // Workgroup sum of the flux for the progressive stop (the host adds the groups in double):
    // each subgroup adds its lanes, then the first invocation adds the subgroups.
    const vec3 subgroupFlux = subgroupAdd(flux);
    if (subgroupElect()) partial[gl_SubgroupID] = subgroupFlux;
    barrier();
    if (gl_LocalInvocationID.x == 0u) {
        vec3 sum = vec3(0.0);
        for (uint k = 0u; k < gl_NumSubgroups; ++k) sum += partial[k];
        groupFlux[pc.sumSlot * gl_NumWorkGroups.x + gl_WorkGroupID.x] = vec4(sum, 0.0);
    }
}
