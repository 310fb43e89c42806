#include "bench/random_lights.h"

#include <cmath>
#include <set>
#include <string>

#include <gtest/gtest.h>

namespace pic {
namespace {

/// A scene that is only bounds and materials: randomLightSet reads nothing else.
Scene boxScene() {
    Scene scene;
    scene.sourcePath = "box";
    scene.bounds.extend(glm::vec3(-2.0f, 0.0f, -1.0f));
    scene.bounds.extend(glm::vec3(2.0f, 3.0f, 1.0f));
    Material white;
    white.name = "white";
    Material panel;
    panel.name = "panel";
    panel.emission = glm::vec3(5.0f);
    scene.materials = {white, panel};
    return scene;
}

TEST(RandomLightSet, SameSeedSameSetOtherSeedOtherSet) {
    const Scene scene = boxScene();
    auto a = randomLightSet(scene, 7);
    auto b = randomLightSet(scene, 7);
    auto c = randomLightSet(scene, 8);
    ASSERT_TRUE(a && b && c);
    EXPECT_EQ(toJson(*a), toJson(*b));
    EXPECT_NE(toJson(*a), toJson(*c));
}

TEST(RandomLightSet, SetsAreValidAndCoverTheRanges) {
    // Over 300 seeds: every set parses back from its JSON (the validation clients' sets pass),
    // positions lie in the bounds, and every count, type, finite range and a zero emissive
    // scale all occur.
    const Scene scene = boxScene();
    const float diagonal = scene.bounds.diagonal();
    std::set<size_t> counts;
    std::set<LightType> types;
    int ranged = 0, saturated = 0, darkEmission = 0;
    for (uint64_t seed = 0; seed < 300; ++seed) {
        auto set = randomLightSet(scene, seed);
        ASSERT_TRUE(set) << set.error().message;
        auto parsed = parseLightSet(toJson(*set));
        ASSERT_TRUE(parsed) << "seed " << seed << ": " << parsed.error().message;
        ASSERT_TRUE(checkLightSet(*set, scene));
        counts.insert(set->lights.size());
        for (const Light& light : set->lights) {
            types.insert(light.type);
            EXPECT_GT(light.intensity, 0.0f);
            EXPECT_TRUE(std::isfinite(light.intensity));
            EXPECT_NEAR(glm::length(light.direction), 1.0f, 1e-5f);
            if (light.type != LightType::Directional) {
                for (int a = 0; a < 3; ++a) {
                    EXPECT_GE(light.position[a], scene.bounds.min[a]) << "seed " << seed;
                    EXPECT_LE(light.position[a], scene.bounds.max[a]) << "seed " << seed;
                }
                // (d/5)² · [0.1, 100] W/sr.
                const float scale = diagonal * diagonal / 25.0f;
                EXPECT_GE(light.intensity, 0.0999f * scale);
                EXPECT_LE(light.intensity, 100.01f * scale);
            }
            if (light.type == LightType::Spot) {
                EXPECT_LE(light.innerConeAngle, light.outerConeAngle);
                EXPECT_GE(light.outerConeAngle, 1.99f * std::numbers::pi_v<float> / 180.0f);
                EXPECT_LE(light.outerConeAngle, 80.01f * std::numbers::pi_v<float> / 180.0f);
            }
            if (std::isfinite(light.range)) {
                ++ranged;
                EXPECT_GE(light.range, 0.099f * diagonal);
                EXPECT_LE(light.range, diagonal * 1.0001f);
            }
            const glm::vec3& c = light.color;
            if (c.r == 0.0f || c.g == 0.0f || c.b == 0.0f) ++saturated;
            EXPECT_GT(c.r + c.g + c.b, 0.0f);
        }
        ASSERT_EQ(set->emissiveScale.size(), 1u) << "only 'panel' emits";
        const float scale = set->emissiveScale.at("panel");
        if (scale == 0.0f)
            ++darkEmission;
        else {
            EXPECT_GE(scale, 0.00999f);
            EXPECT_LE(scale, 10.001f);
        }
    }
    EXPECT_EQ(counts, (std::set<size_t>{1, 2, 3, 4}));
    EXPECT_EQ(types.size(), 3u);
    EXPECT_GT(ranged, 0);
    EXPECT_GT(saturated, 0);
    EXPECT_GT(darkEmission, 0);
}

TEST(RandomLightSet, RefusesAnEmptySceneAndBadRanges) {
    auto empty = randomLightSet(Scene{}, 1);
    ASSERT_FALSE(empty);
    EXPECT_EQ(empty.error().code, ErrorCode::InvalidInput);
    EXPECT_NE(empty.error().message.find("extent"), std::string::npos) << empty.error().message;

    RandomLightRanges reversed;
    reversed.minLights = 3;
    reversed.maxLights = 2;
    auto bad = randomLightSet(boxScene(), 1, reversed);
    ASSERT_FALSE(bad);
    EXPECT_NE(bad.error().message.find("3 and 2"), std::string::npos) << bad.error().message;

    RandomLightRanges cone;
    cone.maxOuterConeDegrees = 120.0f;
    bad = randomLightSet(boxScene(), 1, cone);
    ASSERT_FALSE(bad);
    EXPECT_NE(bad.error().message.find("120"), std::string::npos) << bad.error().message;
}

}  // namespace
}  // namespace pic
