// The shadow-map pass on lavapipe (or the machine's GPU): merged coplanar casters and solids
// drawn from one side store the same depths as the scene's own triangles drawn from both
// sides; levels of detail stay within their error; footprint sides give the orthographic
// texel at the median receiver distance; only lights that changed are rendered again;
// vertices land on the 1/16-texel grid.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/gltf_loader.h"
#include "core/light_set.h"
#include "render/passes/shadow_map_pass.h"
#include "tests/render/gpu_fixture.h"

namespace pic {
namespace {

/// The scene's own lights plus a sun and a narrow spot, so that every layer kind is drawn.
LightSet testLights(const Scene& scene) {
    LightSet lights = defaultLightSet(scene);
    Light sun;
    sun.id = "test_sun";
    sun.type = LightType::Directional;
    sun.direction = glm::normalize(glm::vec3(0.3f, -0.9f, 0.2f));
    lights.lights.push_back(sun);
    Light spot;
    spot.id = "test_spot";
    spot.type = LightType::Spot;
    spot.position = scene.bounds.center() + glm::vec3(0.0f, 0.3f, 0.0f) * scene.bounds.extent();
    spot.direction = glm::normalize(glm::vec3(0.2f, -1.0f, 0.1f));
    spot.outerConeAngle = 0.6f;
    lights.lights.push_back(spot);
    return lights;
}

/// Renders every layer of `lights` and reads them back, one vector per layer.
std::vector<std::vector<float>> renderLayers(gpu::Context& context, gpu::ShadowMapPass& pass,
                                             const LightSet& lights) {
    bool reallocated = false;
    auto prepared = pass.prepare(lights, reallocated);
    EXPECT_TRUE(prepared) << prepared.error().message;
    auto submitted = context.submit([&](VkCommandBuffer cmd) { pass.record(cmd, {}); });
    EXPECT_TRUE(submitted) << submitted.error().message;
    std::vector<std::vector<float>> layers;
    for (uint32_t l = 0; l < pass.depth().layers(); ++l) {
        auto depths = context.downloadDepthLayer(pass.depth(), l);
        EXPECT_TRUE(depths) << depths.error().message;
        layers.push_back(depths ? std::move(*depths) : std::vector<float>{});
    }
    return layers;
}

/// Texels of `actual` whose depth differs from `expected` by more than `tolerance`, over all
/// layers; the fraction of all texels is returned through `fraction`.
size_t differingTexels(const std::vector<std::vector<float>>& actual,
                       const std::vector<std::vector<float>>& expected, float tolerance,
                       double& fraction) {
    EXPECT_EQ(actual.size(), expected.size());
    size_t differing = 0, total = 0;
    for (size_t l = 0; l < std::min(actual.size(), expected.size()); ++l) {
        EXPECT_EQ(actual[l].size(), expected[l].size());
        for (size_t i = 0; i < std::min(actual[l].size(), expected[l].size()); ++i)
            if (std::abs(actual[l][i] - expected[l][i]) > tolerance) ++differing;
        total += expected[l].size();
    }
    fraction = total ? double(differing) / double(total) : 0.0;
    return differing;
}

class ShadowCasters : public testing::TestWithParam<std::string> {};

TEST_P(ShadowCasters, MergedAndOneSidedStoreTheSameDepths) {
    auto scene = loadScene(test::testScenePath(GetParam()));
    ASSERT_TRUE(scene) << scene.error().message;
    auto context = gpu::Context::create();
    if (!context) GTEST_SKIP() << "no Vulkan device: " << context.error().message;
    constexpr uint32_t kSize = 256;
    const LightSet lights = testLights(*scene);
    auto render = [&](gpu::ShadowMapOptions options, uint64_t& oneSided) {
        auto pass = gpu::createPass<gpu::ShadowMapPass>(
            **context, {.scene = &*scene, .shadowMapSize = kSize, .shadowMap = options});
        EXPECT_TRUE(pass) << pass.error().message;
        if (!pass) return std::vector<std::vector<float>>{};
        auto layers = renderLayers(**context, **pass, lights);
        oneSided = (*pass)->oneSidedTriangles();
        EXPECT_LE((*pass)->casterTriangles(), scene->triangles.size());
        return layers;
    };
    uint64_t oneSided = 0;
    const auto reference =
        render({.mergeCoplanar = false, .oneSidedSolids = false, .levelsOfDetail = false}, oneSided);
    EXPECT_EQ(oneSided, 0u);

    // Skipping the faces of solids that look away from the light changes no depth beyond
    // rounding (inverted solids are drawn with their corners in another order). Every scene
    // here has solids seen from outside by some light, so the one-sided path runs.
    const auto solidsOneSided =
        render({.mergeCoplanar = false, .oneSidedSolids = true, .levelsOfDetail = false}, oneSided);
    EXPECT_GT(oneSided, 0u);
    double fraction = 0.0;
    differingTexels(solidsOneSided, reference, 1e-6f, fraction);
    EXPECT_LE(fraction, 1e-3) << GetParam() << ": one-sided solids";

    // Merged coplanar triangles cover the same surfaces. Their longer edges round
    // differently, so texel centres that lie on an edge (within rounding) may change sides:
    // a few texels on silhouettes, nothing else. Each triangulation's corners snap to the
    // 1/16-texel grid (lib/subpixel.glsl) in their own way, which tilts a triangle's depth
    // by its depth change over up to 1/32 texel: on the atrium's surfaces that graze the
    // light, 3e-4 of the depth range at 0.6 % of the texels, under 1e-3 at 0.01 %.
    const auto merged =
        render({.mergeCoplanar = true, .oneSidedSolids = true, .levelsOfDetail = false}, oneSided);
    differingTexels(merged, reference, 1e-3f, fraction);
    EXPECT_LE(fraction, 5e-3) << GetParam() << ": merged casters, differences > 1e-3";
    differingTexels(merged, reference, 1e-2f, fraction);
    EXPECT_LE(fraction, 5e-4) << GetParam() << ": merged casters, differences > 1e-2";
    EXPECT_EQ((*context)->validationMessages(), 0u);
}

/// Metres along the layer's view axis of a stored depth (the pass's near and far planes).
float metres(const gpu::GpuLight& light, float stored) {
    const float n = light.depthNear, f = light.depthFar;
    return light.shadowKind == gpu::kShadowOrthographic ? n + stored * (f - n)
                                                   : n * f / (f - stored * (f - n));
}

TEST_P(ShadowCasters, LevelsOfDetailMoveSurfacesByAtMostHalfATexel) {
    auto scene = loadScene(test::testScenePath(GetParam()));
    ASSERT_TRUE(scene) << scene.error().message;
    auto context = gpu::Context::create();
    if (!context) GTEST_SKIP() << "no Vulkan device: " << context.error().message;
    constexpr uint32_t kSize = 256;
    const LightSet lights = testLights(*scene);
    auto exact = gpu::createPass<gpu::ShadowMapPass>(
        **context,
        {.scene = &*scene, .shadowMapSize = kSize, .shadowMap = {.levelsOfDetail = false}});
    ASSERT_TRUE(exact) << exact.error().message;
    auto coarse =
        gpu::createPass<gpu::ShadowMapPass>(**context, {.scene = &*scene, .shadowMapSize = kSize});
    ASSERT_TRUE(coarse) << coarse.error().message;
    const auto expected = renderLayers(**context, **exact, lights);
    const auto actual = renderLayers(**context, **coarse, lights);
    ASSERT_EQ(actual.size(), expected.size());
    const auto levels = (*coarse)->levels();
    for (size_t k = 1; k < levels.size(); ++k) {
        EXPECT_GT(levels[k].error, levels[k - 1].error);
        EXPECT_LE(levels[k].triangles, kCasterLevelReduction * levels[k - 1].triangles);
    }
    // Only the atrium has curved surfaces (columns) to simplify.
    if (GetParam() == "atrium") {
        EXPECT_GE(levels.size(), 2u);
    }
    for (const gpu::GpuLight& light : (*coarse)->lightRecords()) {
        const uint32_t layers = light.shadowKind == gpu::kShadowCube ? 6 : 1;
        for (uint32_t l = light.firstLayer; l < light.firstLayer + layers; ++l) {
            const uint32_t level = (*coarse)->layerLevels()[l];
            const float error = levels[level].error;
            // Where a layer's texels are all one size, it takes the coarsest level.
            if (light.shadowKind == gpu::kShadowOrthographic) {
                EXPECT_EQ(level, levels.size() - 1);
            }
            EXPECT_LE(error, kCasterErrorPerTexel * (*coarse)->layerRecords()[l].texelSlope *
                                 (light.shadowKind == gpu::kShadowOrthographic ? 1.0f : light.depthFar));
            // Depths differ by more than the level's error only on silhouettes and grazing
            // surfaces, where moving a surface sideways moves the depth along the ray more.
            size_t beyond = 0, beyondFourfold = 0, drawn = 0;
            for (size_t i = 0; i < expected[l].size(); ++i) {
                if (expected[l][i] >= 1.0f && actual[l][i] >= 1.0f) continue;
                ++drawn;
                const float depth = metres(light, expected[l][i]);
                const float dz = std::abs(metres(light, actual[l][i]) - depth);
                if (dz > error + 1e-5f * depth) ++beyond;
                if (dz > 4.0f * error + 1e-5f * depth) ++beyondFourfold;
            }
            const double share = drawn ? 1.0 / double(drawn) : 0.0;
            EXPECT_LE(double(beyond) * share, 0.02) << GetParam() << " layer " << l;
            EXPECT_LE(double(beyondFourfold) * share, 0.005) << GetParam() << " layer " << l;
        }
    }
    EXPECT_EQ((*context)->validationMessages(), 0u);
}

// cornell: closed boxes in an open room; closed_box: a closed room with the lights inside
// it (its walls must keep both sides); two_floors: slabs; atrium: every kind of part.
/// A 20 m × 20 m floor at y = 0 of 2 × 200 × 200 triangles.
Scene floorScene() {
    Scene scene;
    constexpr int kCells = 200;
    constexpr float kHalf = 10.0f;
    for (int j = 0; j <= kCells; ++j)
        for (int i = 0; i <= kCells; ++i) {
            Vertex v;
            v.position = glm::vec3(-kHalf + 2.0f * kHalf * float(i) / kCells, 0.0f,
                                   -kHalf + 2.0f * kHalf * float(j) / kCells);
            scene.vertices.push_back(v);
            scene.bounds.extend(v.position);
        }
    for (int j = 0; j < kCells; ++j)
        for (int i = 0; i < kCells; ++i) {
            const uint32_t a = uint32_t(j * (kCells + 1) + i), b = a + 1, c = a + kCells + 1, d = c + 1;
            scene.triangles.push_back(Triangle{{a, c, b}});
            scene.triangles.push_back(Triangle{{b, c, d}});
        }
    return scene;
}

/// The cube face that holds the direction `v`: its major axis (+x, −x, +y, −y, +z, −z).
uint32_t majorAxisFace(const glm::vec3& v) {
    const glm::vec3 a = glm::abs(v);
    if (a.x >= a.y && a.x >= a.z) return v.x >= 0.0f ? 0 : 1;
    if (a.y >= a.z) return v.y >= 0.0f ? 2 : 3;
    return v.z >= 0.0f ? 4 : 5;
}

/// The floor points `light` reaches (within its range and cone) on its layer `layer` (a cube
/// face, or a spot's one layer), over a fine grid of the floor: their median distance and
/// their share of all the floor points it reaches. What footprint sides take from 4096 area
/// samples.
struct FloorOnLayer {
    float medianDistance = 0.0f;
    double share = 0.0;
};
FloorOnLayer floorOnLayer(const Light& light, bool cube, uint32_t layer) {
    std::vector<float> distances;
    size_t reached = 0;
    constexpr int kSteps = 1000;
    for (int j = 0; j < kSteps; ++j)
        for (int i = 0; i < kSteps; ++i) {
            const glm::vec3 p(-10.0f + 20.0f * (float(i) + 0.5f) / kSteps, 0.0f,
                              -10.0f + 20.0f * (float(j) + 0.5f) / kSteps);
            const glm::vec3 offset = p - light.position;
            const float d = glm::length(offset);
            if (std::isfinite(light.range) && d >= light.range) continue;
            if (light.type == LightType::Spot &&
                glm::dot(offset, light.direction) < std::cos(light.outerConeAngle) * d)
                continue;
            ++reached;
            if (!cube || majorAxisFace(offset) == layer) distances.push_back(d);
        }
    if (distances.empty()) return {};
    std::nth_element(distances.begin(), distances.begin() + distances.size() / 2, distances.end());
    return {distances[distances.size() / 2], double(distances.size()) / double(reached)};
}

TEST(ShadowSides, FootprintSideRoundsUpWithinTheLimits) {
    // 2·5 m / 1 cm = 1000 texels, rounded up to a multiple of 16.
    EXPECT_EQ(gpu::footprintSide(2.0f, 5.0f, 0.01f, 2048), 1008u);
    EXPECT_EQ(gpu::footprintSide(2.0f, 5.0f, 0.01f, 1024), 1008u);
    EXPECT_EQ(gpu::footprintSide(2.0f, 5.0f, 0.01f, 512), 512u);     // at most the image's side
    EXPECT_EQ(gpu::footprintSide(2.0f, 0.01f, 0.01f, 512), gpu::kMinShadowSide);
    EXPECT_EQ(gpu::footprintSide(2.0f, 0.0f, 0.01f, 512), gpu::kMinShadowSide);
    EXPECT_EQ(gpu::footprintSide(2.0f, std::nanf(""), 0.01f, 512), 512u);
    EXPECT_EQ(gpu::footprintSide(2.0f, 1e30f, 0.01f, 512), 512u);
}

TEST(ShadowSides, EqualFootprintGivesTheOrthographicTexelAtTheMedianDistance) {
    const Scene scene = floorScene();
    auto context = gpu::Context::create();
    if (!context) GTEST_SKIP() << "no Vulkan device: " << context.error().message;
    constexpr uint32_t kSize = 1024;
    LightSet lights;
    Light sun;
    sun.id = "sun";
    sun.type = LightType::Directional;
    sun.direction = glm::normalize(glm::vec3(0.2f, -1.0f, 0.1f));
    Light bulb;  // low over one corner: most of the floor is far away
    bulb.id = "bulb";
    bulb.type = LightType::Point;
    bulb.position = glm::vec3(-8.0f, 1.0f, -8.0f);
    Light nearBulb = bulb;  // its range keeps it to the corner
    nearBulb.id = "near bulb";
    nearBulb.range = 4.0f;
    Light spot;  // a narrow cone straight down from high up
    spot.id = "spot";
    spot.type = LightType::Spot;
    spot.position = glm::vec3(2.0f, 12.0f, 0.0f);
    spot.direction = glm::vec3(0.0f, -1.0f, 0.0f);
    spot.outerConeAngle = 0.3f;
    lights.lights = {sun, bulb, nearBulb, spot};

    auto uniform =
        gpu::createPass<gpu::ShadowMapPass>(**context, {.scene = &scene, .shadowMapSize = kSize});
    ASSERT_TRUE(uniform) << uniform.error().message;
    auto footprint = gpu::createPass<gpu::ShadowMapPass>(
        **context,
        {.scene = &scene, .shadowMapSize = kSize, .shadowMap = {.equalFootprint = true}});
    ASSERT_TRUE(footprint) << footprint.error().message;
    const auto uniformLayers = renderLayers(**context, **uniform, lights);
    const auto footprintLayers = renderLayers(**context, **footprint, lights);
    ASSERT_EQ(footprintLayers.size(), uniformLayers.size());

    const auto records = (*footprint)->lightRecords();
    const auto layerRecords = (*footprint)->layerRecords();
    const auto uniformLayerRecords = (*uniform)->layerRecords();
    ASSERT_EQ(records.size(), 4u);
    ASSERT_EQ(layerRecords.size(), 14u);
    const float orthographicTexel = layerRecords[0].texelSlope;
    std::vector<uint64_t> texels(records.size(), 0);
    for (size_t k = 0; k < records.size(); ++k) {
        const gpu::GpuLight& g = records[k];
        const bool cube = g.shadowKind == gpu::kShadowCube;
        const uint32_t layers = cube ? 6 : 1;
        for (uint32_t layer = 0; layer < layers; ++layer) {
            const gpu::GpuShadowLayer& r = layerRecords[g.firstLayer + layer];
            SCOPED_TRACE(lights.lights[k].id + " layer " + std::to_string(layer));
            texels[k] += uint64_t(r.side) * r.side;
            EXPECT_EQ(uniformLayerRecords[g.firstLayer + layer].side, kSize);
            EXPECT_EQ(r.side % gpu::kMinShadowSide, 0u);
            if (g.shadowKind == gpu::kShadowOrthographic) {
                EXPECT_EQ(r.side, kSize);
                continue;
            }
            const float slopeAtOneTexel = r.texelSlope * float(r.side);
            EXPECT_NEAR(slopeAtOneTexel,
                        cube ? 2.0f : uniformLayerRecords[g.firstLayer].texelSlope * kSize, 1e-4f);
            EXPECT_LT(r.side, kSize);
            const FloorOnLayer floor = floorOnLayer(lights.lights[k], cube, layer);
            if (floor.share == 0.0) {  // nothing to shadow there
                EXPECT_EQ(r.side, gpu::kMinShadowSide);
                continue;
            }
            // The texel at the layer's median distance is the orthographic one, but for
            // rounding the side up to kMinShadowSide and the samples' scatter about the
            // median: 1 % where the layer holds a quarter of the light's floor or more
            // (≥ ~1000 of the 4096 samples), 10 % where it holds a few dozen.
            if (floor.share < 0.01) continue;
            const float scatter = floor.share >= 0.25 ? 0.01f : 0.1f;
            const float texelAtMedian = r.texelSlope * floor.medianDistance;
            EXPECT_LE(texelAtMedian, (1.0f + scatter) * orthographicTexel);
            EXPECT_GE(texelAtMedian, (1.0f - scatter) * orthographicTexel *
                                         float(r.side - gpu::kMinShadowSide) / float(r.side));
        }
    }
    // The far bulb sees more of the floor from farther away than the near one.
    EXPECT_GT(texels[1], texels[2]);

    // A footprint layer holds the same depths as the uniform one, seen through fewer texels:
    // each of its texels matches the uniform texel under its centre (a plane's depth is linear
    // in the layer's coordinates, so only edges and the far plane differ).
    for (size_t k = 1; k < records.size(); ++k) {
        const uint32_t layers = records[k].shadowKind == gpu::kShadowCube ? 6 : 1;
        for (uint32_t l = records[k].firstLayer; l < records[k].firstLayer + layers; ++l) {
            const uint32_t side = layerRecords[l].side;
            size_t compared = 0, differing = 0;
            for (uint32_t y = 0; y < side; ++y)
                for (uint32_t x = 0; x < side; ++x) {
                    const uint32_t ux = uint32_t((float(x) + 0.5f) * kSize / side);
                    const uint32_t uy = uint32_t((float(y) + 0.5f) * kSize / side);
                    const float a = footprintLayers[l][size_t(y) * kSize + x];
                    const float b = uniformLayers[l][size_t(uy) * kSize + ux];
                    ++compared;
                    differing += std::abs(a - b) > 1e-3f;
                }
            EXPECT_LE(double(differing), 0.02 * double(compared)) << "layer " << l;
        }
    }
}

TEST(GpuShadowMaps, OnlyLightsThatChangedAreRerendered) {
    const test::BakedScene& b = test::smallBake("cornell", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    auto gpu =
        test::gpuFor(b, BounceParams{1}, {.directVisibility = gpu::DirectVisibility::ShadowMaps});
    ASSERT_TRUE(gpu);
    LightSet lights = test::twoLights(b.scene);
    ASSERT_EQ(lights.lights.size(), 2u);
    UpdateStats stats;
    ASSERT_TRUE(gpu->setLights(lights, &stats));
    EXPECT_EQ(stats.shadowMapsRendered, 2);
    ASSERT_TRUE(gpu->setLights(lights, &stats));
    EXPECT_EQ(stats.shadowMapsRendered, 0);
    // Colour and intensity do not change a depth map.
    lights.lights[1].intensity *= 2.0f;
    lights.lights[1].color = {1.0f, 0.5f, 0.25f};
    ASSERT_TRUE(gpu->setLights(lights, &stats));
    EXPECT_EQ(stats.shadowMapsRendered, 0);
    // Moving one light re-renders that light only.
    lights.lights[1].position.x += 0.05f;
    ASSERT_TRUE(gpu->setLights(lights, &stats));
    EXPECT_EQ(stats.shadowMapsRendered, 1);
}

/// A floor (y = −1) and a marker triangle at y = 1, which fix the scene's bounds, and a
/// caster quad from x = xa to xb (|z| ≤ 0.3) whose height rises with x (y = x/2).
Scene tiltedCasterScene(float xa, float xb) {
    Scene scene;
    scene.materials = {Material{.name = "grey"}};
    const auto add = [&](std::initializer_list<glm::vec3> corners) {
        const uint32_t first = uint32_t(scene.vertices.size());
        for (const glm::vec3& p : corners) {
            Vertex v;
            v.position = p;
            scene.vertices.push_back(v);
            scene.bounds.extend(p);
        }
        for (uint32_t k = 1; k + 1 < corners.size(); ++k)
            scene.triangles.push_back(Triangle{{first, first + k, first + k + 1}, 0, 0});
    };
    add({{-1, -1, -1}, {1, -1, -1}, {1, -1, 1}, {-1, -1, 1}});
    add({{0.9f, 1, 0.9f}, {1, 1, 0.9f}, {1, 1, 1}});
    add({{xa, 0.5f * xa, -0.3f},
         {xb, 0.5f * xb, -0.3f},
         {xb, 0.5f * xb, 0.3f},
         {xa, 0.5f * xa, 0.3f}});
    return scene;
}

// shadow_map.vert puts vertices on the 1/16-texel grid (lib/subpixel.glsl), which every
// rasteriser represents; lavapipe's own grid is 1/256. A caster whose corners all lie 0.02
// texel past texel centres (in x) is drawn 0.02 texel nearer them, minus the 1/1024 nudge:
// the depth stored at a texel centre is the tilted caster's depth that far to the side.
TEST(GpuShadowMaps, VerticesSnapToTheSixteenthTexelGrid) {
    auto context = gpu::Context::create();
    if (!context) GTEST_SKIP() << "no Vulkan device: " << context.error().message;
    constexpr uint32_t kSize = 64;
    LightSet sun;
    sun.lights.push_back(
        Light{.id = "sun", .type = LightType::Directional, .direction = {0, -1, 0}});
    const auto create = [&](const Scene& scene) {
        return gpu::createPass<gpu::ShadowMapPass>(
            **context,
            {.scene = &scene,
             .shadowMapSize = kSize,
             .shadowMap = {
                 .mergeCoplanar = false, .oneSidedSolids = false, .levelsOfDetail = false}});
    };
    // The layer's matrix, from a first caster: the bounds, and so the layer, do not depend on
    // where the caster lies between them.
    const Scene first = tiltedCasterScene(-0.3f, 0.3f);
    auto probe = create(first);
    ASSERT_TRUE(probe) << probe.error().message;
    bool reallocated = false;
    ASSERT_TRUE((*probe)->prepare(sun, reallocated));
    const glm::mat4 clip = (*probe)->layerRecords()[0].clipFromWorld;
    const auto casterAt = [](float x) { return glm::vec4(x, 0.5f * x, 0.0f, 1.0f); };
    const auto texelX = [&](float x) {
        return ((clip * casterAt(x)).x * 0.5f + 0.5f) * float(kSize);
    };
    const auto worldX = [&](float u) { return (u - texelX(0.0f)) / (texelX(1.0f) - texelX(0.0f)); };
    const auto depthAt = [&](float u) { return (clip * casterAt(worldX(u))).z; };

    constexpr float kPast = 0.02f;
    const Scene scene = tiltedCasterScene(worldX(20.5f + kPast), worldX(43.5f + kPast));
    auto pass = create(scene);
    ASSERT_TRUE(pass) << pass.error().message;
    const auto layers = renderLayers(**context, **pass, sun);
    ASSERT_EQ(layers.size(), 1u);
    ASSERT_EQ((*pass)->layerRecords()[0].clipFromWorld, clip);
    const float row = ((clip * glm::vec4(0, 0, 0, 1)).y * 0.5f + 0.5f) * float(kSize);
    const float stored = layers[0][size_t(row) * kSize + 32];
    const float exact = depthAt(32.5f);
    const float snapped = depthAt(32.5f + kPast - 1.0f / 1024.0f);
    ASSERT_GT(std::abs(snapped - exact), 1e-5f);
    EXPECT_NEAR(stored, snapped, 0.1f * std::abs(snapped - exact)) << "unsnapped: " << exact;
}

INSTANTIATE_TEST_SUITE_P(Scenes, ShadowCasters,
                         testing::Values("cornell", "closed_box", "two_floors", "atrium"));

}  // namespace
}  // namespace pic
