// picbake's --target-error pilot (bake/target_error.h) on cornell with small bakes and a small
// pilot: its ladder, its views, the choice for a loose target and a tight budget, bad input.

#include "bake/target_error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "tests/support/baked_scene.h"

namespace {

namespace test = pic::test;
using pic::TargetErrorParams;

/// A pilot small enough for a test.
TargetErrorParams smallPilot(double error) {
    TargetErrorParams params;
    params.error = error;
    params.size = {32, 24};
    params.spp = 32;
    params.shadeSpp = 1;
    return params;
}

TEST(TargetLadder, ClimbsFromCheapToTheDefaultAndOneDearer) {
    const pic::Scene scene = test::loadTestScene("cornell");
    const pic::BakeOptions base = test::smallBakeOptions(4096, 64);
    const auto ladder = pic::targetLadder(scene, base);
    ASSERT_GE(ladder.size(), 4u);
    std::map<std::string, std::string> unused;
    auto defaults = pic::resolveBakeParams(scene, base, unused);
    ASSERT_TRUE(defaults);
    uint32_t surfels = 0, links = 0;
    float texel = std::numeric_limits<float>::max();
    bool sawDefault = false;
    for (const auto& [name, options] : ladder) {
        SCOPED_TRACE(name);
        auto resolved = pic::resolveBakeParams(scene, options, unused);
        ASSERT_TRUE(resolved) << resolved.error().message;
        // Every rung costs at least what the one below it does.
        EXPECT_GE(resolved->surfels, surfels);
        EXPECT_GE(resolved->linksPerCache, links);
        EXPECT_LE(resolved->lightmapTexel, texel);
        EXPECT_LE(resolved->bandsC, resolved->bandsY);
        // lY is never lowered: two bands lose the irradiance's l = 2 band.
        EXPECT_EQ(resolved->bandsY, defaults->bandsY);
        surfels = resolved->surfels, links = resolved->linksPerCache, texel = resolved->lightmapTexel;
        if (name == "default") {
            sawDefault = true;
            EXPECT_EQ(resolved->surfels, 4096u);
            EXPECT_EQ(resolved->linksPerCache, 64u);
        }
    }
    EXPECT_TRUE(sawDefault);
    EXPECT_LT(pic::resolveBakeParams(scene, ladder.front().second, unused)->linksPerCache, 64u);
}

TEST(TargetLadder, ViewsAreTheScenesCamerasElseOneFromItsMiddle) {
    const pic::Scene cornell = test::loadTestScene("cornell");
    std::vector<std::string> how;
    auto views = pic::pilotViews(cornell, how);
    ASSERT_EQ(views.size(), std::min<size_t>(cornell.cameras.size(), 2));
    ASSERT_EQ(how.size(), views.size());
    EXPECT_NE(how[0].find("scene camera 0"), std::string::npos);
    pic::Scene noCamera = cornell;
    noCamera.cameras.clear();
    how.clear();
    views = pic::pilotViews(noCamera, how);
    ASSERT_EQ(views.size(), 1u);
    EXPECT_NE(how[0].find("no camera"), std::string::npos);
    // The generated eye is inside the bounds and looks along a horizontal side.
    const pic::Aabb& b = cornell.bounds;
    EXPECT_TRUE(glm::all(glm::greaterThanEqual(views[0].eye, b.min)) && glm::all(glm::lessThanEqual(views[0].eye, b.max)));
    EXPECT_GT(glm::length(views[0].target - views[0].eye), 0.0f);
}

TEST(TargetError, ALooseTargetTakesTheCheapestRungThatMeetsIt) {
    const pic::Scene scene = test::loadTestScene("cornell");
    const pic::BakeOptions base = test::smallBakeOptions(4096, 64);
    auto choice = pic::chooseBakeForTarget(scene, base, smallPilot(0.6));
    ASSERT_TRUE(choice) << choice.error().message;
    EXPECT_TRUE(choice->met);
    EXPECT_EQ(choice->component, "indirect");
    // The first rung meets a target this loose: one bake, cheaper than the default rung.
    ASSERT_EQ(choice->rungs.size(), 1u);
    EXPECT_EQ(choice->chosen, 0u);
    const pic::TargetRung& chosen = choice->rungs[0];
    EXPECT_TRUE(chosen.meets);
    EXPECT_LE(chosen.error, 0.85 * 0.6);
    EXPECT_GE(chosen.error, 0.0);
    EXPECT_GT(chosen.measured, chosen.error - 1e-12) << "the truth's error is the measured one less the noise";
    EXPECT_LT(choice->bake.params.linksPerCache, 64u);
    EXPECT_LT(choice->bake.params.surfels, 4096u);
    EXPECT_EQ(choice->bake.params.surfels, chosen.params.surfels);
    EXPECT_GT(choice->noise, 0.0);
    EXPECT_GT(chosen.updateMs, 0.0);
    const auto json = pic::targetJson(*choice, smallPilot(0.6));
    EXPECT_EQ(json.at("chosen"), "cheapest");
    EXPECT_EQ(json.at("met"), true);
    EXPECT_EQ(json.at("rungs").size(), 1u);
}

TEST(TargetError, OverTheBudgetItStopsAndSaysSo) {
    const pic::Scene scene = test::loadTestScene("cornell");
    TargetErrorParams params = smallPilot(0.6);
    params.budgetMs = 1e-6;  // no update is this fast
    auto choice = pic::chooseBakeForTarget(scene, test::smallBakeOptions(4096, 64), params);
    ASSERT_TRUE(choice) << choice.error().message;
    EXPECT_FALSE(choice->met);
    // The first rung is over the budget; dearer rungs cost more still, so the pilot stops and
    // keeps the cheapest.
    EXPECT_EQ(choice->rungs.size(), 1u);
    EXPECT_EQ(choice->chosen, 0u);
    EXPECT_FALSE(choice->rungs[0].meets);
}

TEST(TargetError, RefusesTargetsAndBudgetsOutOfRange) {
    const pic::Scene scene = test::loadTestScene("cornell");
    for (double bad : {0.0, -0.1, 11.0, std::nan("")}) {
        auto choice = pic::chooseBakeForTarget(scene, {}, smallPilot(bad));
        ASSERT_FALSE(choice) << bad;
        EXPECT_EQ(choice.error().code, pic::ErrorCode::InvalidInput);
        EXPECT_NE(choice.error().message.find("--target-error"), std::string::npos);
    }
    TargetErrorParams params = smallPilot(0.1);
    params.budgetMs = 0.0;
    auto choice = pic::chooseBakeForTarget(scene, {}, params);
    ASSERT_FALSE(choice);
    EXPECT_NE(choice.error().message.find("--budget-ms"), std::string::npos);
}

}  // namespace
