// The Embree scene (rays/embree_scene.h) against answers worked out by hand: a unit square
// and a triangle behind it, occlusion over an open segment, the closest hit's distance,
// barycentrics, normal and side, and point queries against a brute force over the triangles.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "rays/embree_scene.h"

namespace pic {
namespace {

/// Adds triangle abc (counter-clockwise seen from where its normal points).
void addTriangle(Scene& scene, glm::vec3 a, glm::vec3 b, glm::vec3 c) {
    Triangle triangle;
    for (int k = 0; k < 3; ++k) {
        Vertex vertex;
        vertex.position = k == 0 ? a : k == 1 ? b : c;
        triangle.v[k] = uint32_t(scene.vertices.size());
        scene.vertices.push_back(vertex);
        scene.bounds.extend(vertex.position);
    }
    scene.triangles.push_back(triangle);
}

/// The square [0, 1]² at z = 0 facing +z (triangles 0 and 1) and a triangle at z = −1 facing
/// +z (triangle 2).
Scene squareAndTriangle() {
    Scene scene;
    scene.sourcePath = "square.gltf";
    addTriangle(scene, {0, 0, 0}, {1, 0, 0}, {1, 1, 0});
    addTriangle(scene, {0, 0, 0}, {1, 1, 0}, {0, 1, 0});
    addTriangle(scene, {0, 0, -1}, {2, 0, -1}, {0, 2, -1});
    return scene;
}

TEST(EmbreeScene, OcclusionCountsOnlyTheOpenSegment) {
    const Scene scene = squareAndTriangle();
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays) << rays.error().message;
    const glm::vec3 down(0.0f, 0.0f, -1.0f);
    EXPECT_TRUE((*rays)->occluded({0.5f, 0.25f, 1.0f}, down, 0.0f, 2.0f));
    // The square sits at t = 1: a segment that ends before it, or starts after the triangle at
    // t = 2, sees nothing.
    EXPECT_FALSE((*rays)->occluded({0.5f, 0.25f, 1.0f}, down, 0.0f, 0.99f));
    EXPECT_FALSE((*rays)->occluded({0.5f, 0.25f, 1.0f}, down, 2.01f, 10.0f));
    // Beside the square but over the triangle.
    EXPECT_TRUE((*rays)->occluded({1.5f, 0.25f, 1.0f}, down, 0.0f, 10.0f));
    EXPECT_FALSE((*rays)->occluded({1.5f, 1.5f, 1.0f}, down, 0.0f, 10.0f));
}

TEST(EmbreeScene, ClosestHitGivesDistanceBarycentricsNormalAndSide) {
    const Scene scene = squareAndTriangle();
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays) << rays.error().message;
    auto hit = (*rays)->intersect({0.75f, 0.25f, 3.0f}, {0.0f, 0.0f, -1.0f}, 0.0f, 100.0f);
    ASSERT_TRUE(hit);
    EXPECT_NEAR(hit->t, 3.0f, 1e-5f);
    EXPECT_EQ(hit->triangle, 0u);
    // (0.75, 0.25) = (1 − b1 − b2)·(0, 0) + b1·(1, 0) + b2·(1, 1): b2 = 0.25, b1 = 0.5.
    EXPECT_NEAR(hit->b1, 0.5f, 1e-5f);
    EXPECT_NEAR(hit->b2, 0.25f, 1e-5f);
    EXPECT_NEAR(glm::distance(hit->geometricNormal, glm::vec3(0, 0, 1)), 0.0f, 1e-6f);
    EXPECT_FALSE(hit->backFace);

    // From below, the first surface is the triangle's back, then the square's.
    auto below = (*rays)->intersect({0.5f, 0.25f, -2.0f}, {0.0f, 0.0f, 1.0f}, 0.0f, 100.0f);
    ASSERT_TRUE(below);
    EXPECT_EQ(below->triangle, 2u);
    EXPECT_NEAR(below->t, 1.0f, 1e-5f);
    EXPECT_TRUE(below->backFace);
    auto past = (*rays)->intersect({0.5f, 0.25f, -2.0f}, {0.0f, 0.0f, 1.0f}, 1.5f, 100.0f);
    ASSERT_TRUE(past);
    EXPECT_EQ(past->triangle, 0u);
    EXPECT_NEAR(past->t, 2.0f, 1e-5f);
    EXPECT_FALSE((*rays)->intersect({5.0f, 5.0f, 1.0f}, {0.0f, 0.0f, -1.0f}, 0.0f, 100.0f));
}

TEST(EmbreeScene, NearestDistanceIsTheClosestPointOfAnyTriangle) {
    const Scene scene = squareAndTriangle();
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays) << rays.error().message;
    // Above the square's interior, off its corner, off an edge, and under the square.
    EXPECT_NEAR((*rays)->nearestDistance({0.3f, 0.6f, 0.25f}, 10.0f), 0.25f, 1e-6f);
    EXPECT_NEAR((*rays)->nearestDistance({2.0f, 2.0f, 0.0f}, 10.0f), std::sqrt(2.0f), 1e-6f);
    EXPECT_NEAR((*rays)->nearestDistance({0.5f, -0.5f, 0.5f}, 10.0f), std::sqrt(0.5f), 1e-6f);
    EXPECT_NEAR((*rays)->nearestDistance({0.5f, 0.25f, -0.6f}, 10.0f), 0.4f, 1e-6f);
    // Nothing within the limit: +∞.
    EXPECT_EQ((*rays)->nearestDistance({0.5f, 0.5f, 3.0f}, 1.0f),
              std::numeric_limits<float>::infinity());
}

TEST(EmbreeScene, NearestDistanceMatchesABruteForceOverSampledSurfacePoints) {
    // Random triangles; the brute force samples each densely (its minimum is an upper bound
    // within the sampling step of the exact distance).
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> where(-1.0f, 1.0f);
    Scene scene;
    for (int t = 0; t < 20; ++t)
        addTriangle(scene, {where(rng), where(rng), where(rng)}, {where(rng), where(rng), where(rng)},
                    {where(rng), where(rng), where(rng)});
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays) << rays.error().message;
    constexpr int kSteps = 200;
    for (int q = 0; q < 20; ++q) {
        const glm::vec3 p(2.0f * where(rng), 2.0f * where(rng), 2.0f * where(rng));
        float brute = std::numeric_limits<float>::infinity();
        for (const Triangle& t : scene.triangles) {
            const glm::vec3 a = scene.vertices[t.v[0]].position, b = scene.vertices[t.v[1]].position,
                            c = scene.vertices[t.v[2]].position;
            for (int i = 0; i <= kSteps; ++i)
                for (int j = 0; i + j <= kSteps; ++j) {
                    const float u = float(i) / kSteps, v = float(j) / kSteps;
                    brute = std::min(brute, glm::distance(p, a + u * (b - a) + v * (c - a)));
                }
        }
        const float nearest = (*rays)->nearestDistance(p, 100.0f);
        EXPECT_LE(nearest, brute + 1e-5f) << q;
        EXPECT_GE(nearest, brute - 0.02f) << q;  // 2 m edges / 200 steps, with margin
    }
}

TEST(EmbreeScene, AnEmptySceneIsRefusedByName) {
    Scene scene;
    scene.sourcePath = "empty.gltf";
    auto rays = EmbreeScene::create(scene);
    ASSERT_FALSE(rays);
    EXPECT_EQ(rays.error().code, ErrorCode::InvalidInput);
    EXPECT_NE(rays.error().message.find("empty.gltf"), std::string::npos);
}

}  // namespace
}  // namespace pic
