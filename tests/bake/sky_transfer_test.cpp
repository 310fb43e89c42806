// Sky transfer (bake/sky_transfer.h): against the clamped cosine and the cone of core/sh.h
// where nothing blocks the sky, zero where everything does, and half of it under a wall.

#include "bake/sky_transfer.h"

#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

#include "core/sh.h"
#include "core/sky.h"
#include "rays/embree_scene.h"

namespace pic {
namespace {

/// Adds the quad a b c d (counter-clockwise seen from its front) to `scene`.
void addQuad(Scene& scene, glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d) {
    for (const auto& corners : {std::array{a, b, c}, std::array{a, c, d}}) {
        Triangle t;
        for (int k = 0; k < 3; ++k) {
            Vertex v;
            v.position = corners[size_t(k)];
            t.v[k] = uint32_t(scene.vertices.size());
            scene.vertices.push_back(v);
            scene.bounds.extend(v.position);
        }
        scene.triangles.push_back(t);
    }
}

/// A 2 m square floor facing up at y = 0.
Scene floorScene() {
    Scene scene;
    scene.sourcePath = "floor.gltf";
    addQuad(scene, {-1, 0, -1}, {-1, 0, 1}, {1, 0, 1}, {1, 0, -1});
    return scene;
}

Surfel surfelAt(glm::vec3 position, glm::vec3 normal) {
    Surfel s{};
    s.position = position;
    s.normal = normal;
    s.area = 1e-4f;
    s.radius = std::sqrt(s.area / std::numbers::pi_v<float>);
    s.albedo = glm::vec3(0.5f);
    return s;
}

Cache cacheAt(glm::vec3 position, uint32_t kind, glm::vec3 normal = glm::vec3(0.0f)) {
    Cache c{};
    c.position = position;
    c.kind = kind;
    c.normal = normal;
    return c;
}

TEST(SkyTransfer, AnOpenSurfelProjectsTheClampedCosine) {
    const Scene scene = floorScene();
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays) << rays.error().message;
    // One facing up on the floor, one tilted 10 m above it: the floor (0.04 sr from there)
    // hides a negligible part of its hemisphere.
    const glm::vec3 tilted = glm::normalize(glm::vec3(1.0f, 2.0f, -0.5f));
    const std::vector<Surfel> surfels = {surfelAt({0.2f, 0.0f, -0.3f}, {0, 1, 0}),
                                         surfelAt({0.0f, 10.0f, 0.0f}, tilted)};
    const std::vector<float> transfer = surfelSkyTransfer(**rays, surfels, 1024, 5);
    ASSERT_EQ(transfer.size(), 2u * kSkyCoefficients);
    for (size_t i = 0; i < surfels.size(); ++i) {
        float expected[kSkyCoefficients] = {};
        shAddClampedCosine(kSkyBands, surfels[i].normal, 1.0f, expected);
        for (int k = 0; k < kSkyCoefficients; ++k)
            EXPECT_NEAR(transfer[i * kSkyCoefficients + size_t(k)], expected[k], 0.01f)
                << "surfel " << i << " coefficient " << k;
        // A constant sky L then gives E = Σ s_k T_k = 2√π·L·T_0 = π·L.
        EXPECT_NEAR(2.0f * std::sqrt(std::numbers::pi_v<float>) * transfer[i * kSkyCoefficients],
                    std::numbers::pi_v<float>, 1e-3f);
    }
}

TEST(SkyTransfer, CachesSeeTheirHemisphereOrTheSphere) {
    const Scene scene = floorScene();
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays) << rays.error().message;
    const uint32_t bandsY = 3;
    const int bands = skyVisibilityBands(int(bandsY)), count = shCount(bands);
    // A light-map cache on the floor sees the upper hemisphere; a grid cache 20 m above it
    // the whole sphere but the floor's 0.01 sr.
    const std::vector<Cache> caches = {cacheAt({0.1f, 0.0f, 0.4f}, gpu::kCacheKindLightmap, {0, 1, 0}),
                                       cacheAt({0.0f, 20.0f, 0.0f}, gpu::kCacheKindGrid)};
    const std::vector<float> v = cacheSkyVisibility(**rays, caches, 0, 2, bandsY, 2048, 9);
    ASSERT_EQ(v.size(), 2u * size_t(count));
    std::vector<float> hemisphere(size_t(count), 0.0f);
    shAddCone(bands, {0, 1, 0}, 1.0f, 1.0f, hemisphere.data());
    for (int k = 0; k < count; ++k) {
        EXPECT_NEAR(v[size_t(k)], hemisphere[size_t(k)], 0.03f) << "light-map coefficient " << k;
        const float sphere = k == 0 ? 2.0f * std::sqrt(std::numbers::pi_v<float>) : 0.0f;
        EXPECT_NEAR(v[size_t(count + k)], sphere, 0.03f) << "grid coefficient " << k;
    }
    // Only a range of caches: the second alone.
    const std::vector<float> second = cacheSkyVisibility(**rays, caches, 1, 2, bandsY, 2048, 9);
    ASSERT_EQ(second.size(), size_t(count));
    for (int k = 0; k < count; ++k) EXPECT_EQ(second[size_t(k)], v[size_t(count + k)]);
}

