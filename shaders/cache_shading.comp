#version 460
// Cache shading (render/passes/cache_shading_pass.h): each pixel of the G-buffer lit like the CPU
// twin render/cpu/cache_shading.cpp lights a ray hit. Direct: Σ ρ/π·E_light·V with V from the
// shadow maps; indirect: ρ/π·max(0, E_SH(n)) from the caches interpolated around the point
// (light map: 4 texels bilinearly; grid: 8 vertices trilinearly; texels and vertices without
// a cache take no weight and the others are renormalised, core/cache_values.h), plus the
// glossy lobe about the mirror direction; emission in the full component. Misses are black.
// With subsamples the renderer runs it once per subsample's G-buffer, each run adding to the
// pixel's sum (pc.accumulate).
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#extension GL_EXT_shader_16bit_storage : require
#extension GL_EXT_shader_explicit_arithmetic_types_float16 : require
#include "shared/cache_shading.h"
#include "shared/gbuffer.h"
#include "shared/shadow_map.h"
#include "shared/sh_tables.h"

layout(local_size_x = 64) in;
layout(constant_id = 0) const uint kBandsY = 3u;
layout(constant_id = 1) const uint kBandsC = 2u;
const uint kCountY = kBandsY * kBandsY;
const uint kCountC = kBandsC * kBandsC;

layout(binding = 0) uniform sampler2D gbufferPositionU;
layout(binding = 1) uniform sampler2D gbufferNormalV;
layout(binding = 2) uniform sampler2D gbufferAlbedo;
layout(binding = 3) uniform sampler2D gbufferEmission;
layout(std430, binding = 4) readonly buffer Lights { GpuLight lights[]; };
layout(std430, binding = 5) readonly buffer ShadowLayers { GpuShadowLayer shadowLayers[]; };
layout(binding = 6) uniform sampler2DArray shadowMaps;
// Cache textures (core/cache_textures.h layout), half floats, coefficient-major layers.
layout(std430, binding = 7) readonly buffer GridY { float16_t gridY[]; };
layout(std430, binding = 8) readonly buffer GridCo { float16_t gridCo[]; };
layout(std430, binding = 9) readonly buffer GridCg { float16_t gridCg[]; };
layout(std430, binding = 10) readonly buffer GridCoverage { float16_t gridCoverage[]; };
layout(std430, binding = 11) readonly buffer LightmapY { float16_t lightmapY[]; };
layout(std430, binding = 12) readonly buffer LightmapCo { float16_t lightmapCo[]; };
layout(std430, binding = 13) readonly buffer LightmapCg { float16_t lightmapCg[]; };
layout(std430, binding = 14) readonly buffer LightmapCoverage { float16_t lightmapCoverage[]; };
layout(std140, binding = 15) uniform Sh { ShTables sh; };
layout(std430, binding = 16) buffer Radiance { vec4 radiance[]; };  // width·height
layout(push_constant) uniform Push { CacheShadingPush pc; };

#include "lib/sh.glsl"
#include "lib/lights.glsl"

/// Up to 8 texels (light map) or vertices (grid) around a point with their final weights.
struct Stencil {
    uint texel[8];
    float weight[8];
    uint count;
};

/// Adds a neighbour that holds a cache (coverage 1); others take no weight.
void addNeighbour(inout Stencil s, uint texel, float w, bool lightmap) {
    const float coverage = lightmap ? float(lightmapCoverage[texel]) : float(gridCoverage[texel]);
    if (!(coverage > 0.5)) return;
    s.texel[s.count] = texel;
    s.weight[s.count] = w;
    ++s.count;
}

/// core/cache_values.cpp StencilBuilder::finish: renormalised weights, or equal weights when
/// every neighbour with a cache sits at weight 0.
void finishStencil(inout Stencil s) {
    float total = 0.0;
    for (uint k = 0u; k < s.count; ++k) total += s.weight[k];
    for (uint k = 0u; k < s.count; ++k)
        s.weight[k] = total > 0.0 ? s.weight[k] / total : 1.0 / float(s.count);
}

