#version 460
// Surfel lighting (paper 000 Figure 2 step 2): each leaf surfel's outgoing flux in W per RGB
// channel. Direct mode: Φ = ρ·A·Σ E_light·V + π·L_e·A·emissiveScale, V from the shadow maps;
// bounce mode: Φ = Φ_direct + ρ·A·max(0, E) with E the irradiance the previous bounce's caches
// deliver at the surfel (its precomputed interpolation stencil). Each workgroup also writes
// its summed flux for the progressive stop, in one of two slots so that consecutive passes
// of one submission keep both sums. CPU twin: server/cpu/surfel_lighting.cpp.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#extension GL_EXT_shader_16bit_storage : require
#extension GL_EXT_shader_explicit_arithmetic_types_float16 : require
#include "shared/bake_layout.h"
#include "shared/shadow_map.h"
#include "shared/sh_tables.h"
#include "shared/surfel_lighting.h"

layout(local_size_x = 64) in;
layout(constant_id = 0) const uint kBandsY = 3u;
layout(constant_id = 1) const uint kBandsC = 2u;
const uint kCountY = kBandsY * kBandsY;
const uint kCountC = kBandsC * kBandsC;

layout(std430, binding = 0) readonly buffer Surfels { Surfel surfels[]; };
layout(std430, binding = 1) readonly buffer Lights { GpuLight lights[]; };
layout(std430, binding = 2) readonly buffer LayerMatrices { mat4 clipFromWorld[]; };
layout(std430, binding = 3) readonly buffer EmissiveScale { float emissiveScale[]; };  // per material
layout(binding = 4) uniform sampler2DArray shadowMaps;
layout(std430, binding = 5) buffer DirectFlux { vec4 directFlux[]; };   // nS
layout(std430, binding = 6) buffer NodeFlux { vec4 nodeFlux[]; };       // leaves [0, nS)
layout(std430, binding = 7) readonly buffer Stencils { SurfelStencil stencils[]; };
layout(std430, binding = 8) readonly buffer CacheY { float16_t cacheY[]; };
layout(std430, binding = 9) readonly buffer CacheCo { float16_t cacheCo[]; };
layout(std430, binding = 10) readonly buffer CacheCg { float16_t cacheCg[]; };
layout(std140, binding = 11) uniform Sh { ShTables sh; };
layout(std430, binding = 12) writeonly buffer GroupFlux { vec4 groupFlux[]; };
layout(push_constant) uniform Push { SurfelLightingPush pc; };

#include "lib/sh.glsl"

shared vec3 partial[64];

/// core/light_set.h lightIrradiance: irradiance on a surface at p with normal n, the unit
/// direction to the light and its distance (∞ for directional lights).
vec3 lightIrradiance(GpuLight light, vec3 p, vec3 n, out vec3 toLight, out float distance) {
    if (light.type == kLightDirectional) {
        toLight = -light.direction;
        distance = 1.0 / 0.0;
        return light.radiant * max(0.0, dot(n, toLight));
    }
    const vec3 offset = light.position - p;
    distance = length(offset);
    if (!(distance > 0.0)) {
        toLight = n;
        return vec3(0.0);
    }
    toLight = offset / distance;
    const float cosTheta = dot(n, toLight);
    if (cosTheta <= 0.0) return vec3(0.0);
    float attenuation = 1.0 / (distance * distance);
    if (light.range > 0.0) {
        const float ratio = distance / light.range;
        const float ratio2 = ratio * ratio;
        attenuation *= clamp(1.0 - ratio2 * ratio2, 0.0, 1.0);
    }
    if (light.type == kLightSpot) {
        const float cd = dot(light.direction, -toLight);
        if (light.hardCone != 0u) {
            attenuation *= cd >= light.cosOuter ? 1.0 : 0.0;
        } else {
            const float scale = 1.0 / max(0.001, light.cosInner - light.cosOuter);
            const float ramp = clamp(cd * scale - light.cosOuter * scale, 0.0, 1.0);
            attenuation *= ramp * ramp;
        }
    }
    return light.radiant * (cosTheta * attenuation);
}

