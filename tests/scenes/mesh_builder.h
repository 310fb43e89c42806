#pragma once
/// Flat-shaded world-space geometry for the test scenes: planar faces, subdivided quads, closed
/// boxes and cylinders, gathered into one glTF primitive per material.

#include <cstdint>
#include <map>
#include <vector>

#include <glm/glm.hpp>

#include "tests/scenes/gltf_builder.h"

namespace pic::testscenes {

/// Accumulates planar faces; each face owns its vertices (flat shading) and every triangle is wound
/// counter-clockwise seen from the side its face normal points to.
class MeshBuilder {
public:
    /// Faces added from now on use `material`.
    void setMaterial(uint32_t material);

    /// Starts a planar face with unit `normal`; the vertices added next belong to it.
    void beginFace(const glm::vec3& normal);
    /// Adds a vertex to the current face and returns the index to pass to addTriangle.
    uint32_t addVertex(const glm::vec3& position);
    /// Adds a triangle of the current face, ordering it counter-clockwise around the face normal;
    /// aborts if it is degenerate or not in the face's plane orientation.
    void addTriangle(uint32_t a, uint32_t b, uint32_t c);

    /// Planar convex quad p0 p1 p2 p3 (counter-clockwise seen from its front) in nu × nv cells.
    void addQuad(const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2, const glm::vec3& p3,
                 uint32_t nu = 1, uint32_t nv = 1);
    /// Closed box with outward faces, turned by `yawRadians` about +Y around its centre; each
    /// face is split into the cells of its two axes, shared edges carrying identical vertices.
    void addBox(const glm::vec3& center, const glm::vec3& halfExtents, float yawRadians = 0.0f,
                const glm::uvec3& cells = glm::uvec3(1));
    /// Closed upright cylinder with `segments` flat side facets and two fan caps (4·segments
    /// triangles), outward faces.
    void addCylinder(const glm::vec3& baseCenter, float radius, float height, uint32_t segments);

    /// Triangles added so far.
    uint64_t triangleCount() const { return mTriangleCount; }
    /// Hands over one primitive per material, in material order, and empties the builder.
    std::vector<PrimitiveData> takePrimitives();

private:
    /// Emits an nu × nv grid face from its (nu + 1) × (nv + 1) points, row-major in u.
    void addGrid(uint32_t nu, uint32_t nv, const glm::vec3& normal,
                 const std::vector<glm::vec3>& points);

    std::map<uint32_t, PrimitiveData> mPrimitives;
    uint32_t mMaterial = 0;
    PrimitiveData* mFace = nullptr;
    glm::vec3 mFaceNormal{0.0f};
    uint64_t mTriangleCount = 0;
};

}  // namespace pic::testscenes
