#pragma once
/// The scene model every pic tool shares: triangles in world space (metres, Y up),
/// Lambertian materials, KHR_lights_punctual lights and pinhole cameras (ARCHITECTURE.md §4).

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "core/texture.h"

namespace pic {

/// Axis-aligned bounding box; empty when min > max.
struct Aabb {
    glm::vec3 min{std::numeric_limits<float>::max()};
    glm::vec3 max{-std::numeric_limits<float>::max()};

    void extend(const glm::vec3& p) {
        min = glm::min(min, p);
        max = glm::max(max, p);
    }
    void extend(const Aabb& b) {
        min = glm::min(min, b.min);
        max = glm::max(max, b.max);
    }
    bool empty() const { return min.x > max.x; }
    glm::vec3 extent() const { return empty() ? glm::vec3(0.0f) : max - min; }
    glm::vec3 center() const { return 0.5f * (min + max); }
    /// Length of the diagonal in metres.
    float diagonal() const { return glm::length(extent()); }
};

/// A Lambertian material: albedo = baseColorFactor × baseColorTexture × vertex colour.
struct Material {
    std::string name;
    glm::vec4 baseColorFactor{1.0f};
    int baseColorTexture = -1;   ///< index into Scene::textures, -1 for none
    int baseColorTexCoord = 0;   ///< 0 for TEXCOORD_0, 1 for TEXCOORD_1
    glm::vec3 emission{0.0f};    ///< radiance W/(m²·sr): emissiveFactor × emissive_strength
    int emissiveTexture = -1;    ///< index into Scene::textures multiplying emission, -1 for none
    bool doubleSided = false;
};

/// A mesh vertex in world space.
struct Vertex {
    glm::vec3 position{0.0f};  ///< metres, world space
    glm::vec3 normal{0.0f};    ///< unit, world space
    glm::vec2 uv0{0.0f};       ///< TEXCOORD_0
    glm::vec2 uv1{0.0f};       ///< TEXCOORD_1 (meaningful only when the primitive has it)
    glm::vec4 color{1.0f};     ///< COLOR_0, linear RGBA
};

/// One triangle: three vertex indices, its material and the primitive it came from.
struct Triangle {
    uint32_t v[3] = {0, 0, 0};
    uint32_t material = 0;
    uint32_t primitive = 0;
};

/// One glTF mesh primitive instanced under one node, as a contiguous triangle range.
struct Primitive {
    std::string name;             ///< "mesh/primitive" for messages
    uint32_t firstTriangle = 0;
    uint32_t triangleCount = 0;
    bool hasUv1 = false;          ///< TEXCOORD_1 present: used as light-map UVs
};

enum class LightType { Point, Spot, Directional };

/// A KHR_lights_punctual light with its numbers read as radiometric units (ARCHITECTURE.md §4).
struct Light {
    std::string id;
    LightType type = LightType::Point;
    glm::vec3 position{0.0f};                      ///< metres, world space (point, spot)
    glm::vec3 direction{0.0f, 0.0f, -1.0f};        ///< unit, the direction light travels (spot, directional)
    glm::vec3 color{1.0f};
    float intensity = 1.0f;                        ///< W/sr (point, spot) or W/m² (directional)
    float innerConeAngle = 0.0f;                   ///< radians, half-angle
    float outerConeAngle = 0.7853981634f;          ///< radians, half-angle
    float range = std::numeric_limits<float>::infinity();  ///< metres; infinity = no cut-off
    friend bool operator==(const Light&, const Light&) = default;
};

/// A pinhole camera.
struct Camera {
    std::string name;
    glm::vec3 eye{0.0f};
    glm::vec3 target{0.0f, 0.0f, -1.0f};
    glm::vec3 up{0.0f, 1.0f, 0.0f};
    float fovyDegrees = 60.0f;
};

/// How the UV of a point changes as it moves in its triangle's plane (Scene::uvGradients).
struct UvGradients {
    glm::vec3 u{0.0f};  ///< ∂u/∂position, per metre
    glm::vec3 v{0.0f};  ///< ∂v/∂position, per metre
};

/// A loaded scene: a flat triangle list in world space plus materials, lights and cameras.
struct Scene {
    std::string sourcePath;
    std::vector<Vertex> vertices;
    std::vector<Triangle> triangles;
    std::vector<Primitive> primitives;
    std::vector<Material> materials;
    std::vector<Texture> textures;
    std::vector<Light> lights;
    std::vector<Camera> cameras;
    Aabb bounds;
    double totalArea = 0.0;        ///< sum of triangle areas, m²
    uint64_t hash = 0;             ///< content hash of geometry and materials
    uint32_t droppedDegenerate = 0;  ///< zero-area triangles skipped at load
    uint32_t rewound = 0;  ///< triangles turned at load to wind counter-clockwise about their normals

    /// Area of triangle t in m².
    float triangleArea(uint32_t t) const;
    /// Unit geometric normal of triangle t (counter-clockwise winding).
    glm::vec3 triangleNormal(uint32_t t) const;
    /// Albedo (linear RGB) at barycentric (b1, b2) of triangle t, texture and vertex colour
    /// included; the texture read bilinearly at the point (level 0).
    glm::vec3 albedoAt(uint32_t t, float b1, float b2) const;
    /// The gradients of the UV set `texCoord` (0 or 1) of triangle t in its plane: the point
    /// p0 + d of the plane has uv(p0) + (dot(gradients.u, d), dot(gradients.v, d)). Zero for
    /// a triangle whose corners share one UV.
    UvGradients uvGradients(uint32_t t, int texCoord) const;
    /// albedoAt with the base-colour texture averaged over the pixel footprint whose sides are
    /// the hit position's changes per pixel dPdx, dPdy (metres, in the triangle's plane):
    /// Texture::sampleFootprint of the UV changes uvGradients gives for them.
    glm::vec3 albedoOverFootprint(uint32_t t, float b1, float b2, const glm::vec3& dPdx,
                                  const glm::vec3& dPdy) const;
    /// Emitted radiance at barycentric (b1, b2) of triangle t.
    glm::vec3 emissionAt(uint32_t t, float b1, float b2) const;
};

/// Sets `scene`'s bounds, total area and content hash (over geometry, materials and their
/// texels) from its vertices, triangles, materials and textures: the last step of loading or
/// building a scene.
void finishScene(Scene& scene);

}  // namespace pic
