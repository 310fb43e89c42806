#include "core/scene.h"

#include <cmath>

#include "core/error.h"

namespace pic {

namespace {

/// Maps a texel coordinate (in texel units, centres at i + 0.5) to the index of the texel at or
/// left of it, and the next one, under the wrap mode; `fraction` is the weight of the second.
struct TexelPair {
    int i0;
    int i1;
    float fraction;
};

TexelPair texelPair(float coord, int size, bool repeat) {
    // Reduce before scaling so huge or negative coordinates never overflow the int conversion;
    // a non-finite coordinate reads texel 0 rather than spreading NaN into lighting.
    if (!std::isfinite(coord)) coord = 0.0f;
    coord = repeat ? coord - std::floor(coord) : std::fmin(std::fmax(coord, 0.0f), 1.0f);
    float x = coord * static_cast<float>(size) - 0.5f;
    float base = std::floor(x);
    int i0 = static_cast<int>(base);
    int i1 = i0 + 1;
    if (repeat) {
        if (i0 < 0) i0 += size;
        if (i1 >= size) i1 -= size;
    } else {
        i0 = i0 < 0 ? 0 : i0;
        i1 = i1 >= size ? size - 1 : i1;
    }
    return {i0, i1, x - base};
}

}  // namespace

glm::vec4 Texture::sample(glm::vec2 uv) const {
    PIC_DCHECK(width > 0 && height > 0 && texels.size() == size_t(width) * size_t(height));
    TexelPair s = texelPair(uv.x, width, repeatS);
    TexelPair t = texelPair(uv.y, height, repeatT);
    auto at = [&](int x, int y) { return texels[size_t(y) * size_t(width) + size_t(x)]; };
    glm::vec4 top = glm::mix(at(s.i0, t.i0), at(s.i1, t.i0), s.fraction);
    glm::vec4 bottom = glm::mix(at(s.i0, t.i1), at(s.i1, t.i1), s.fraction);
    return glm::mix(top, bottom, t.fraction);
}

float Scene::triangleArea(uint32_t t) const {
    const Triangle& tri = triangles[t];
    const glm::vec3& p0 = vertices[tri.v[0]].position;
    return 0.5f * glm::length(glm::cross(vertices[tri.v[1]].position - p0,
                                         vertices[tri.v[2]].position - p0));
}

glm::vec3 Scene::triangleNormal(uint32_t t) const {
    const Triangle& tri = triangles[t];
    const glm::vec3& p0 = vertices[tri.v[0]].position;
    glm::vec3 c = glm::cross(vertices[tri.v[1]].position - p0, vertices[tri.v[2]].position - p0);
    return c / glm::length(c);
}

glm::vec3 Scene::albedoAt(uint32_t t, float b1, float b2) const {
    const Triangle& tri = triangles[t];
    const Material& material = materials[tri.material];
    const Vertex& v0 = vertices[tri.v[0]];
    const Vertex& v1 = vertices[tri.v[1]];
    const Vertex& v2 = vertices[tri.v[2]];
    float b0 = 1.0f - b1 - b2;
    glm::vec3 albedo = glm::vec3(material.baseColorFactor) *
                       glm::vec3(b0 * v0.color + b1 * v1.color + b2 * v2.color);
    if (material.baseColorTexture >= 0) {
        glm::vec2 uv = material.baseColorTexCoord == 1 ? b0 * v0.uv1 + b1 * v1.uv1 + b2 * v2.uv1
                                                       : b0 * v0.uv0 + b1 * v1.uv0 + b2 * v2.uv0;
        albedo *= glm::vec3(textures[size_t(material.baseColorTexture)].sample(uv));
    }
    return albedo;
}

glm::vec3 Scene::emissionAt(uint32_t t, float b1, float b2) const {
    const Triangle& tri = triangles[t];
    const Material& material = materials[tri.material];
    if (material.emissiveTexture < 0) return material.emission;
    // The loader accepts emissive textures on TEXCOORD_0 only (Material has no texCoord for them).
    float b0 = 1.0f - b1 - b2;
    glm::vec2 uv =
        b0 * vertices[tri.v[0]].uv0 + b1 * vertices[tri.v[1]].uv0 + b2 * vertices[tri.v[2]].uv0;
    return material.emission * glm::vec3(textures[size_t(material.emissiveTexture)].sample(uv));
}

}  // namespace pic
