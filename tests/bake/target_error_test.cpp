// picbake's --target-error pilot (bake/target_error.h) on cornell with small bakes and a small
// pilot: its axes and levels, its views, the choice for a loose target, its cache, a budget
// nothing fits, bad input.

#include "bake/target_error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>

#include "tests/support/baked_scene.h"

namespace {

namespace fs = std::filesystem;
namespace test = pic::test;
using pic::TargetAxis;
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

/// The base the tests start from: small, so that the pilot's bakes are quick.
/// A small base with the bake's default grid caches (only where surfaces read them).
pic::BakeOptions smallBase() {
    pic::BakeOptions options = test::smallBakeOptions(2048, 32, 0.125f, 0.06f);
    options.gridCaches = pic::GridCaches::Surfaces;
    return options;
}

TEST(TargetAxes, LevelsRunFromCheapestToDearestAroundTheBase) {
    const pic::Scene scene = test::loadTestScene("cornell");
    const pic::BakeOptions base = smallBase();
    const auto axes = pic::targetAxes(scene, base);
    ASSERT_EQ(axes.size(), pic::kTargetAxes);
    std::map<std::string, std::string> unused;
    auto d = pic::resolveBakeParams(scene, base, unused);
    ASSERT_TRUE(d);
    for (const pic::TargetAxisLevels& axis : axes) {
        ASSERT_LT(axis.base, axis.values.size());
        const bool coarserIsCheaper = axis.axis == TargetAxis::GridCell || axis.axis == TargetAxis::Texel;
        for (size_t l = 1; l < axis.values.size(); ++l)
            if (coarserIsCheaper)
                EXPECT_GT(axis.values[l - 1], axis.values[l]);
            else
                EXPECT_LT(axis.values[l - 1], axis.values[l]);
    }
    auto levelOf = [&](TargetAxis a) { return axes[size_t(a)]; };
    EXPECT_EQ(levelOf(TargetAxis::Surfels).values[levelOf(TargetAxis::Surfels).base], 2048.0);
    EXPECT_EQ(levelOf(TargetAxis::Links).values[levelOf(TargetAxis::Links).base], 32.0);
    EXPECT_EQ(levelOf(TargetAxis::Links).values.front(), 8.0) << "nL ×⅛ is clamped to 8";
    EXPECT_EQ(levelOf(TargetAxis::BandsY).values.front(), double(d->bandsY - 1));
    EXPECT_EQ(levelOf(TargetAxis::BandsC).values.front(), 1.0);
    EXPECT_LE(levelOf(TargetAxis::BandsC).values.back(), double(d->bandsY));
    EXPECT_FLOAT_EQ(float(levelOf(TargetAxis::GridCell).values.front()), 4.0f * d->gridCell);
    EXPECT_EQ(levelOf(TargetAxis::LinkSamples).values.front(), 4.0);
}

TEST(TargetAxes, OptionsAndNamesFollowTheLevels) {
    const pic::Scene scene = test::loadTestScene("cornell");
    const pic::BakeOptions base = smallBase();
    const auto axes = pic::targetAxes(scene, base);
    pic::TargetLevels levels{};
    for (size_t a = 0; a < axes.size(); ++a) levels[a] = uint8_t(axes[a].base);
    EXPECT_EQ(pic::targetLevelsName(axes, levels), "base");
    pic::BakeOptions o = pic::targetOptions(base, axes, levels);
    EXPECT_EQ(o.surfels, 2048u);
    EXPECT_EQ(o.links, 32u);
    levels[size_t(TargetAxis::Links)] = 0;
    levels[size_t(TargetAxis::GridCell)] = 0;
    EXPECT_EQ(pic::targetLevelsName(axes, levels), "nL 8, grid cell x4");
    o = pic::targetOptions(base, axes, levels);
    EXPECT_EQ(o.links, 8u);
    // lC never exceeds lY, whatever the levels say.
    levels[size_t(TargetAxis::BandsY)] = 0;
    levels[size_t(TargetAxis::BandsC)] = uint8_t(axes[size_t(TargetAxis::BandsC)].values.size() - 1);
    o = pic::targetOptions(base, axes, levels);
    EXPECT_LE(*o.bandsC, *o.bandsY);
}

/// The pilot's views of `scene` under its own lights.
pic::Result<std::vector<pic::Camera>> viewsOf(const pic::Scene& scene, std::vector<std::string>& how) {
    auto rays = pic::EmbreeScene::create(scene);
    if (!rays) return std::unexpected(rays.error());
    auto lights = pic::loadLightSet("", scene);
    if (!lights) return std::unexpected(lights.error());
    return pic::pilotViews(scene, **rays, *lights, how);
}

TEST(TargetAxes, ViewsAreTheScenesCamerasElseFourFromItsMiddle) {
    const pic::Scene cornell = test::loadTestScene("cornell");
    std::vector<std::string> how;
    auto views = viewsOf(cornell, how);
    ASSERT_TRUE(views) << views.error().message;
    ASSERT_EQ(views->size(), std::min<size_t>(cornell.cameras.size(), 2));
    ASSERT_EQ(how.size(), views->size());
    EXPECT_NE(how[0].find("scene camera 0"), std::string::npos);
    pic::Scene noCamera = cornell;
    noCamera.cameras.clear();
    how.clear();
    views = viewsOf(noCamera, how);
    ASSERT_TRUE(views) << views.error().message;
    ASSERT_EQ(views->size(), 4u);
    EXPECT_NE(how[0].find("the centre of the bounds"), std::string::npos) << how[0];
    EXPECT_NE(how[0].find("no camera"), std::string::npos);
    // Every eye is inside the bounds; the views turn round: opposite ways, then across.
    const pic::Aabb& b = cornell.bounds;
    for (const pic::Camera& v : *views)
        EXPECT_TRUE(glm::all(glm::greaterThanEqual(v.eye, b.min)) && glm::all(glm::lessThanEqual(v.eye, b.max)));
    auto look = [&](size_t i) { return glm::normalize((*views)[i].target - (*views)[i].eye); };
    EXPECT_LT(glm::dot(look(0), look(1)), 0.0f);
    EXPECT_NEAR(glm::dot(look(0), look(2)), 0.0f, 0.2f);
}

TEST(TargetAxes, ViewsThatSeeNoIndirectLightAreSkipped) {
    // two_floors' camera looks into the upper room, which no light reaches, and the middle of
    // its bounds is inside the slab: the pilot looks from its lamp in the lower room instead.
    const pic::Scene scene = test::loadTestScene("two_floors");
    ASSERT_FALSE(scene.cameras.empty());
    std::vector<std::string> how;
    auto views = viewsOf(scene, how);
    ASSERT_TRUE(views) << views.error().message;
    ASSERT_FALSE(views->empty());
    for (size_t i = 0; i < views->size(); ++i) {
        EXPECT_EQ(how[i].rfind("from ", 0), 0u) << how[i];
        EXPECT_NE(how[i].find("sees no indirect light"), std::string::npos) << how[i];
        EXPECT_LT((*views)[i].eye.y, scene.bounds.center().y) << how[i];
    }
    // A scene no light reaches at all: no view can measure a relative error.
    std::vector<std::string> none;
    auto rays = pic::EmbreeScene::create(scene);
    ASSERT_TRUE(rays);
    auto dark = pic::pilotViews(scene, **rays, pic::LightSet{}, none);
    ASSERT_FALSE(dark);
    EXPECT_EQ(dark.error().code, pic::ErrorCode::InvalidInput);
    EXPECT_NE(dark.error().message.find("--pilot-camera"), std::string::npos);
}

TEST(TargetError, ALooseTargetTakesACheaperBakeAndASecondTargetReusesThePilot) {
    const pic::Scene scene = test::loadTestScene("cornell");
    const fs::path dir = fs::path(::testing::TempDir()) / "pic_target_error_cache";
    fs::remove_all(dir);
    TargetErrorParams params = smallPilot(0.6);
    params.cacheDir = dir.string();
    auto choice = pic::chooseBakeForTarget(scene, smallBase(), params);
    ASSERT_TRUE(choice) << choice.error().message;
    EXPECT_TRUE(choice->met);
    EXPECT_GT(choice->noise, 0.0);
    // The base first, then single settings, the corner, and any checks.
    ASSERT_GE(choice->rungs.size(), 10u);
    EXPECT_EQ(choice->rungs[0].kind, "base");
    EXPECT_EQ(choice->rungs[0].name, "base");
    EXPECT_EQ(choice->rungs[0].params.surfels, 2048u);
    size_t singles = 0, corners = 0;
    for (const pic::TargetRung& r : choice->rungs) {
        SCOPED_TRACE(r.name);
        singles += r.kind == "single";
        corners += r.kind == "corner";
        EXPECT_GE(r.error, 0.0);
        EXPECT_GE(r.measured, r.error - 1e-12) << "the truth's error is the measured one less the noise";
        ASSERT_EQ(r.viewErrors.size(), 1u) << "cornell's one camera";
        EXPECT_DOUBLE_EQ(r.error, r.viewErrors[0]);
        EXPECT_GT(r.updateMs, 0.0);
        EXPECT_GT(r.predictedMs, 0.0);
        EXPECT_EQ(r.meets, r.error <= params.safety * params.error);
        EXPECT_FALSE(r.cached);
        if (r.kind == "check") {
            EXPECT_TRUE(r.predictedError.has_value());
        }
    }
    EXPECT_GE(singles, 9u);
    EXPECT_EQ(corners, 1u);
    // No cornell surface reads the grid: the base keeps no grid cache and no rung moves its cell.
    EXPECT_EQ(choice->rungs[0].gridCaches, 0u);
    for (const pic::TargetRung& r : choice->rungs) EXPECT_EQ(r.params.gridCell, choice->rungs[0].params.gridCell) << r.name;
    for (double c : choice->cost.coefficients) EXPECT_GE(c, 0.0);
    EXPECT_GT(choice->combinations, singles);
    // The choice: within the goal, the cheapest such rung by the cost model, cheaper than the
    // base, and the bake handed back is its bake.
    const pic::TargetRung& chosen = choice->rungs[choice->chosen];
    EXPECT_TRUE(chosen.meets);
    for (const pic::TargetRung& r : choice->rungs)
        if (r.meets) {
            EXPECT_GE(r.predictedMs, chosen.predictedMs) << r.name;
        }
    EXPECT_LT(chosen.predictedMs, choice->rungs[0].predictedMs);
    EXPECT_EQ(choice->bake.params.surfels, chosen.params.surfels);
    EXPECT_EQ(choice->bake.params.linksPerCache, chosen.params.linksPerCache);
    EXPECT_EQ(choice->bake.caches.size(), chosen.caches);
    const auto json = pic::targetJson(*choice, params);
    EXPECT_EQ(json.at("chosen"), chosen.name);
    EXPECT_EQ(json.at("met"), true);
    EXPECT_EQ(json.at("rungs").size(), choice->rungs.size());
    EXPECT_EQ(json.at("pilot").at("cache"), choice->cachePath);
    ASSERT_TRUE(fs::exists(choice->cachePath));

    // A second target on the same scene bakes nothing the first measured.
    params.error = 0.8;
    auto again = pic::chooseBakeForTarget(scene, smallBase(), params);
    ASSERT_TRUE(again) << again.error().message;
    for (size_t i = 0; i < choice->rungs.size() && i < again->rungs.size(); ++i) {
        if (again->rungs[i].kind == "check") break;
        EXPECT_TRUE(again->rungs[i].cached) << again->rungs[i].name;
        EXPECT_EQ(again->rungs[i].error, choice->rungs[i].error);
    }
    EXPECT_LE(again->rungs[again->chosen].predictedMs, chosen.predictedMs + 1e-9) << "a looser target costs no more";
    fs::remove_all(dir);
}

TEST(TargetError, WhenNothingFitsTheBudgetItTakesTheCheapestAndSaysSo) {
    const pic::Scene scene = test::loadTestScene("cornell");
    TargetErrorParams params = smallPilot(0.6);
    params.budgetMs = 1e-6;  // no update is this fast
    auto choice = pic::chooseBakeForTarget(scene, smallBase(), params);
    ASSERT_TRUE(choice) << choice.error().message;
    EXPECT_FALSE(choice->met);
    for (const pic::TargetRung& r : choice->rungs) {
        EXPECT_FALSE(r.meets) << r.name;
        EXPECT_NE(r.kind, "check") << "no combination is predicted within the budget";
        EXPECT_GE(r.predictedMs, choice->rungs[choice->chosen].predictedMs) << r.name;
    }
    EXPECT_TRUE(choice->cachePath.empty());
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
