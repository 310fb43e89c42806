// The surfel-lighting CPU twin (render/cpu/surfel_lighting.h) on tiny hand-built inputs with
// known answers: one surfel under a point, directional or occluded light, emission, the
// visibility bits of a spot, one bounce from a cache of constant radiance, and the stencil
// that leaves out caches behind a wall.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "core/bake_data.h"
#include "core/cache_values.h"
#include "core/light_set.h"
#include "rays/embree_scene.h"
#include "render/cpu/surfel_lighting.h"
#include "render/surfel_visibility.h"
#include "tests/support/lights.h"

namespace pic {
namespace {

constexpr double kPi = std::numbers::pi;

/// Adds the quad a, b, c, d (counter-clockwise seen from its front) as two triangles.
void addQuad(Scene& scene, glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d,
             uint32_t material) {
    const uint32_t first = static_cast<uint32_t>(scene.vertices.size());
    for (const glm::vec3& p : {a, b, c, d}) {
        Vertex v;
        v.position = p;
        scene.vertices.push_back(v);
        scene.bounds.extend(p);
    }
    scene.triangles.push_back(Triangle{{first, first + 1, first + 2}, material, 0});
    scene.triangles.push_back(Triangle{{first, first + 2, first + 3}, material, 0});
}

/// A 2 m floor at y = 0 facing +y (triangles 0, 1), material 0 "floor", material 1 "glow".
Scene floorScene() {
    Scene scene;
    scene.materials = {Material{.name = "floor"}, Material{.name = "glow"}};
    addQuad(scene, {-1, 0, -1}, {-1, 0, 1}, {1, 0, 1}, {1, 0, -1}, 0);
    return scene;
}

/// One surfel on triangle 0 of floorScene, as a complete one-node bake.
BakeData oneSurfelBake(const glm::vec3& position) {
    BakeData bake;
    Surfel s{};
    s.position = position;
    s.area = 0.01f;
    s.normal = {0, 1, 0};
    s.material = 0;
    s.albedo = {0.5f, 0.25f, 0.8f};
    s.radius = std::sqrt(s.area / float(kPi));
    s.emission = {0, 0, 0};
    s.triangle = 0;
    bake.surfels = {s};
    Node leaf{};
    leaf.center = s.position;
    leaf.area = s.area;
    leaf.normal = s.normal;
    leaf.left = leaf.right = leaf.parent = kNoNode;
    leaf.surfelCount = 1;
    bake.nodes = {leaf};
    bake.levelOffsets = {1};
    return bake;
}

using test::pointLight;

void expectVecNear(const glm::vec3& actual, const glm::dvec3& expected, double relative) {
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(actual[c], expected[c], relative * std::abs(expected[c]) + 1e-12)
            << "channel " << c;
}

TEST(SurfelLighting, PointLightGivesAlbedoAreaIntensityCosineOverDistanceSquared) {
    Scene scene = floorScene();
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays) << rays.error().message;
    const glm::vec3 position(0.2f, 0.0f, 0.1f);
    BakeData bake = oneSurfelBake(position);
    LightSet lights;
    const glm::vec3 lamp(0.5f, 2.0f, -0.3f);
    lights.lights = {pointLight(lamp, 3.0f, {1.0f, 0.5f, 0.25f})};

    std::vector<glm::vec3> flux(1);
    lightSurfels(scene, **rays, bake, lights, nullptr, flux);
    const glm::dvec3 toLamp = glm::dvec3(lamp) - glm::dvec3(position);
    const double d = glm::length(toLamp);
    const double cosTheta = toLamp.y / d;
    const glm::dvec3 expected = glm::dvec3(0.5, 0.25, 0.8) * 0.01 * 3.0 *
                                glm::dvec3(1.0, 0.5, 0.25) * cosTheta / (d * d);
    expectVecNear(flux[0], expected, 1e-5);
}

TEST(SurfelLighting, DirectionalLightGivesAlbedoAreaIrradianceCosine) {
    Scene scene = floorScene();
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays);
    BakeData bake = oneSurfelBake({0.0f, 0.0f, 0.0f});
    Light sun;
    sun.id = "sun";
    sun.type = LightType::Directional;
    sun.direction = glm::normalize(glm::vec3(0.0f, -1.0f, -1.0f));
    sun.intensity = 2.0f;
    LightSet lights;
    lights.lights = {sun};
    std::vector<glm::vec3> flux(1);
    directSurfelFlux(scene, **rays, bake, lights, flux);
    expectVecNear(flux[0], glm::dvec3(0.5, 0.25, 0.8) * 0.01 * 2.0 * std::sqrt(0.5), 1e-5);
}

