#pragma once
/// Queries against the scene's triangles with Embree 3: occlusion for visibility, closest hits
/// for cache placement and the path tracer, nearest points for measuring simplified shadow
/// casters. Thread-safe queries.

#include <cstdint>
#include <memory>
#include <optional>

#include <glm/glm.hpp>

#include "core/error.h"
#include "core/scene.h"

namespace pic {

/// The closest intersection of a ray with the scene.
struct RayHit {
    float t = 0.0f;               ///< distance along the (unit) ray direction, metres
    uint32_t triangle = 0;        ///< scene triangle index
    float b1 = 0.0f;              ///< barycentric weight of the triangle's vertex 1
    float b2 = 0.0f;              ///< barycentric weight of the triangle's vertex 2
    glm::vec3 geometricNormal{0.0f};  ///< unit, counter-clockwise winding
    bool backFace = false;        ///< the ray arrived from behind the triangle's winding
};

/// A committed Embree scene over all triangles of a pic::Scene.
class EmbreeScene {
public:
    /// Builds the acceleration structure; fails on Embree errors.
    static Result<std::unique_ptr<EmbreeScene>> create(const Scene& scene);
    ~EmbreeScene();
    EmbreeScene(const EmbreeScene&) = delete;
    EmbreeScene& operator=(const EmbreeScene&) = delete;

    /// True if anything blocks the segment origin + t·direction, t in (tNear, tFar).
    /// `direction` must be unit length.
    bool occluded(const glm::vec3& origin, const glm::vec3& direction, float tNear,
                  float tFar) const;

    /// Closest hit along origin + t·direction for t in (tNear, tFar), if any.
    std::optional<RayHit> intersect(const glm::vec3& origin, const glm::vec3& direction,
                                    float tNear, float tFar) const;

    /// Distance (metres) from `point` to the nearest point of the scene's triangles, +∞ when
    /// none lies within `limit` (an Embree point query; distances computed in double).
    float nearestDistance(const glm::vec3& point, float limit) const;

    /// A distance that is small against the scene (1e-5 of its diagonal, at least 1e-6 m),
    /// used to offset ray origins from surfaces.
    float epsilon() const { return mEpsilon; }

    const Scene& scene() const { return *mScene; }

private:
    EmbreeScene() = default;
    struct Impl;
    std::unique_ptr<Impl> mImpl;
    const Scene* mScene = nullptr;
    float mEpsilon = 1e-5f;
};

}  // namespace pic