/// Shadow-map visibility of the light from a surface point p with normal n (cosTheta the
/// cosine between n and the direction to the light). The point moves off the surface by the
/// ray offset plus one shadow texel's footprint along the normal (normal-offset shadows), and
/// the depth test allows half a texel plus a slope term, so that a lit plane never shadows
/// itself while contact shadows keep their place.
bool visible(GpuLight light, vec3 p, vec3 n, float cosTheta) {
    // Layer and depth along its view axis.
    uint layer = light.firstLayer;
    if (light.shadowKind == kShadowCube) {
        const vec3 v = p - light.position;
        const vec3 a = abs(v);
        uint face = a.x >= a.y && a.x >= a.z ? (v.x >= 0.0 ? 0u : 1u)
                  : a.y >= a.z             ? (v.y >= 0.0 ? 2u : 3u)
                                           : (v.z >= 0.0 ? 4u : 5u);
        layer += face;
    }
    const bool ortho = light.shadowKind == kShadowOrthographic;
    const mat4 m = clipFromWorld[layer];
    const float depthP = ortho ? light.depthNear + (m * vec4(p, 1.0)).z * (light.depthFar - light.depthNear)
                               : (m * vec4(p, 1.0)).w;
    const float texel = ortho ? light.texelSlope : light.texelSlope * max(depthP, 0.0);
    const float tanTheta = sqrt(max(1.0 - cosTheta * cosTheta, 0.0)) / max(cosTheta, 1e-4);
    const vec3 q = p + n * (pc.epsilon + texel);
    const vec4 clip = m * vec4(q, 1.0);
    if (!ortho && clip.w <= 0.0) return true;  // behind the light's near plane
    const vec3 ndc = clip.xyz / clip.w;
    const vec2 uv = ndc.xy * 0.5 + 0.5;
    const int size = int(pc.shadowSize);
    const ivec2 xy = clamp(ivec2(floor(uv * float(size))), ivec2(0), ivec2(size - 1));
    const float stored = texelFetch(shadowMaps, ivec3(xy, int(layer)), 0).r;
    if (stored >= 1.0) return true;  // nothing drawn there: the far plane
    const float n0 = light.depthNear, f0 = light.depthFar;
    const float depthStored = ortho ? n0 + stored * (f0 - n0) : n0 * f0 / (f0 - stored * (f0 - n0));
    const float depthQ = ortho ? n0 + ndc.z * (f0 - n0) : clip.w;
    const float bias = texel * (0.5 + 0.5 * min(tanTheta, 10.0));
    return depthQ <= depthStored + bias;
}

void main() {
    const uint i = gl_GlobalInvocationID.x;
    vec3 flux = vec3(0.0);
    if (i < pc.surfelCount) {
        const Surfel surfel = surfels[i];
        if (pc.mode == kSurfelModeDirect) {
            vec3 irradiance = vec3(0.0);
            for (uint k = 0u; k < pc.lightCount; ++k) {
                const GpuLight light = lights[k];
                vec3 toLight;
                float distance;
                const vec3 e = lightIrradiance(light, surfel.position, surfel.normal, toLight, distance);
                // Surfels facing away, outside the cone or past the range need no shadow test.
                if (!(e.r > 0.0 || e.g > 0.0 || e.b > 0.0)) continue;
                if (visible(light, surfel.position, surfel.normal, dot(surfel.normal, toLight)))
                    irradiance += e;
            }
            flux = surfel.albedo * (surfel.area * irradiance) +
                   (kPi * surfel.area * emissiveScale[surfel.material]) * surfel.emission;
            directFlux[i] = vec4(flux, 0.0);
        } else {
            // Interpolate the previous bounce's caches in YCoCg, then convolve with the
            // clamped cosine about the normal.
            const SurfelStencil s = stencils[i];
            float y[kCountY];
            float co[kCountC];
            float cg[kCountC];
            [[unroll]] for (uint c = 0u; c < kCountY; ++c) y[c] = 0.0;
            [[unroll]] for (uint c = 0u; c < kCountC; ++c) { co[c] = 0.0; cg[c] = 0.0; }
            [[unroll]] for (uint k = 0u; k < 8u; ++k) {
                const float w = k < 4u ? s.weightLow[k] : s.weightHigh[k - 4u];
                if (w == 0.0) continue;
                const uint cache = k < 4u ? s.cacheLow[k] : s.cacheHigh[k - 4u];
                [[unroll]] for (uint c = 0u; c < kCountY; ++c) y[c] += w * float(cacheY[cache * kCountY + c]);
                [[unroll]] for (uint c = 0u; c < kCountC; ++c) {
                    co[c] += w * float(cacheCo[cache * kCountC + c]);
                    cg[c] += w * float(cacheCg[cache * kCountC + c]);
                }
            }
            float basis[64];
            shEvaluate(surfel.normal, basis);
            vec3 e = vec3(0.0);  // YCoCg irradiance: Σ K_l L_lm y_lm(n)
            [[unroll]] for (uint c = 0u; c < kCountY; ++c) {
                const float w = PIC_SH_TABLE(sh.clampedCosine, kShBandOf[c]) * basis[c];
                e.x += y[c] * w;
                if (c < kCountC) {
                    e.y += co[c] * w;
                    e.z += cg[c] * w;
                }
            }
            // SH ringing can make irradiance negative on the dark side; cut at zero per channel.
            const vec3 irradiance = max(yCoCgToRgb(e), vec3(0.0));
            flux = directFlux[i].xyz + surfel.albedo * (surfel.area * irradiance);
        }
        nodeFlux[i] = vec4(flux, 0.0);
    }

    // Workgroup sum of the flux for the progressive stop (the host adds the groups in double).
    partial[gl_LocalInvocationID.x] = flux;
    barrier();
    for (uint stride = 32u; stride > 0u; stride >>= 1u) {
        if (gl_LocalInvocationID.x < stride)
            partial[gl_LocalInvocationID.x] += partial[gl_LocalInvocationID.x + stride];
        barrier();
    }
    if (gl_LocalInvocationID.x == 0u)
        groupFlux[pc.sumSlot * gl_NumWorkGroups.x + gl_WorkGroupID.x] = vec4(partial[0], 0.0);
}