TEST(SurfelLighting, OccludedLightGivesNothing) {
    Scene scene = floorScene();
    // A blocker at y = 1 between the surfel and the lamp (facing down: both sides block).
    addQuad(scene, {-0.5f, 1, -0.5f}, {0.5f, 1, -0.5f}, {0.5f, 1, 0.5f}, {-0.5f, 1, 0.5f}, 0);
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays);
    BakeData bake = oneSurfelBake({0.0f, 0.0f, 0.0f});
    LightSet lights;
    lights.lights = {pointLight({0.1f, 2.0f, 0.0f}, 5.0f, glm::vec3(1.0f))};
    std::vector<glm::vec3> flux(1, glm::vec3(-1.0f));
    directSurfelFlux(scene, **rays, bake, lights, flux);
    EXPECT_EQ(flux[0], glm::vec3(0.0f));

    // Below the blocker's edge the same lamp shines again: the blocker, not the pass, is dark.
    lights.lights = {pointLight({0.9f, 2.0f, 0.0f}, 5.0f, glm::vec3(1.0f))};
    bake.surfels[0].position = {0.9f, 0.0f, 0.0f};
    directSurfelFlux(scene, **rays, bake, lights, flux);
    EXPECT_GT(flux[0].x, 0.0f);
}

TEST(SurfelLighting, VisibilityBitsAreWhereTheDirectFluxIsLit) {
    // 70 surfels along x (three words, the last one partly used), the middle ones under a
    // blocker; a spot whose cone leaves out the far end. Bit i is set exactly where the
    // direct flux of that light is positive, whatever its colour and intensity.
    Scene scene = floorScene();
    addQuad(scene, {-0.2f, 1, -0.5f}, {0.2f, 1, -0.5f}, {0.2f, 1, 0.5f}, {-0.2f, 1, 0.5f}, 0);
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays);
    BakeData bake = oneSurfelBake({0.0f, 0.0f, 0.0f});
    const Surfel first = bake.surfels[0];
    bake.surfels.clear();
    for (int i = 0; i < 70; ++i) {
        Surfel s = first;
        s.position = {-0.95f + 0.0275f * float(i), 0.0f, 0.0f};
        bake.surfels.push_back(s);
    }
    Light spot = pointLight({0.0f, 2.0f, 0.0f}, 4.0f, {1.0f, 0.0f, 0.5f});
    spot.type = LightType::Spot;
    spot.direction = glm::normalize(glm::vec3(-0.3f, -1.0f, 0.0f));
    spot.outerConeAngle = 0.45f;
    spot.innerConeAngle = 0.3f;
    LightSet lights;
    lights.lights = {spot};
    std::vector<glm::vec3> flux(bake.surfels.size());
    directSurfelFlux(scene, **rays, bake, lights, flux);
    std::vector<uint32_t> bits(visibilityWords(bake.surfels.size()), ~0u);
    ASSERT_EQ(bits.size(), 3u);
    surfelVisibility(**rays, bake, spot, bits);
    int lit = 0, blocked = 0;
    for (size_t i = 0; i < bake.surfels.size(); ++i) {
        const bool bit = (bits[i / 32] >> (i % 32)) & 1u;
        EXPECT_EQ(bit, flux[i].r > 0.0f) << "surfel " << i;
        lit += bit;
        blocked += std::abs(bake.surfels[i].position.x) < 0.15f && !bit;
    }
    EXPECT_GT(lit, 10);
    EXPECT_GT(blocked, 5);
    EXPECT_LT(lit + blocked, 70);  // the cone leaves some out
    EXPECT_EQ(bits[2] >> 6, 0u);   // bits past the last surfel stay clear

    // Colour and intensity do not change what the light reaches.
    Light dim = spot;
    dim.intensity = 0.0f;
    dim.color = {0.0f, 1.0f, 0.0f};
    std::vector<uint32_t> dimBits(bits.size());
    surfelVisibility(**rays, bake, dim, dimBits);
    EXPECT_EQ(dimBits, bits);
}

