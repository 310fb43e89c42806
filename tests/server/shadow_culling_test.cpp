// Frustum culling of the shadow-map pass (CPU side, no Vulkan): clusters partition the
// triangles, and every triangle with a point inside a layer's clip volume is drawn.

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "server/passes/shadow_map_pass.h"

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
    const Scene casters = gpu::mergeShadowCasters(scene);
    // The floor's interior collapses; its border vertices stay, so what is left is a fan
    // over them, not 2 triangles. The tube cannot lose a facet.
    EXPECT_LT(casters.triangles.size(), 2 * kFacets + floorTriangles / 2);
    EXPECT_GE(casters.triangles.size(), size_t(2 * kFacets + 2));
    EXPECT_NEAR(totalArea(casters), totalArea(scene), 1e-5 * totalArea(scene));
    EXPECT_EQ(casters.bounds.min, scene.bounds.min);
    EXPECT_EQ(casters.bounds.max, scene.bounds.max);
}

TEST(ShadowCulling, ClustersPartitionTheTrianglesAndBoundThem) {
    const Scene scene = randomTriangles(5000, 1);
    std::vector<uint32_t> order;
    const auto clusters = gpu::buildTriangleClusters(scene, 512, order);
    ASSERT_EQ(order.size(), scene.triangles.size());
    std::vector<int> seen(scene.triangles.size(), 0);
    for (uint32_t t : order) ++seen.at(t);
    for (int s : seen) EXPECT_EQ(s, 1);
    uint32_t next = 0;
    for (const gpu::TriangleCluster& c : clusters) {
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
    const auto clusters = gpu::buildTriangleClusters(scene, 256, order);

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
        const auto ranges = gpu::visibleTriangleRanges(clusters, layers[l]);
        std::vector<bool> drawn(scene.triangles.size(), false);
        uint32_t end = 0;
        for (const gpu::TriangleRange& r : ranges) {
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
