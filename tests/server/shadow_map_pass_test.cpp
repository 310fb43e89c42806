// The shadow-map pass on lavapipe (or the machine's GPU): merged coplanar casters and solids
// drawn from one side store the same depths as the scene's own triangles drawn from both
// sides.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/gltf_loader.h"
#include "core/light_set.h"
#include "server/passes/shadow_map_pass.h"

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
    auto submitted = context.submit([&](VkCommandBuffer cmd) { pass.record(cmd); });
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
    auto scene = loadScene(std::string(PIC_TEST_SCENE_DIR) + "/" + GetParam() + ".gltf");
    ASSERT_TRUE(scene) << scene.error().message;
    auto context = gpu::Context::create();
    if (!context) GTEST_SKIP() << "no Vulkan device: " << context.error().message;
    constexpr uint32_t kSize = 256;
    const LightSet lights = testLights(*scene);
    auto render = [&](gpu::ShadowCasterOptions options, uint64_t& oneSided) {
        auto pass = gpu::ShadowMapPass::create(**context, *scene, kSize, options);
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
    // a few texels on silhouettes, nothing else.
    const auto merged =
        render({.mergeCoplanar = true, .oneSidedSolids = true, .levelsOfDetail = false}, oneSided);
    differingTexels(merged, reference, 1e-4f, fraction);
    EXPECT_LE(fraction, 5e-3) << GetParam() << ": merged casters, differences > 1e-4";
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
    auto scene = loadScene(std::string(PIC_TEST_SCENE_DIR) + "/" + GetParam() + ".gltf");
    ASSERT_TRUE(scene) << scene.error().message;
    auto context = gpu::Context::create();
    if (!context) GTEST_SKIP() << "no Vulkan device: " << context.error().message;
    constexpr uint32_t kSize = 256;
    const LightSet lights = testLights(*scene);
    auto exact = gpu::ShadowMapPass::create(**context, *scene, kSize, {.levelsOfDetail = false});
    ASSERT_TRUE(exact) << exact.error().message;
    auto coarse = gpu::ShadowMapPass::create(**context, *scene, kSize);
    ASSERT_TRUE(coarse) << coarse.error().message;
    const auto expected = renderLayers(**context, **exact, lights);
    const auto actual = renderLayers(**context, **coarse, lights);
    ASSERT_EQ(actual.size(), expected.size());
    const auto levels = (*coarse)->levels();
    for (size_t k = 1; k < levels.size(); ++k) {
        EXPECT_GT(levels[k].error, levels[k - 1].error);
        EXPECT_LE(levels[k].triangles, gpu::kCasterLevelReduction * levels[k - 1].triangles);
    }
    // Only the atrium has curved surfaces (columns) to simplify.
    if (GetParam() == "atrium") EXPECT_GE(levels.size(), 2u);
    for (const gpu::GpuLight& light : (*coarse)->lightRecords()) {
        const uint32_t layers = light.shadowKind == gpu::kShadowCube ? 6 : 1;
        for (uint32_t l = light.firstLayer; l < light.firstLayer + layers; ++l) {
            const uint32_t level = (*coarse)->layerLevels()[l];
            const float error = levels[level].error;
            // Where a layer's texels are all one size, it takes the coarsest level.
            if (light.shadowKind == gpu::kShadowOrthographic) EXPECT_EQ(level, levels.size() - 1);
            EXPECT_LE(error, gpu::kCasterErrorPerTexel * light.texelSlope *
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
INSTANTIATE_TEST_SUITE_P(Scenes, ShadowCasters,
                         testing::Values("cornell", "closed_box", "two_floors", "atrium"));

}  // namespace
}  // namespace pic