TEST(SurfelLighting, EmissiveSurfelGivesPiRadianceAreaScale) {
    Scene scene = floorScene();
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays);
    BakeData bake = oneSurfelBake({0.0f, 0.0f, 0.0f});
    bake.surfels[0].material = 1;
    bake.surfels[0].emission = {2.0f, 3.0f, 4.0f};
    LightSet lights;
    lights.emissiveScale["glow"] = 0.5f;
    std::vector<glm::vec3> flux(1);
    directSurfelFlux(scene, **rays, bake, lights, flux);
    expectVecNear(flux[0], kPi * glm::dvec3(2.0, 3.0, 4.0) * 0.01 * 0.5, 1e-6);

    // Scales of other materials do not apply; an unlisted material emits at scale 1.
    lights.emissiveScale = {{"floor", 7.0f}};
    directSurfelFlux(scene, **rays, bake, lights, flux);
    expectVecNear(flux[0], kPi * glm::dvec3(2.0, 3.0, 4.0) * 0.01, 1e-6);
}

TEST(SurfelLighting, BounceAddsAlbedoAreaTimesCacheIrradiance) {
    // Every grid vertex holds one cache of constant grey radiance L: irradiance is π·L, so
    // the bounce adds ρ·A·π·L to the direct flux.
    Scene scene = floorScene();
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays);
    BakeData bake = oneSurfelBake({0.3f, 0.0f, -0.2f});
    bake.params.bandsY = 3;
    bake.params.bandsC = 2;
    bake.caches.resize(1);
    bake.grid.origin = {-1.0f, -1.0f, -1.0f};
    bake.grid.cellSize = 2.0f;
    bake.grid.dims = {2, 2, 2};
    bake.grid.cacheIndex.assign(8, 0u);
    CacheValues values = CacheValues::zeros(1, 3, 2);
    const double radiance = 0.75;
    values.y[0] = float(radiance * 2.0 * std::sqrt(kPi));  // L / y_0^0

    LightSet lights;
    lights.lights = {pointLight({0.0f, 1.0f, 0.0f}, 1.0f, glm::vec3(1.0f))};
    std::vector<glm::vec3> direct(1), bounced(1), combined(1);
    directSurfelFlux(scene, **rays, bake, lights, direct);
    bounceSurfelFlux(bake, surfelStencils(scene, **rays, bake), direct, values, bounced);
    lightSurfels(scene, **rays, bake, lights, &values, combined);
    const glm::dvec3 expected =
        glm::dvec3(direct[0]) + glm::dvec3(0.5, 0.25, 0.8) * 0.01 * kPi * radiance;
    expectVecNear(bounced[0], expected, 1e-5);
    EXPECT_EQ(bounced[0], combined[0]);
}

TEST(SurfelLighting, BounceReadsCachesOnItsSurfaceThroughTheirIrradianceAlongTheNormal) {
    // Two caches of constant grey radiance L (SH irradiance π·L) whose irradiance along their
    // normal says E_0 and E_1 instead: a stencil entry marked alongNormal adds its weight times
    // E_k, an unmarked one its weight times π·L; without irradiance every entry reads the SH.
    Scene scene = floorScene();
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays);
    BakeData bake = oneSurfelBake({0.3f, 0.0f, -0.2f});
    bake.params.bandsY = 3;
    bake.params.bandsC = 2;
    bake.caches.resize(2);
    CacheValues values = CacheValues::zeros(2, 3, 2);
    const double radiance = 0.75;
    for (int c = 0; c < 2; ++c) values.y[size_t(c) * 9] = float(radiance * 2.0 * std::sqrt(kPi));
    values.irradiance = {glm::vec3(1.0f, 2.0f, 3.0f), glm::vec3(0.5f, 0.0f, 4.0f)};
    CacheStencil stencil;
    stencil.count = 2;
    stencil.cache[0] = 0, stencil.cache[1] = 1;
    stencil.weight[0] = 0.25f, stencil.weight[1] = 0.75f;
    const std::vector<glm::vec3> direct = {glm::vec3(0.1f)};
    const glm::dvec3 albedoArea = glm::dvec3(0.5, 0.25, 0.8) * 0.01;  // oneSurfelBake's ρ·A
    const glm::dvec3 sh(kPi * radiance);
    const auto bounce = [&](uint8_t alongNormal, const CacheValues& from) {
        stencil.alongNormal = alongNormal;
        std::vector<glm::vec3> out(1);
        bounceSurfelFlux(bake, std::span<const CacheStencil>(&stencil, 1), direct, from, out);
        return out[0];
    };
    expectVecNear(bounce(0, values), glm::dvec3(direct[0]) + albedoArea * sh, 1e-5);
    expectVecNear(bounce(3, values),
                  glm::dvec3(direct[0]) + albedoArea * (0.25 * glm::dvec3(values.irradiance[0]) +
                                                        0.75 * glm::dvec3(values.irradiance[1])),
                  1e-5);
    expectVecNear(
        bounce(2, values),
        glm::dvec3(direct[0]) + albedoArea * (0.25 * sh + 0.75 * glm::dvec3(values.irradiance[1])),
        1e-5);
    CacheValues shOnly = values;
    shOnly.irradiance.clear();
    expectVecNear(bounce(3, shOnly), glm::dvec3(direct[0]) + albedoArea * sh, 1e-5);
}

