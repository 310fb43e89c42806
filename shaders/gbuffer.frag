#version 460
// G-buffer (render/passes/gbuffer_pass.h): what shading needs of the surface a pixel centre sees,
// computed as the CPU twin (render/cpu/cache_shading.cpp) computes it at a ray hit: the
// geometric normal facing the camera, Scene::albedoOverFootprint (baseColorFactor × vertex
// colour × the base-colour texture averaged over the pixel's footprint: mip-mapped,
// anisotropic, core/texture.h), Scene::emissionAt × the light set's emissive scale on front
// faces, and the light-map UV of light-mapped triangles. Layout in shared/gbuffer.h.
#extension GL_GOOGLE_include_directive : require
#include "shared/gbuffer.h"

// Nothing here writes depth or memory: fragments the depth test rejects need not be shaded.
layout(early_fragment_tests) in;

layout(location = 0) in vec3 inPosition;
layout(location = 1) in vec4 inColor;
layout(location = 2) in vec2 inUv0;
layout(location = 3) in vec2 inUv1;
layout(location = 4) in vec2 inLightmapUv;
layout(location = 5) flat in uint inTriangle;

layout(std430, binding = 0) readonly buffer Triangles { GbufferTriangle triangles[]; };
layout(std430, binding = 1) readonly buffer Materials { GbufferMaterial materials[]; };
layout(std430, binding = 2) readonly buffer Textures { GbufferTexture textures[]; };
layout(std430, binding = 3) readonly buffer Texels { vec4 texels[]; };
layout(std430, binding = 4) readonly buffer EmissiveScale { float emissiveScale[]; };  // per material
layout(std430, binding = 5) readonly buffer TextureLevels { GbufferTextureLevel levels[]; };
layout(push_constant) uniform Push { GbufferPush pc; };

layout(location = 0) out vec4 outPositionU;
layout(location = 1) out vec4 outNormalV;
layout(location = 2) out vec4 outAlbedo;
layout(location = 3) out vec4 outEmission;

/// core/texture.cpp texelPair: the texel at or left of a coordinate (texel centres at i + 0.5),
/// the next one under the wrap mode, and the weight of the second.
void texelPair(float coord, int size, bool repeat, out int i0, out int i1, out float fraction) {
    // A non-finite coordinate reads texel 0 rather than spreading NaN into lighting.
    if (isnan(coord) || isinf(coord)) coord = 0.0;
    coord = repeat ? coord - floor(coord) : min(max(coord, 0.0), 1.0);
    const float x = coord * float(size) - 0.5;
    const float base = floor(x);
    i0 = int(base);
    i1 = i0 + 1;
    if (repeat) {
        if (i0 < 0) i0 += size;
        if (i1 >= size) i1 -= size;
    } else {
        i0 = max(i0, 0);
        i1 = min(i1, size - 1);
    }
    fraction = x - base;
}

/// core/texture.cpp bilinear: one mip level with the texture's wrap modes.
vec4 bilinear(GbufferTextureLevel l, bool repeatS, bool repeatT, vec2 uv) {
    int s0, s1, t0, t1;
    float fs, ft;
    texelPair(uv.x, l.width, repeatS, s0, s1, fs);
    texelPair(uv.y, l.height, repeatT, t0, t1, ft);
    const uint row0 = l.firstTexel + uint(t0 * l.width);
    const uint row1 = l.firstTexel + uint(t1 * l.width);
    const vec4 top = mix(texels[row0 + uint(s0)], texels[row0 + uint(s1)], fs);
    const vec4 bottom = mix(texels[row1 + uint(s0)], texels[row1 + uint(s1)], fs);
    return mix(top, bottom, ft);
}

/// Level `level` (clamped to the chain) of texture t, bilinear.
vec4 sampleLevel(GbufferTexture t, int level, vec2 uv) {
    return bilinear(levels[t.firstLevel + uint(clamp(level, 0, t.levelCount - 1))],
                    (t.wrap & kTextureRepeatS) != 0u, (t.wrap & kTextureRepeatT) != 0u, uv);
}

