#include "core/scene.h"

#include <cmath>

#include "core/error.h"
#include "core/hash.h"

namespace pic {

namespace {

/// The UV of set `texCoord` at barycentric (b0, b1, b2) of triangle `tri`.
glm::vec2 uvAt(const Scene& scene, const Triangle& tri, int texCoord, float b0, float b1,
               float b2) {
    const Vertex& v0 = scene.vertices[tri.v[0]];
    const Vertex& v1 = scene.vertices[tri.v[1]];
    const Vertex& v2 = scene.vertices[tri.v[2]];
    return texCoord == 1 ? b0 * v0.uv1 + b1 * v1.uv1 + b2 * v2.uv1
                         : b0 * v0.uv0 + b1 * v1.uv0 + b2 * v2.uv0;
}

/// baseColorFactor × the interpolated vertex colour: the albedo before its texture.
glm::vec3 untexturedAlbedo(const Scene& scene, const Triangle& tri, float b0, float b1, float b2) {
    return glm::vec3(scene.materials[tri.material].baseColorFactor) *
           glm::vec3(b0 * scene.vertices[tri.v[0]].color + b1 * scene.vertices[tri.v[1]].color +
                     b2 * scene.vertices[tri.v[2]].color);
}

}  // namespace

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
    const float b0 = 1.0f - b1 - b2;
    glm::vec3 albedo = untexturedAlbedo(*this, tri, b0, b1, b2);
    if (material.baseColorTexture >= 0)
        albedo *= glm::vec3(textures[size_t(material.baseColorTexture)].sample(
            uvAt(*this, tri, material.baseColorTexCoord, b0, b1, b2)));
    return albedo;
}

UvGradients Scene::uvGradients(uint32_t t, int texCoord) const {
    const Triangle& tri = triangles[t];
    const glm::dvec3 p0 = vertices[tri.v[0]].position;
    const glm::dvec3 e1 = glm::dvec3(vertices[tri.v[1]].position) - p0;
    const glm::dvec3 e2 = glm::dvec3(vertices[tri.v[2]].position) - p0;
    const glm::dvec2 uv0 = uvAt(*this, tri, texCoord, 1.0f, 0.0f, 0.0f);
    const glm::dvec2 d1 = glm::dvec2(uvAt(*this, tri, texCoord, 0.0f, 1.0f, 0.0f)) - uv0;
    const glm::dvec2 d2 = glm::dvec2(uvAt(*this, tri, texCoord, 0.0f, 0.0f, 1.0f)) - uv0;
    // A gradient g in the plane is α·e1 + β·e2 with g·e1 = Δ1 and g·e2 = Δ2: the 2×2 Gram
    // system, in double so that slivers keep their digits.
    const double a = glm::dot(e1, e1), b = glm::dot(e1, e2), c = glm::dot(e2, e2);
    const double det = a * c - b * b;
    if (!(det > 0.0)) return {};
    const auto gradient = [&](double delta1, double delta2) {
        return glm::vec3(((c * delta1 - b * delta2) * e1 + (a * delta2 - b * delta1) * e2) / det);
    };
    return {gradient(d1.x, d2.x), gradient(d1.y, d2.y)};
}

glm::vec3 Scene::albedoOverFootprint(uint32_t t, float b1, float b2, const glm::vec3& dPdx,
                                     const glm::vec3& dPdy) const {
    const Triangle& tri = triangles[t];
    const Material& material = materials[tri.material];
    const float b0 = 1.0f - b1 - b2;
    glm::vec3 albedo = untexturedAlbedo(*this, tri, b0, b1, b2);
    if (material.baseColorTexture >= 0) {
        const UvGradients g = uvGradients(t, material.baseColorTexCoord);
        const glm::vec2 dUvdx(glm::dot(g.u, dPdx), glm::dot(g.v, dPdx));
        const glm::vec2 dUvdy(glm::dot(g.u, dPdy), glm::dot(g.v, dPdy));
        albedo *= glm::vec3(textures[size_t(material.baseColorTexture)].sampleFootprint(
            uvAt(*this, tri, material.baseColorTexCoord, b0, b1, b2), dUvdx, dUvdy));
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

void finishScene(Scene& scene) {
    scene.bounds = Aabb{};
    for (const Vertex& v : scene.vertices) scene.bounds.extend(v.position);
    double area = 0.0;
    for (uint32_t t = 0; t < scene.triangles.size(); ++t) area += scene.triangleArea(t);
    scene.totalArea = area;

    static_assert(sizeof(Vertex) == 14 * sizeof(float), "Vertex must have no padding");
    static_assert(sizeof(Triangle) == 5 * sizeof(uint32_t), "Triangle must have no padding");
    uint64_t h = hashVector(scene.vertices);
    h = hashVector(scene.triangles, h);
    for (const Material& m : scene.materials) {
        h = hashBytes(m.name.data(), m.name.size(), h);
        h = hashBytes(&m.baseColorFactor, sizeof(m.baseColorFactor), h);
        h = hashBytes(&m.baseColorTexture, sizeof(m.baseColorTexture), h);
        h = hashBytes(&m.baseColorTexCoord, sizeof(m.baseColorTexCoord), h);
        h = hashBytes(&m.emission, sizeof(m.emission), h);
        h = hashBytes(&m.emissiveTexture, sizeof(m.emissiveTexture), h);
        uint8_t doubleSided = m.doubleSided ? 1 : 0;
        h = hashBytes(&doubleSided, 1, h);
    }
    for (const Texture& t : scene.textures) {
        int32_t header[4] = {t.width, t.height, t.repeatS ? 1 : 0, t.repeatT ? 1 : 0};
        h = hashBytes(header, sizeof(header), h);
        h = hashVector(t.texels, h);
    }
    scene.hash = h;
}

}  // namespace pic