TEST(SurfelLighting, ASurfelsStencilLeavesOutTheCachesBehindAWall) {
    // A one-cell grid over the floor: vertices at x = −1 hold cache 0, at x = +1 cache 1, so a
    // surfel at x = 0.2 reads them 0.4 : 0.6. A wall at x = 0.5 standing on the floor hides
    // cache 1: the stencil keeps cache 0 alone. Walls on both sides hide both: the surfel
    // keeps its stencil rather than go dark.
    const auto bakeOverGrid = [] {
        BakeData bake = oneSurfelBake({0.2f, 0.0f, 0.0f});
        bake.caches.resize(2);
        bake.caches[0].position = {-1.0f, 0.5f, 0.0f};
        bake.caches[1].position = {1.0f, 0.5f, 0.0f};
        bake.grid.origin = {-1.0f, -0.5f, -1.0f};
        bake.grid.cellSize = 2.0f;
        bake.grid.dims = {2, 2, 2};
        for (uint32_t i = 0; i < 8; ++i) bake.grid.cacheIndex.push_back(i & 1u);
        for (Cache& c : bake.caches) c.kind = gpu::kCacheKindGrid;
        return bake;
    };
    const auto wallAt = [](Scene& scene, float x) {
        addQuad(scene, {x, 0, -1}, {x, 2, -1}, {x, 2, 1}, {x, 0, 1}, 0);
    };
    const auto weightOf = [](const CacheStencil& s, uint32_t cache) {
        float w = 0.0f;
        for (int k = 0; k < s.count; ++k)
            if (s.cache[k] == cache) w += s.weight[k];
        return w;
    };
    const BakeData bake = bakeOverGrid();

    Scene open = floorScene();
    auto openRays = EmbreeScene::create(open);
    ASSERT_TRUE(openRays);
    const CacheStencil both = surfelStencils(open, **openRays, bake)[0];
    EXPECT_NEAR(weightOf(both, 0), 0.4f, 1e-5f);
    EXPECT_NEAR(weightOf(both, 1), 0.6f, 1e-5f);

    Scene walled = floorScene();
    wallAt(walled, 0.5f);
    auto walledRays = EmbreeScene::create(walled);
    ASSERT_TRUE(walledRays);
    const CacheStencil near = surfelStencils(walled, **walledRays, bake)[0];
    EXPECT_NEAR(weightOf(near, 0), 1.0f, 1e-6f);
    EXPECT_EQ(weightOf(near, 1), 0.0f);

    Scene boxed = floorScene();
    wallAt(boxed, 0.5f);
    wallAt(boxed, -0.5f);
    auto boxedRays = EmbreeScene::create(boxed);
    ASSERT_TRUE(boxedRays);
    const CacheStencil hidden = surfelStencils(boxed, **boxedRays, bake)[0];
    EXPECT_NEAR(weightOf(hidden, 0), 0.4f, 1e-5f);
    EXPECT_NEAR(weightOf(hidden, 1), 0.6f, 1e-5f);
}

}  // namespace
}  // namespace pic