TEST(SkyTransfer, NothingInAClosedBox) {
    Scene scene;
    scene.sourcePath = "box.gltf";
    const glm::vec3 p[8] = {{-1, 0, -1}, {1, 0, -1}, {1, 0, 1}, {-1, 0, 1},
                            {-1, 2, -1}, {1, 2, -1}, {1, 2, 1}, {-1, 2, 1}};
    // Faces inward.
    addQuad(scene, p[0], p[1], p[2], p[3]);
    addQuad(scene, p[4], p[7], p[6], p[5]);
    addQuad(scene, p[0], p[4], p[5], p[1]);
    addQuad(scene, p[1], p[5], p[6], p[2]);
    addQuad(scene, p[2], p[6], p[7], p[3]);
    addQuad(scene, p[3], p[7], p[4], p[0]);
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays) << rays.error().message;
    const std::vector<Surfel> surfels = {surfelAt({0.0f, 0.0f, 0.0f}, {0, 1, 0}),
                                         surfelAt({0.0f, 2.0f, 0.5f}, {0, -1, 0})};
    for (float t : surfelSkyTransfer(**rays, surfels, 256, 1)) EXPECT_EQ(t, 0.0f);
    const std::vector<Cache> caches = {cacheAt({0.0f, 1.0f, 0.0f}, gpu::kCacheKindGrid),
                                       cacheAt({-1.0f, 1.0f, 0.0f}, gpu::kCacheKindLightmap, {1, 0, 0})};
    for (float v : cacheSkyVisibility(**rays, caches, 0, 2, 3, 256, 1)) EXPECT_EQ(v, 0.0f);
}

TEST(SkyTransfer, AWallHalvesTheSkyOfTheFloorAtItsFoot) {
    // A floor and a tall wall along x = 0 facing +x: a surfel at its foot sees the half of its
    // hemisphere towards +x, its T_0 half the open value and its x-slope towards +x.
    Scene scene = floorScene();
    addQuad(scene, {0, 0, -50}, {0, 0, 50}, {0, 50, 50}, {0, 50, -50});
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays) << rays.error().message;
    const std::vector<Surfel> surfels = {surfelAt({0.01f, 0.0f, 0.0f}, {0, 1, 0})};
    const std::vector<float> t = surfelSkyTransfer(**rays, surfels, 4096, 2);
    float open[kSkyCoefficients] = {};
    shAddClampedCosine(kSkyBands, {0, 1, 0}, 1.0f, open);
    EXPECT_NEAR(t[0], 0.5f * open[0], 0.01f);
    // Band 1 along +x: ∫ over the +x quarter of max(0, y)·y_1(x) > 0 (whatever its sign
    // convention, the x coefficient is the one that grows).
    float basis[kSkyCoefficients];
    shEvaluate(kSkyBands, {1, 0, 0}, basis);
    float along = 0.0f;
    for (int k = 1; k < 4; ++k) along += t[size_t(k)] * basis[k];
    EXPECT_GT(along, 0.1f);
}

}  // namespace
}  // namespace pic
