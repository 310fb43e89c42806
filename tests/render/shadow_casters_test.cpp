// Shadow-caster preparation (render/shadow_casters.h, CPU only, no Vulkan): coplanar triangles
// merge and curved ones stay, levels of detail are measured, clusters partition the triangles,
// and every triangle with a point inside a layer's clip volume is drawn.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "render/shadow_casters.h"

namespace pic {
namespace {

/// `count` small random triangles in the cube [−5, 5]³.
Scene randomTriangles(uint32_t count, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> where(-5.0f, 5.0f);
    std::uniform_real_distribution<float> offset(-0.3f, 0.3f);
    Scene scene;
    for (uint32_t t = 0; t < count; ++t) {
        const glm::vec3 centre(where(rng), where(rng), where(rng));
        Triangle tri;
        for (int k = 0; k < 3; ++k) {
            Vertex v;
            v.position = centre + glm::vec3(offset(rng), offset(rng), offset(rng));
            tri.v[k] = uint32_t(scene.vertices.size());
            scene.vertices.push_back(v);
            scene.bounds.extend(v.position);
        }
        scene.triangles.push_back(tri);
    }
    return scene;
}

/// Whether a world point lies inside Vulkan's clip volume of `clipFromWorld`.
bool insideClip(const glm::mat4& clipFromWorld, const glm::vec3& p) {
    const glm::vec4 c = clipFromWorld * glm::vec4(p, 1.0f);
    return c.w > 0.0f && std::abs(c.x) <= c.w && std::abs(c.y) <= c.w && c.z >= 0.0f && c.z <= c.w;
}

/// The total area of the scene's triangles, m².
double totalArea(const Scene& scene) {
    double area = 0.0;
    for (const Triangle& t : scene.triangles) {
        const glm::dvec3 a = scene.vertices[t.v[0]].position, b = scene.vertices[t.v[1]].position,
                         c = scene.vertices[t.v[2]].position;
        area += 0.5 * glm::length(glm::cross(b - a, c - a));
    }
    return area;
}

TEST(ShadowCasters, CoplanarTrianglesMergeAndCurvedOnesStay) {
    // A flat 2 m × 1 m floor tessellated into 20 × 10 cells with its own vertices per cell
    // (as exporters write it), and a tube of 16 facets, open at both ends.
    Scene scene;
    auto vertex = [&](const glm::vec3& p) {
        Vertex v;
        v.position = p;
        scene.vertices.push_back(v);
        scene.bounds.extend(p);
        return uint32_t(scene.vertices.size() - 1);
    };
    for (int i = 0; i < 20; ++i)
        for (int j = 0; j < 10; ++j) {
            const float x = 0.1f * float(i), z = 0.1f * float(j);
            const uint32_t a = vertex({x, 0, z}), b = vertex({x, 0, z + 0.1f}),
                           c = vertex({x + 0.1f, 0, z + 0.1f}), d = vertex({x + 0.1f, 0, z});
            scene.triangles.push_back(Triangle{{a, b, c}});
            scene.triangles.push_back(Triangle{{a, c, d}});
        }
    const size_t floorTriangles = scene.triangles.size();
    constexpr int kFacets = 16;
    for (int k = 0; k < kFacets; ++k) {
        const float a0 = 2.0f * 3.14159265f * float(k) / kFacets;
        const float a1 = 2.0f * 3.14159265f * float(k + 1) / kFacets;
        const glm::vec3 p0(3 + 0.2f * std::cos(a0), 0, 0.2f * std::sin(a0));
        const glm::vec3 p1(3 + 0.2f * std::cos(a1), 0, 0.2f * std::sin(a1));
        const uint32_t a = vertex(p0), b = vertex(p1), c = vertex(p1 + glm::vec3(0, 1, 0)),
                       d = vertex(p0 + glm::vec3(0, 1, 0));
        scene.triangles.push_back(Triangle{{a, c, b}});
        scene.triangles.push_back(Triangle{{a, d, c}});
    }
    const Scene casters = mergeShadowCasters(scene);
    // The floor's interior collapses; its border vertices stay, so what is left is a fan
    // over them, not 2 triangles. The tube cannot lose a facet.
    EXPECT_LT(casters.triangles.size(), 2 * kFacets + floorTriangles / 2);
    EXPECT_GE(casters.triangles.size(), size_t(2 * kFacets + 2));
    EXPECT_NEAR(totalArea(casters), totalArea(scene), 1e-5 * totalArea(scene));
    EXPECT_EQ(casters.bounds.min, scene.bounds.min);
    EXPECT_EQ(casters.bounds.max, scene.bounds.max);
}

/// Distance from p to triangle abc (closest point by region: vertices, edges, face).
float pointTriangleDistance(const glm::vec3& p, const glm::vec3& a, const glm::vec3& b,
                            const glm::vec3& c) {
    const glm::vec3 n = glm::cross(b - a, c - a);
    const float area2 = glm::dot(n, n);
    if (area2 > 0.0f) {
        // Barycentric coordinates of p's projection onto the plane.
        const glm::vec3 q = p - n * (glm::dot(p - a, n) / area2);
        const float u = glm::dot(glm::cross(c - b, q - b), n) / area2;
        const float v = glm::dot(glm::cross(a - c, q - c), n) / area2;
        if (u >= 0.0f && v >= 0.0f && u + v <= 1.0f) return glm::length(p - q);
    }
    auto segment = [&](const glm::vec3& s0, const glm::vec3& s1) {
        const glm::vec3 d = s1 - s0;
        const float len2 = glm::dot(d, d);
        const float t = len2 > 0.0f ? glm::clamp(glm::dot(p - s0, d) / len2, 0.0f, 1.0f) : 0.0f;
        return glm::length(p - (s0 + t * d));
    };
    return std::min({segment(a, b), segment(b, c), segment(c, a)});
}

/// Largest distance from a point of `fine` (its vertices, edge midpoints and centroids) to
/// the surface of `coarse`.
float deviation(const Scene& fine, const Scene& coarse) {
    float worst = 0.0f;
    for (const Triangle& t : fine.triangles) {
        const glm::vec3 a = fine.vertices[t.v[0]].position, b = fine.vertices[t.v[1]].position,
                        c = fine.vertices[t.v[2]].position;
        for (const glm::vec3& p : {a, b, c, 0.5f * (a + b), 0.5f * (b + c), 0.5f * (c + a),
                                   (a + b + c) / 3.0f}) {
            float nearest = std::numeric_limits<float>::infinity();
            for (const Triangle& u : coarse.triangles)
                nearest = std::min(nearest, pointTriangleDistance(p, coarse.vertices[u.v[0]].position,
                                                                  coarse.vertices[u.v[1]].position,
                                                                  coarse.vertices[u.v[2]].position));
            worst = std::max(worst, nearest);
        }
    }
    return worst;
}

/// A closed surface of revolution about the y axis through the profile points (radius,
/// height), `around` facets around, capped by fans where the radius is not 0.
Scene revolution(const std::vector<glm::vec2>& profile, int around) {
    Scene scene;
    auto vertex = [&](const glm::vec3& p) {
        Vertex v;
        v.position = p;
        scene.vertices.push_back(v);
        scene.bounds.extend(p);
        return uint32_t(scene.vertices.size() - 1);
    };
    auto point = [&](int k, size_t j) {
        const float a = 2.0f * 3.14159265f * float(k % around) / float(around);
        return glm::vec3(profile[j].x * std::cos(a), profile[j].y, profile[j].x * std::sin(a));
    };
    for (size_t j = 0; j + 1 < profile.size(); ++j)
        for (int k = 0; k < around; ++k) {
            const uint32_t a = vertex(point(k, j)), b = vertex(point(k + 1, j)),
                           c = vertex(point(k + 1, j + 1)), d = vertex(point(k, j + 1));
            scene.triangles.push_back(Triangle{{a, c, b}});
            scene.triangles.push_back(Triangle{{a, d, c}});
        }
    for (size_t j : {size_t{0}, profile.size() - 1}) {
        if (profile[j].x == 0.0f) continue;
        const uint32_t centre = vertex({0.0f, profile[j].y, 0.0f});
        for (int k = 0; k < around; ++k) {
            const uint32_t a = vertex(point(k, j)), b = vertex(point(k + 1, j));
            scene.triangles.push_back(j == 0 ? Triangle{{centre, a, b}} : Triangle{{centre, b, a}});
        }
    }
    return scene;
}

TEST(ShadowCasters, SurfaceDeviationIsMeasuredNotEstimated) {
    // A cylinder (r 0.5 m, 2 m high, 4 rings: coplanar strips) and a sphere (r 0.5 m), 32
    // facets around: a facet's sagitta is r·(1 − cos(π/32)) = 2.4 mm.
    std::vector<glm::vec2> cylinder, sphere;
    for (int j = 0; j <= 4; ++j) cylinder.push_back({0.5f, 0.5f * float(j)});
    for (int j = 0; j <= 16; ++j) {
        const float polar = 3.14159265f * float(j) / 16.0f;
        sphere.push_back({j == 0 || j == 16 ? 0.0f : 0.5f * std::sin(polar), -0.5f * std::cos(polar)});
    }
    for (const auto& profile : {cylinder, sphere}) {
        const Scene scene = revolution(profile, 32);
        const Scene merged = mergeShadowCasters(scene);
        EXPECT_LE(merged.triangles.size(), scene.triangles.size());
        EXPECT_NEAR(surfaceDeviation(scene, merged, 1.0f), deviation(scene, merged), 1e-5f);
        size_t previous = merged.triangles.size();
        for (float target : {0.004f, 0.02f, 0.1f}) {
            const Scene level = simplifyShadowCasters(merged, target);
            EXPECT_LT(level.triangles.size(), previous) << target;
            EXPECT_GT(level.triangles.size(), 0u) << target;
            // The measure (Embree point queries from corners and centroids) is what the
            // brute force over every pair finds, edge midpoints included.
            const float measured = surfaceDeviation(scene, level, 1.0f);
            const float exhaustive = deviation(scene, level);
            EXPECT_NEAR(measured, exhaustive, 0.05f * exhaustive + 1e-5f) << target;
            // Nothing within the limit: +∞.
            EXPECT_TRUE(std::isinf(surfaceDeviation(scene, level, 0.5f * measured)));
            previous = level.triangles.size();
        }
    }
}

TEST(ShadowCulling, NearestClusterDepthIsTheClosestVisibleBoxCorner) {
    // A light at the origin looking down −z (view depth = −z); boxes in front at 2 m and
    // 5 m, one behind it and one outside the 90° frustum at 1 m.
    const glm::mat4 clip = glm::perspectiveRH_ZO(glm::radians(90.0f), 1.0f, 0.01f, 20.0f) *
                           glm::lookAtRH(glm::vec3(0), glm::vec3(0, 0, -1), glm::vec3(0, 1, 0));
    auto cluster = [](const glm::vec3& lo, const glm::vec3& hi) {
        TriangleCluster c;
        c.bounds.extend(lo);
        c.bounds.extend(hi);
        return c;
    };
    std::vector<TriangleCluster> clusters = {
        cluster({-1, -1, -6}, {1, 1, -5}), cluster({0.5f, 0, -3}, {1, 0.2f, -2}),
        cluster({-1, -1, 1}, {1, 1, 3}), cluster({3, 0, -1.2f}, {4, 1, -1})};
    EXPECT_NEAR(nearestClusterDepth(clusters, clip), 2.0f, 1e-4f);
    clusters.erase(clusters.begin() + 1);
    EXPECT_NEAR(nearestClusterDepth(clusters, clip), 5.0f, 1e-4f);
    clusters.erase(clusters.begin());
    EXPECT_TRUE(std::isinf(nearestClusterDepth(clusters, clip)));
}

TEST(ShadowCulling, ClustersPartitionTheTrianglesAndBoundThem) {
    const Scene scene = randomTriangles(5000, 1);
    std::vector<uint32_t> order;
    const auto clusters = buildTriangleClusters(scene, 512, order);
    ASSERT_EQ(order.size(), scene.triangles.size());
    std::vector<int> seen(scene.triangles.size(), 0);
    for (uint32_t t : order) ++seen.at(t);
    for (int s : seen) EXPECT_EQ(s, 1);
    uint32_t next = 0;
    for (const TriangleCluster& c : clusters) {
        EXPECT_EQ(c.firstTriangle, next);
        EXPECT_GT(c.triangleCount, 0u);
        EXPECT_LE(c.triangleCount, 512u);
        next += c.triangleCount;
        for (uint32_t i = c.firstTriangle; i < c.firstTriangle + c.triangleCount; ++i)
            for (uint32_t v : scene.triangles[order[i]].v) {
                const glm::vec3 p = scene.vertices[v].position;
                EXPECT_TRUE(glm::all(glm::greaterThanEqual(p, c.bounds.min)) &&
                            glm::all(glm::lessThanEqual(p, c.bounds.max)));
            }
    }
    EXPECT_EQ(next, scene.triangles.size());
}

TEST(ShadowCulling, EveryTriangleInsideALayerIsDrawnAndCubeFacesSkipMost) {
    const Scene scene = randomTriangles(20000, 2);
    std::vector<uint32_t> order;
    const auto clusters = buildTriangleClusters(scene, 256, order);

    // The six cube faces of a point light inside the cloud, a narrow spot and an
    // orthographic layer over part of it, as the pass builds them.
    std::vector<glm::mat4> layers;
    const glm::vec3 light(0.7f, -1.2f, 0.4f);
    const glm::mat4 cube = glm::perspectiveRH_ZO(glm::radians(90.0f), 1.0f, 0.01f, 20.0f);
    const glm::vec3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (const glm::vec3& axis : axes) {
        const glm::vec3 up = std::abs(axis.y) > 0.9f ? glm::vec3(0, 0, 1) : glm::vec3(0, 1, 0);
        layers.push_back(cube * glm::lookAtRH(light, light + axis, up));
    }
    layers.push_back(glm::perspectiveRH_ZO(0.6f, 1.0f, 0.05f, 30.0f) *
                     glm::lookAtRH(glm::vec3(-6, 4, 2), glm::vec3(1, -1, 0), glm::vec3(0, 1, 0)));
    layers.push_back(glm::orthoRH_ZO(-2.0f, 3.0f, -1.0f, 2.0f, 0.0f, 12.0f) *
                     glm::lookAtRH(glm::vec3(0, 8, 0), glm::vec3(0.5f, 0, 0.2f), glm::vec3(0, 0, 1)));

    uint64_t cubeDrawn = 0;
    for (size_t l = 0; l < layers.size(); ++l) {
        const auto ranges = visibleTriangleRanges(clusters, layers[l]);
        std::vector<bool> drawn(scene.triangles.size(), false);
        uint32_t end = 0;
        for (const TriangleRange& r : ranges) {
            EXPECT_GE(r.firstTriangle, end) << "ranges overlap or are unsorted";
            end = r.firstTriangle + r.triangleCount;
            for (uint32_t i = r.firstTriangle; i < end; ++i) drawn[order[i]] = true;
            if (l < 6) cubeDrawn += r.triangleCount;
        }
        // Points on every triangle (vertices, edge midpoints, centroid) inside the volume
        // must belong to drawn triangles.
        for (size_t t = 0; t < scene.triangles.size(); ++t) {
            const glm::vec3 a = scene.vertices[scene.triangles[t].v[0]].position;
            const glm::vec3 b = scene.vertices[scene.triangles[t].v[1]].position;
            const glm::vec3 c = scene.vertices[scene.triangles[t].v[2]].position;
            const glm::vec3 samples[7] = {a, b, c, 0.5f * (a + b), 0.5f * (b + c), 0.5f * (c + a),
                                          (a + b + c) / 3.0f};
            for (const glm::vec3& p : samples) {
                if (insideClip(layers[l], p)) {
                    ASSERT_TRUE(drawn[t]) << "layer " << l << " culled visible triangle " << t;
                }
            }
        }
    }
    // Without culling the six faces would draw 6 × 20000 triangles; their frusta tile the
    // sphere, so one scene's worth plus the clusters that straddle faces is drawn (2.3× here:
    // a uniform cloud of 78 clusters around the light is the worst case for boxes).
    EXPECT_LT(cubeDrawn, 3u * scene.triangles.size());
    EXPECT_GE(cubeDrawn, scene.triangles.size());
}

}  // namespace
}  // namespace pic
