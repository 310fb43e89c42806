#version 460
// G-buffer (render/passes/gbuffer_pass.h): what shading needs of the surface a pixel centre sees,
// computed as the CPU twin (render/cpu/cache_shading.cpp) computes it at a ray hit: the
// geometric normal facing the camera, Scene::albedoAt (baseColorFactor × vertex colour ×
// bilinear base-colour texture), Scene::emissionAt × the light set's emissive scale on front
// faces, and the light-map UV of light-mapped triangles. Layout in shared/gbuffer.h.
#extension GL_GOOGLE_include_directive : require
#include "shared/gbuffer.h"

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
layout(push_constant) uniform Push { GbufferPush pc; };

layout(location = 0) out vec4 outPositionU;
layout(location = 1) out vec4 outNormalV;
layout(location = 2) out vec4 outAlbedo;
layout(location = 3) out vec4 outEmission;

/// core/scene.cpp texelPair: the texel at or left of a coordinate (texel centres at i + 0.5),
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

/// core/scene.h Texture::sample: bilinear with the texture's wrap modes.
vec4 sampleTexture(int index, vec2 uv) {
    const GbufferTexture t = textures[index];
    int s0, s1, t0, t1;
    float fs, ft;
    texelPair(uv.x, t.width, (t.wrap & kTextureRepeatS) != 0u, s0, s1, fs);
    texelPair(uv.y, t.height, (t.wrap & kTextureRepeatT) != 0u, t0, t1, ft);
    const uint row0 = t.firstTexel + uint(t0 * t.width);
    const uint row1 = t.firstTexel + uint(t1 * t.width);
    const vec4 top = mix(texels[row0 + uint(s0)], texels[row0 + uint(s1)], fs);
    const vec4 bottom = mix(texels[row1 + uint(s0)], texels[row1 + uint(s1)], fs);
    return mix(top, bottom, ft);
}

void main() {
    const GbufferTriangle triangle = triangles[inTriangle];
    const GbufferMaterial material = materials[triangle.material];

    // Both faces reflect: the camera sees the side its ray arrives on (the CPU twin's
    // backFace is dot(normal, ray direction) > 0).
    const bool backFace = dot(triangle.normal, inPosition - pc.eye) > 0.0;
    const vec3 normal = backFace ? -triangle.normal : triangle.normal;

    vec3 albedo = material.baseColorFactor.rgb * inColor.rgb;
    if (material.baseColorTexture >= 0)
        albedo *= sampleTexture(material.baseColorTexture,
                                material.baseColorTexCoord == 1 ? inUv1 : inUv0).rgb;

    // Emitters glow from their front face only.
    vec3 emission = vec3(0.0);
    if (!backFace) {
        emission = material.emission;
        if (material.emissiveTexture >= 0)
            emission *= sampleTexture(material.emissiveTexture, inUv0).rgb;
        emission *= emissiveScale[triangle.material];
    }

    const vec2 lightmapUv = triangle.lightmapped != 0u ? inLightmapUv : vec2(kNotLightmappedUv);
    outPositionU = vec4(inPosition, lightmapUv.x);
    outNormalV = vec4(normal, lightmapUv.y);
    outAlbedo = vec4(albedo, 1.0);
    outEmission = vec4(emission, 0.0);
}