/// core/cache_values.cpp surfaceStencil for a light-mapped point at atlas coordinate uv.
Stencil lightmapStencil(vec2 uv) {
    Stencil s;
    s.count = 0u;
    const vec2 size = vec2(float(pc.lightmapWidth), float(pc.lightmapHeight));
    // Texel centres sit at (x + 0.5, y + 0.5) in texel units.
    const vec2 p = uv * size - 0.5;
    const vec2 base = floor(p);
    const vec2 f = p - base;
    for (uint dy = 0u; dy < 2u; ++dy) {
        for (uint dx = 0u; dx < 2u; ++dx) {
            const float x = base.x + float(dx);
            const float y = base.y + float(dy);
            // Texels outside the atlas do not exist: they take no weight.
            if (!(x >= 0.0 && y >= 0.0 && x < size.x && y < size.y)) continue;
            const float w = (dx != 0u ? f.x : 1.0 - f.x) * (dy != 0u ? f.y : 1.0 - f.y);
            addNeighbour(s, uint(x) + pc.lightmapWidth * uint(y), w, true);
        }
    }
    finishStencil(s);
    return s;
}

/// core/cache_values.cpp gridAxis: lower vertex and fraction along one axis, points outside
/// the grid clamped to its boundary (NaN to vertex 0).
void gridAxis(float coordinate, uint vertices, out uint lower, out float fraction) {
    if (vertices < 2u) {
        lower = 0u;
        fraction = 0.0;
        return;
    }
    const float c = !(coordinate > 0.0) ? 0.0 : min(coordinate, float(vertices - 1u));
    lower = min(uint(c), vertices - 2u);
    fraction = c - float(lower);
}

/// core/cache_values.cpp gridStencil.
Stencil gridStencil(vec3 position) {
    Stencil s;
    s.count = 0u;
    if (pc.gridCellSize > 0.0 && pc.gridDims.x * pc.gridDims.y * pc.gridDims.z > 0u) {
        const vec3 p = (position - pc.gridOrigin) / pc.gridCellSize;
        uint lower[3];
        float fraction[3];
        [[unroll]] for (int a = 0; a < 3; ++a) gridAxis(p[a], pc.gridDims[a], lower[a], fraction[a]);
        for (uint corner = 0u; corner < 8u; ++corner) {
            uint v[3];
            float w = 1.0;
            bool exists = true;
            [[unroll]] for (int a = 0; a < 3; ++a) {
                const uint upper = (corner >> uint(a)) & 1u;
                // A one-vertex axis has no upper neighbour.
                exists = exists && !(upper != 0u && pc.gridDims[a] < 2u);
                v[a] = lower[a] + upper;
                w *= upper != 0u ? fraction[a] : 1.0 - fraction[a];
            }
            if (!exists) continue;
            addNeighbour(s, v[0] + pc.gridDims.x * (v[1] + pc.gridDims.y * v[2]), w, false);
        }
    }
    finishStencil(s);
    return s;
}

