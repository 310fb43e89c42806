#include "tests/scenes/mesh_builder.h"

#include <cmath>
#include <initializer_list>
#include <numbers>
#include <tuple>
#include <utility>

#include "core/error.h"

namespace pic::testscenes {

namespace {

/// Lattice coordinates min..max in `cells` steps with both ends exact.
std::vector<float> lattice(float min, float max, uint32_t cells) {
    std::vector<float> values(cells + 1);
    for (uint32_t i = 0; i <= cells; ++i)
        values[i] = i == cells ? max : min + (max - min) * float(i) / float(cells);
    return values;
}

/// Newell's normal of a planar polygon, unit length.
glm::vec3 polygonNormal(std::initializer_list<glm::vec3> corners) {
    glm::vec3 n(0.0f);
    const glm::vec3* points = corners.begin();
    for (size_t i = 0; i < corners.size(); ++i) {
        const glm::vec3& a = points[i];
        const glm::vec3& b = points[(i + 1) % corners.size()];
        n += glm::vec3((a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x),
                       (a.x - b.x) * (a.y + b.y));
    }
    PIC_CHECK(glm::length(n) > 0.0f);
    return glm::normalize(n);
}

}  // namespace

void MeshBuilder::setMaterial(uint32_t material) {
    mMaterial = material;
    mFace = nullptr;
}

void MeshBuilder::beginFace(const glm::vec3& normal) {
    PIC_CHECK(std::abs(glm::length(normal) - 1.0f) < 1e-4f);
    mFace = &mPrimitives[mMaterial];
    mFace->material = mMaterial;
    mFaceNormal = normal;
}

uint32_t MeshBuilder::addVertex(const glm::vec3& position) {
    PIC_CHECK(mFace != nullptr);
    mFace->positions.push_back(position);
    mFace->normals.push_back(mFaceNormal);
    return uint32_t(mFace->positions.size() - 1);
}

void MeshBuilder::addTriangle(uint32_t a, uint32_t b, uint32_t c) {
    PIC_CHECK(mFace != nullptr);
    const std::vector<glm::vec3>& p = mFace->positions;
    const glm::vec3 n = glm::cross(p[b] - p[a], p[c] - p[a]);
    const float length = glm::length(n);
    PIC_CHECK(length > 0.0f);
    // A triangle of a planar face is parallel to the face, so its normal is ±the face normal.
    const float alignment = glm::dot(n, mFaceNormal) / length;
    PIC_CHECK(std::abs(alignment) > 0.999f);
    if (alignment < 0.0f) std::swap(b, c);
    mFace->indices.insert(mFace->indices.end(), {a, b, c});
    ++mTriangleCount;
}

void MeshBuilder::addGrid(uint32_t nu, uint32_t nv, const glm::vec3& normal,
                          const std::vector<glm::vec3>& points) {
    PIC_CHECK(nu > 0 && nv > 0);
    PIC_CHECK(points.size() == size_t(nu + 1) * (nv + 1));
    beginFace(normal);
    const uint32_t first = addVertex(points[0]);
    for (size_t k = 1; k < points.size(); ++k) addVertex(points[k]);
    const auto at = [&](uint32_t i, uint32_t j) { return first + j * (nu + 1) + i; };
    for (uint32_t j = 0; j < nv; ++j) {
        for (uint32_t i = 0; i < nu; ++i) {
            addTriangle(at(i, j), at(i + 1, j), at(i + 1, j + 1));
            addTriangle(at(i, j), at(i + 1, j + 1), at(i, j + 1));
        }
    }
}

void MeshBuilder::addQuad(const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2,
                          const glm::vec3& p3, uint32_t nu, uint32_t nv) {
    std::vector<glm::vec3> points;
    points.reserve(size_t(nu + 1) * (nv + 1));
    // Bilinear lattice; rows at exact v = 0 and v = 1 reproduce the corners bit for bit.
    for (uint32_t j = 0; j <= nv; ++j) {
        const float t = j == nv ? 1.0f : float(j) / float(nv);
        const glm::vec3 left = j == nv ? p3 : j == 0 ? p0 : p0 + (p3 - p0) * t;
        const glm::vec3 right = j == nv ? p2 : j == 0 ? p1 : p1 + (p2 - p1) * t;
        for (uint32_t i = 0; i <= nu; ++i)
            points.push_back(i == 0    ? left
                             : i == nu ? right
                                       : left + (right - left) * (float(i) / float(nu)));
    }
    addGrid(nu, nv, polygonNormal({p0, p1, p2, p3}), points);
}

void MeshBuilder::addBox(const glm::vec3& center, const glm::vec3& halfExtents, float yawRadians,
                         const glm::uvec3& cells) {
    PIC_CHECK(halfExtents.x > 0.0f && halfExtents.y > 0.0f && halfExtents.z > 0.0f);
    const std::vector<float> xs = lattice(-halfExtents.x, halfExtents.x, cells.x);
    const std::vector<float> ys = lattice(-halfExtents.y, halfExtents.y, cells.y);
    const std::vector<float> zs = lattice(-halfExtents.z, halfExtents.z, cells.z);
    const float c = std::cos(yawRadians);
    const float s = std::sin(yawRadians);
    const auto rotate = [c, s](const glm::vec3& v) {
        return glm::vec3(c * v.x + s * v.z, v.y, -s * v.x + c * v.z);
    };
    // Every face reads its points from the same (i, j, k) lattice, so shared edges match exactly.
    const auto point = [&](uint32_t i, uint32_t j, uint32_t k) {
        return center + rotate(glm::vec3(xs[i], ys[j], zs[k]));
    };
    // For each face: its normal and how its grid (u, v) maps to lattice indices; cross(u, v)
    // points out of the box.
    const auto face = [&](const glm::vec3& normal, uint32_t nu, uint32_t nv, auto latticeAt) {
        std::vector<glm::vec3> points;
        points.reserve(size_t(nu + 1) * (nv + 1));
        for (uint32_t v = 0; v <= nv; ++v)
            for (uint32_t u = 0; u <= nu; ++u) points.push_back(latticeAt(u, v));
        addGrid(nu, nv, rotate(normal), points);
    };
    const uint32_t nx = cells.x, ny = cells.y, nz = cells.z;
    face({1, 0, 0}, ny, nz, [&](uint32_t u, uint32_t v) { return point(nx, u, v); });
    face({-1, 0, 0}, nz, ny, [&](uint32_t u, uint32_t v) { return point(0, v, u); });
    face({0, 1, 0}, nz, nx, [&](uint32_t u, uint32_t v) { return point(v, ny, u); });
    face({0, -1, 0}, nx, nz, [&](uint32_t u, uint32_t v) { return point(u, 0, v); });
    face({0, 0, 1}, nx, ny, [&](uint32_t u, uint32_t v) { return point(u, v, nz); });
    face({0, 0, -1}, ny, nx, [&](uint32_t u, uint32_t v) { return point(v, u, 0); });
}

void MeshBuilder::addCylinder(const glm::vec3& baseCenter, float radius, float height,
                              uint32_t segments) {
    PIC_CHECK(segments >= 3 && radius > 0.0f && height > 0.0f);
    const glm::vec3 topCenter = baseCenter + glm::vec3(0.0f, height, 0.0f);
    std::vector<glm::vec3> bottom(segments);
    std::vector<glm::vec3> top(segments);
    for (uint32_t i = 0; i < segments; ++i) {
        const double phi = 2.0 * std::numbers::pi * double(i) / double(segments);
        const glm::vec3 offset(float(radius * std::cos(phi)), 0.0f, float(radius * std::sin(phi)));
        bottom[i] = baseCenter + offset;
        top[i] = topCenter + offset;
    }
    for (uint32_t i = 0; i < segments; ++i) {
        const uint32_t next = (i + 1) % segments;
        const double mid = 2.0 * std::numbers::pi * (double(i) + 0.5) / double(segments);
        beginFace(glm::vec3(float(std::cos(mid)), 0.0f, float(std::sin(mid))));
        const uint32_t b0 = addVertex(bottom[i]);
        const uint32_t t0 = addVertex(top[i]);
        const uint32_t t1 = addVertex(top[next]);
        const uint32_t b1 = addVertex(bottom[next]);
        addTriangle(b0, t0, t1);
        addTriangle(b0, t1, b1);
    }
    for (const auto& [center, rim, normal] :
         {std::tuple{topCenter, &top, glm::vec3(0, 1, 0)},
          std::tuple{baseCenter, &bottom, glm::vec3(0, -1, 0)}}) {
        beginFace(normal);
        const uint32_t hub = addVertex(center);
        const uint32_t first = addVertex((*rim)[0]);
        for (uint32_t i = 1; i < segments; ++i) addVertex((*rim)[i]);
        for (uint32_t i = 0; i < segments; ++i)
            addTriangle(hub, first + i, first + (i + 1) % segments);
    }
}

std::vector<PrimitiveData> MeshBuilder::takePrimitives() {
    std::vector<PrimitiveData> primitives;
    primitives.reserve(mPrimitives.size());
    for (auto& [material, primitive] : mPrimitives) primitives.push_back(std::move(primitive));
    mPrimitives.clear();
    mFace = nullptr;
    mTriangleCount = 0;
    return primitives;
}

}  // namespace pic::testscenes