/// core/texture.h Texture::sampleFootprint with textureFootprint's rule: as many trilinear
/// taps along the footprint's major side as it is longer than wide (at most one per texel of
/// it and kGbufferMaxAnisotropy), each at the level where it covers major / taps texels; the
/// taps summed per level and blended once, in the CPU twin's order.
vec4 sampleFootprint(int index, vec2 uv, vec2 dUvdx, vec2 dUvdy) {
    const GbufferTexture t = textures[index];
    const GbufferTextureLevel level0 = levels[t.firstLevel];
    const vec2 size = vec2(level0.width, level0.height);
    const float lengthX = length(dUvdx * size);
    const float lengthY = length(dUvdy * size);
    const float last = float(t.levelCount - 1);
    const float major = max(lengthX, lengthY);
    const float minor = min(lengthX, lengthY);
    float lod = 0.0;
    float taps = 1.0;
    vec2 axis = vec2(0.0);
    if (isinf(lengthX) || isnan(lengthX) || isinf(lengthY) || isnan(lengthY)) {
        // A ray grazing its plane spreads over the whole texture: its mean is the last level.
        lod = last;
    } else if (major > 0.0) {
        const float anisotropy = float(kGbufferMaxAnisotropy);
        const float ratio = minor > 0.0 ? major / minor : anisotropy;
        taps = max(1.0, min(ceil(min(ratio, anisotropy)), ceil(major)));
        lod = clamp(log2(major / taps), 0.0, last);
        if (taps > 1.0) axis = lengthX >= lengthY ? dUvdx : dUvdy;
    }
    const float base = min(floor(lod), last);
    const float fraction = lod - base;  // 0 at the last level
    const GbufferTextureLevel fine = levels[t.firstLevel + uint(base)];
    const GbufferTextureLevel coarse = levels[t.firstLevel + uint(min(base + 1.0, last))];
    const bool repeatS = (t.wrap & kTextureRepeatS) != 0u;
    const bool repeatT = (t.wrap & kTextureRepeatT) != 0u;
    vec4 sumFine = vec4(0.0);
    vec4 sumCoarse = vec4(0.0);
    for (int i = 0; i < int(taps); ++i) {
        const vec2 at = uv + axis * ((float(i) + 0.5) / taps - 0.5);
        sumFine += bilinear(fine, repeatS, repeatT, at);
        if (fraction > 0.0) sumCoarse += bilinear(coarse, repeatS, repeatT, at);
    }
    return mix(sumFine, sumCoarse, fraction) / taps;
}

void main() {
    const GbufferTriangle triangle = triangles[inTriangle];
    const GbufferMaterial material = materials[triangle.material];

    // Both faces reflect: the camera sees the side its ray arrives on (the CPU twin's
    // backFace is dot(normal, ray direction) > 0).
    const bool backFace = dot(triangle.normal, inPosition - pc.eye) > 0.0;
    const vec3 normal = backFace ? -triangle.normal : triangle.normal;

    vec3 albedo = material.baseColorFactor.rgb * inColor.rgb;
    if (material.baseColorTexture >= 0) {
        // core/camera.cpp CameraRays::footprintOnPlane: the pixel's sides on the triangle's
        // plane, from how the camera ray's direction changes per pixel; then the UV changes
        // along them (Scene::albedoOverFootprint).
        const vec3 toHit = inPosition - pc.eye;
        const vec3 forward =
            vec3(pc.clipFromWorld[0][3], pc.clipFromWorld[1][3], pc.clipFromWorld[2][3]);
        const float depth = dot(toHit, forward);
        const float along = dot(triangle.normal, toHit);
        const vec3 sx = depth * pc.directionPerPixelX.xyz;
        const vec3 sy = depth * pc.directionPerPixelY.xyz;
        const vec3 dPdx = sx - toHit * (dot(triangle.normal, sx) / along);
        const vec3 dPdy = sy - toHit * (dot(triangle.normal, sy) / along);
        const vec2 dUvdx = vec2(dot(triangle.uGradient, dPdx), dot(triangle.vGradient, dPdx));
        const vec2 dUvdy = vec2(dot(triangle.uGradient, dPdy), dot(triangle.vGradient, dPdy));
        albedo *= sampleFootprint(material.baseColorTexture,
                                  material.baseColorTexCoord == 1 ? inUv1 : inUv0, dUvdx,
                                  dUvdy).rgb;
    }

    // Emitters glow from their front face only.
    vec3 emission = vec3(0.0);
    if (!backFace) {
        emission = material.emission;
        if (material.emissiveTexture >= 0)
            emission *= sampleLevel(textures[material.emissiveTexture], 0, inUv0).rgb;
        emission *= emissiveScale[triangle.material];
    }

    const vec2 lightmapUv = triangle.lightmapped != 0u ? inLightmapUv : vec2(kNotLightmappedUv);
    outPositionU = vec4(inPosition, lightmapUv.x);
    outNormalV = vec4(normal, lightmapUv.y);
    outAlbedo = vec4(albedo, 1.0);
    outEmission = vec4(emission, 0.0);
}