void main() {
    const uint pixel = pc.firstPixel + gl_GlobalInvocationID.x;
    if (pixel >= pc.width * pc.height) return;
    const ivec2 xy = ivec2(pixel % pc.width, pixel / pc.width);
    const vec4 positionU = texelFetch(gbufferPositionU, xy, 0);
    const vec4 normalV = texelFetch(gbufferNormalV, xy, 0);
    const vec4 albedoHit = texelFetch(gbufferAlbedo, xy, 0);
    // The pixel sees nothing: black.
    if (albedoHit.w == 0.0) {
        if (pc.accumulate == 0u) radiance[pixel] = vec4(0.0);
        return;
    }
    const vec3 position = positionU.xyz;
    const vec3 normal = normalV.xyz;
    const vec3 albedo = albedoHit.rgb;
    vec3 result = vec3(0.0);

    if (pc.component == kShadeFull) result += texelFetch(gbufferEmission, xy, 0).rgb;

    if (pc.component == kShadeFull || pc.component == kShadeDirect) {
        vec3 irradiance = vec3(0.0);
        for (uint k = 0u; k < pc.lightCount; ++k) {
            const GpuLight light = lights[k];
            vec3 toLight;
            float distance;
            const vec3 e = lightIrradiance(light, position, normal, toLight, distance);
            // Points facing away, outside the cone or past the range need no shadow test.
            if (!(e.r > 0.0 || e.g > 0.0 || e.b > 0.0)) continue;
            if (shadowVisible(light, position, normal, dot(normal, toLight), pc.epsilon))
                irradiance += e;
        }
        result += albedo * (1.0 / kPi) * irradiance;
    }

    if (pc.component != kShadeDirect) {
        // Interpolate the caches' YCoCg coefficients around the point (the conversion to RGB
        // is linear, so it happens once, after the convolution).
        const bool lightmapped = positionU.w != kNotLightmappedUv && pc.lightmapWidth > 0u &&
                                 pc.lightmapHeight > 0u;
        const Stencil s = lightmapped ? lightmapStencil(vec2(positionU.w, normalV.w))
                                      : gridStencil(position);
        const uint layer = lightmapped ? pc.lightmapWidth * pc.lightmapHeight
                                       : pc.gridDims.x * pc.gridDims.y * pc.gridDims.z;
        float y[kCountY];
        float co[kCountC];
        float cg[kCountC];
        [[unroll]] for (uint c = 0u; c < kCountY; ++c) y[c] = 0.0;
        [[unroll]] for (uint c = 0u; c < kCountC; ++c) { co[c] = 0.0; cg[c] = 0.0; }
        for (uint k = 0u; k < s.count; ++k) {
            const float w = s.weight[k];
            const uint t = s.texel[k];
            if (lightmapped) {
                [[unroll]] for (uint c = 0u; c < kCountY; ++c) y[c] += w * float(lightmapY[c * layer + t]);
                [[unroll]] for (uint c = 0u; c < kCountC; ++c) {
                    co[c] += w * float(lightmapCo[c * layer + t]);
                    cg[c] += w * float(lightmapCg[c * layer + t]);
                }
            } else {
                [[unroll]] for (uint c = 0u; c < kCountY; ++c) y[c] += w * float(gridY[c * layer + t]);
                [[unroll]] for (uint c = 0u; c < kCountC; ++c) {
                    co[c] += w * float(gridCo[c * layer + t]);
                    cg[c] += w * float(gridCg[c * layer + t]);
                }
            }
        }

        // Irradiance Σ K_l L_lm y_lm(n) per YCoCg channel, the chroma of the bands above lC
        // predicted from their luma (core/cache_values.h blendCaches). A truncated expansion
        // rings: on the dark side of a bright cache it can dip below zero, which irradiance
        // never does, so each RGB channel is cut at 0.
        const vec2 chroma = chromaPerLuma(vec3(y[0], co[0], cg[0]));
        float basis[64];
        shEvaluate(normal, basis);
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
        // The light set's artistic scales (paper 001 §4) on the reconstructed luma and chroma.
        const vec3 scale = vec3(pc.yScale, pc.cocgScale, pc.cocgScale);
        if (pc.component != kShadeGlossy)
            result += albedo * (1.0 / kPi) * max(yCoCgToRgb(scale * e), vec3(0.0));

        if (pc.glossyWeight > 0.0) {
            // The normalised cosine lobe about the mirror direction of the view ray averages
            // the incident radiance; clamped like the irradiance, for the same ringing.
            const vec3 mirror = reflect(normalize(position - pc.eye), normal);
            shEvaluate(mirror, basis);
            vec3 g = vec3(0.0);
            [[unroll]] for (uint c = 0u; c < kCountY; ++c) {
                const float w = PIC_SH_TABLE(pc.glossyLobe, kShBandOf[c]) * basis[c];
                g.x += y[c] * w;
                if (c < kCountC) {
                    g.y += co[c] * w;
                    g.z += cg[c] * w;
                } else {
                    g.yz += chroma * (y[c] * w);
                }
            }
            result += pc.glossyWeight * max(yCoCgToRgb(scale * g), vec3(0.0));
        }
    }
    radiance[pixel] = pc.accumulate != 0u ? radiance[pixel] + vec4(result, 0.0) : vec4(result, 0.0);
}
