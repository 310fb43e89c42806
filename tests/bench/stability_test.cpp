// The stability suite (bench/stability_benchmark.h) on small bakes: its metrics against
// hand-worked answers, then paper 000 §5.2's and paper 001 §7's failure cases, a moving light
// and random light sets, each held to a bound measured with margin (the measured value is in
// the comment beside it). `picbench stability` runs the same functions at full size.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "bench/stability_benchmark.h"
#include "core/color.h"
#include "core/light_set.h"
#include "core/sh.h"
#include "render/cpu/surfel_lighting.h"
#include "tests/support/baked_scene.h"

namespace pic {
namespace {

/// A test scene baked small: a few seconds per bake on two cores, as the runtime tests do.
const test::BakedScene& small(const std::string& name) {
    return test::bakedScene(name, test::smallBakeOptions(4096, 64), 0.12f, 0.06f);
}

/// A uniform image of one colour.
Image flat(uint32_t w, uint32_t h, const glm::vec3& color) {
    Image image(w, h);
    for (glm::vec3& p : image.pixels) p = color;
    return image;
}

// ---------------------------------------------------------------------------------------------
// The metrics on hand-worked inputs.

TEST(StabilityMetrics, LowestProjectionOfNonNegativeLight) {
    // Σ_{l<L} (2l+1)·P_l(x): 1; 1 + 3x → −2 at x = −1; 1 + 3x + 5(3x² − 1)/2 → −1.8 at x = −0.2.
    EXPECT_DOUBLE_EQ(minNonNegativeProjection(1), 1.0);
    EXPECT_NEAR(minNonNegativeProjection(2), -2.0, 1e-12);
    EXPECT_NEAR(minNonNegativeProjection(3), -1.8, 1e-9);
    // More bands ring deeper.
    EXPECT_LT(minNonNegativeProjection(4), minNonNegativeProjection(3));
}

TEST(StabilityMetrics, FlickerOfConstantAndAlternatingFrames) {
    const std::vector<Image> still(5, flat(4, 3, glm::vec3(0.5f)));
    auto s = flickerSeries(still);
    ASSERT_TRUE(s) << s.error().message;
    EXPECT_EQ(s->index, 0.0);
    // Luminance alternating 1, 2, 1, 2: |Δ| = 1 against a level of 1.5 every step.
    std::vector<Image> blinking;
    for (int t = 0; t < 4; ++t) blinking.push_back(flat(4, 3, glm::vec3(t % 2 ? 2.0f : 1.0f)));
    s = flickerSeries(blinking);
    ASSERT_TRUE(s);
    EXPECT_NEAR(s->index, 1.0 / 1.5, 1e-6);
    EXPECT_EQ(s->change[0], 0.0);
    EXPECT_NEAR(s->mean[1], 2.0, 1e-6);
    EXPECT_FALSE(flickerSeries({flat(4, 3, glm::vec3(1.0f))}));
    EXPECT_FALSE(flickerSeries({flat(4, 3, glm::vec3(1.0f)), flat(3, 3, glm::vec3(1.0f))}));
}

TEST(StabilityMetrics, ChromaOfSameAndSwappedColours) {
    Image reference = flat(4, 2, glm::vec3(1.0f, 0.1f, 0.0f));
    for (uint32_t x = 0; x < 4; ++x) reference.at(x, 1) = glm::vec3(0.1f, 1.0f, 0.0f);
    auto same = chromaStats(reference, reference);
    ASSERT_TRUE(same);
    EXPECT_NEAR(same->error, 0.0, 1e-12);
    EXPECT_EQ(same->hueAgreement, 1.0);
    // Red and green swapped: chromaticities (10/11, 1/11, 0) and (1/11, 10/11, 0) are 9/11
    // apart, and no hue agrees.
    Image swapped = reference;
    for (glm::vec3& p : swapped.pixels) std::swap(p.r, p.g);
    auto bad = chromaStats(swapped, reference);
    ASSERT_TRUE(bad);
    EXPECT_NEAR(bad->error, 9.0 / 11.0, 1e-6);
    EXPECT_EQ(bad->hueAgreement, 0.0);
    // Grey keeps no hue and is 1 − 1/3 − … away: (1/3, 1/3, 1/3) vs (10/11, 1/11, 0).
    auto grey = chromaStats(flat(4, 2, glm::vec3(1.0f)), reference);
    ASSERT_TRUE(grey);
    EXPECT_NEAR(grey->error, 0.5 * (10.0 / 11 - 1.0 / 3 + 1.0 / 3 - 1.0 / 11 + 1.0 / 3), 1e-6);
    EXPECT_EQ(grey->hueAgreement, 0.0);
}

/// Cache values of one cache holding the luma of a delta of radiance `strength` from `d`
/// (the most negative ringing any non-negative light can have) and grey chroma.
CacheValues deltaCache(const glm::vec3& d, float strength) {
    CacheValues values = CacheValues::zeros(1, 3, 2);
    shEvaluate(3, d, values.y.data());
    for (float& c : values.y) c *= strength;
    return values;
}

TEST(StabilityMetrics, CacheChecksPassADeltaAndCatchWhatNoLightCanGive) {
    const glm::vec3 d = glm::normalize(glm::vec3(0.3f, -0.8f, 0.5f));
    EXPECT_EQ(invalidCacheValues(deltaCache(d, 2.0f)), std::nullopt);
    EXPECT_EQ(invalidCacheValues(CacheValues::zeros(3, 3, 2)), std::nullopt);

    CacheValues nan = deltaCache(d, 2.0f);
    nan.y[4] = std::numeric_limits<float>::quiet_NaN();
    auto reason = invalidCacheValues(nan);
    ASSERT_TRUE(reason);
    EXPECT_NE(reason->find("coefficient 4"), std::string::npos) << *reason;

    // Band 0 of red below 0: R = Y + Co − Cg.
    CacheValues negativeRed = deltaCache(d, 2.0f);
    negativeRed.co[0] = -2.0f * negativeRed.y[0];
    reason = invalidCacheValues(negativeRed);
    ASSERT_TRUE(reason);
    EXPECT_NE(reason->find("channel R"), std::string::npos) << *reason;

    // The delta's mean halved: its ringing dips below −1.8 × the mean.
    CacheValues ringing = deltaCache(d, 2.0f);
    ringing.y[0] *= 0.5f;
    reason = invalidCacheValues(ringing);
    ASSERT_TRUE(reason);
    EXPECT_NE(reason->find("luma"), std::string::npos) << *reason;

    Image image = flat(3, 2, glm::vec3(0.2f));
    EXPECT_EQ(invalidPixels(image), std::nullopt);
    image.at(2, 1).g = -1e-6f;
    reason = invalidPixels(image);
    ASSERT_TRUE(reason);
    EXPECT_NE(reason->find("(2, 1) channel G"), std::string::npos) << *reason;
}

TEST(StabilityMetrics, MovingLightPathIsSeededAndInsideTheScene) {
    const test::BakedScene& b = small("furnished_room");
    ASSERT_TRUE(b.ok);
    const auto path = movingLightPath(b.scene, 3, 60);
    ASSERT_EQ(path.size(), 60u);
    EXPECT_EQ(path, movingLightPath(b.scene, 3, 60));
    EXPECT_NE(path, movingLightPath(b.scene, 4, 60));
    float longest = 0.0f;
    for (size_t k = 0; k < path.size(); ++k) {
        for (int a = 0; a < 3; ++a) {
            EXPECT_GT(path[k][a], b.scene.bounds.min[a]);
            EXPECT_LT(path[k][a], b.scene.bounds.max[a]);
        }
        longest = std::max(longest, glm::distance(path[k], path[(k + 1) % path.size()]));
    }
    // A closed loop of at most 2π × 0.39 × 5 m ≈ 12.3 m: steps of at most ~0.25 m.
    EXPECT_LT(longest, 0.3f);
}

// ---------------------------------------------------------------------------------------------
// The furnished rooms.

TEST(StabilityScenes, TheSunComesInThroughTheWindowOnly) {
    // Each furnished room's sun alone lights some surfels (through the window) but far from all:
    // the walls, ceiling and most of the floor stay in its shadow.
    for (const std::string name : {"furnished_room", "furnished_study"}) {
        const test::BakedScene& b = small(name);
        ASSERT_TRUE(b.ok) << name;
        LightSet sun = defaultLightSet(b.scene);
        std::erase_if(sun.lights, [](const Light& l) { return l.type != LightType::Directional; });
        ASSERT_EQ(sun.lights.size(), 1u) << name;
        std::vector<glm::vec3> flux(b.bake.surfels.size());
        directSurfelFlux(b.scene, *b.rays, b.bake, sun, flux);
        size_t lit = 0;
        for (const glm::vec3& f : flux) lit += luminance(f) > 0.0f;
        EXPECT_GT(lit, b.bake.surfels.size() / 100) << name;
        EXPECT_LT(lit, b.bake.surfels.size() / 5) << name;
        EXPECT_GE(b.scene.lights.size(), 3u) << name << ": sun, ceiling lamp, spot";
    }
}

// ---------------------------------------------------------------------------------------------
// The failure cases on small bakes.

/// No path tracing, no ideal caches: the linked caches alone.
StabilitySettings linkedOnly(glm::uvec2 size) {
    StabilitySettings settings;
    settings.size = size;
    settings.spp = 0;
    settings.probeSamples = 0;
    return settings;
}

TEST(StabilitySuite, ThinWallLeaksLittle) {
    // thin_wall: dark side ÷ lit side of the indirect light, measured 0.0023 from the linked
    // caches and 0.0022 from the ideal ones (128 directions each); path tracing gives 0, the
    // partition being sealed. What is left sits where caches straddle the partition (the
    // ideal caches leak as much). Paper 000 §5.2 (c)'s clusters that straddle a wall leaked
    // 0.051 here with the paper's hierarchy and 16-ray link estimates. `picbench stability`
    // gives 0.0029 at the default bake.
    const test::BakedScene& b = small("thin_wall");
    ASSERT_TRUE(b.ok);
    ASSERT_GE(b.scene.cameras.size(), 2u);
    StabilitySettings settings = linkedOnly({48, 36});
    settings.probeSamples = 128;
    auto relit = relightScene(b.scene, *b.rays, b.bake, defaultLightSet(b.scene), settings);
    ASSERT_TRUE(relit) << relit.error().message;
    auto leak = measureLeak(*relit, b.scene.cameras[0], b.scene.cameras[1], settings);
    ASSERT_TRUE(leak) << leak.error().message;
    ASSERT_TRUE(leak->ideal);
    EXPECT_GT(meanLuminance(leak->lit.linked), 0.0);
    EXPECT_LT(leak->linked, 0.01);
    EXPECT_LT(*leak->ideal, 0.01);
}

TEST(StabilitySuite, SmallSpotKeepsItsIndirectLight) {
    // small_spot: its 8° spot lights a disc of 0.53 m², 20 of the 4096 surfels (measured 21).
    // Linked ÷ path-traced (64 spp) indirect mean measured 1.03 (`picbench stability`,
    // default bake: 0.989).
    const test::BakedScene& b = small("small_spot");
    ASSERT_TRUE(b.ok);
    std::vector<glm::vec3> flux(b.bake.surfels.size());
    directSurfelFlux(b.scene, *b.rays, b.bake, defaultLightSet(b.scene), flux);
    const auto lit = std::count_if(flux.begin(), flux.end(),
                                   [](const glm::vec3& f) { return luminance(f) > 0.0f; });
    EXPECT_GT(lit, 5);
    EXPECT_LT(lit, 60) << "no longer a spot that lights few surfels";
    StabilitySettings settings = linkedOnly({48, 27});
    settings.spp = 64;
    auto relit = relightScene(b.scene, *b.rays, b.bake, defaultLightSet(b.scene), settings);
    ASSERT_TRUE(relit) << relit.error().message;
    auto view = indirectView(*relit, b.scene.cameras[0], settings);
    ASSERT_TRUE(view) << view.error().message;
    ASSERT_TRUE(view->reference);
    const double reference = meanLuminance(*view->reference);
    ASSERT_GT(reference, 0.0);
    EXPECT_GT(meanLuminance(view->linked) / reference, 0.8);
}

TEST(StabilitySuite, OppositeColoursKeepTheirHue) {
    // opposite_colors (paper 001 §7: chroma with lC = 2 bands against a red and a green lamp
    // at either end): against path tracing (64 spp), hue agreement measured 0.997 and chroma
    // error 0.056 (`picbench stability`, default bake: 1.000 and 0.036).
    const test::BakedScene& b = small("opposite_colors");
    ASSERT_TRUE(b.ok);
    StabilitySettings settings = linkedOnly({48, 27});
    settings.spp = 64;
    auto relit = relightScene(b.scene, *b.rays, b.bake, defaultLightSet(b.scene), settings);
    ASSERT_TRUE(relit) << relit.error().message;
    auto view = indirectView(*relit, b.scene.cameras[0], settings);
    ASSERT_TRUE(view) << view.error().message;
    auto stats = chromaStats(view->linked, *view->reference);
    ASSERT_TRUE(stats) << stats.error().message;
    EXPECT_GT(stats->hueAgreement, 0.97);
    EXPECT_LT(stats->error, 0.08);
}

TEST(StabilitySuite, MovingLightFlickersNoMoreThanIdealCaches) {
    // furnished_room, a point light over 12 steps of a closed loop, 32×24 indirect frames:
    // flicker index measured 0.143 linked, 0.165 ideal (512 directions per cache), ratio 0.87;
    // roughness 0.131 and 0.151, ratio 0.86. The target of the suite is a ratio ≤ 1.2.
    const test::BakedScene& b = small("furnished_room");
    ASSERT_TRUE(b.ok);
    StabilitySettings settings = linkedOnly({32, 24});
    settings.probeSamples = 512;
    auto moving = runMovingLight(b.scene, *b.rays, b.bake, b.scene.cameras[0], 12, 1, settings);
    ASSERT_TRUE(moving) << moving.error().message;
    ASSERT_TRUE(moving->ideal);
    ASSERT_EQ(moving->linked.mean.size(), 12u);
    EXPECT_GT(moving->linked.index, 0.0);
    EXPECT_LT(moving->linked.index, 1.2 * moving->ideal->index);
    EXPECT_LT(moving->linked.roughness, 1.3 * moving->ideal->roughness);
}

// A client that blends cache versions (core/cache_blend.h, paper 001 §3) draws the moving
// light without jumps: without blending, one frame per version carries the whole change and
// the others none; blending over an update interval spreads it over the interval's frames,
// and longer blends also average the versions' noise, at the cost of lagging behind.
TEST(StabilitySuite, BlendingClientsSpreadTheMovingLightsChanges) {
    const test::BakedScene& b = small("furnished_room");
    ASSERT_TRUE(b.ok);
    const StabilitySettings settings = linkedOnly({32, 24});
    auto moving = runMovingLight(b.scene, *b.rays, b.bake, b.scene.cameras[0], 10, 1, settings,
                                 {0.0, 1.0, 4.0}, 4);
    ASSERT_TRUE(moving) << moving.error().message;
    ASSERT_EQ(moving->blended.size(), 3u);
    const BlendedFlicker& none = moving->blended[0];
    const BlendedFlicker& one = moving->blended[1];
    const BlendedFlicker& four = moving->blended[2];
    ASSERT_EQ(none.frames.mean.size(), 40u);
    // Unblended, the client shows each version as it arrives: the same jumps as the versions.
    EXPECT_NEAR(none.frames.peak, moving->linked.peak, 1e-9);
    // 39 frame-to-frame changes of which 9 are the versions' and the rest none.
    EXPECT_NEAR(none.frames.index * 39.0, moving->linked.index * 9.0,
                1e-6 * moving->linked.index * 9.0);
    EXPECT_EQ(none.lag, 0.0);
    // Blending over one interval: the jumps are spread over the interval's four frames.
    EXPECT_LT(one.frames.peak, 0.5 * none.frames.peak);
    EXPECT_LT(one.frames.roughness, none.frames.roughness);
    EXPECT_GT(one.lag, 0.0);
    // Over four intervals: smoother still, and further behind.
    EXPECT_LT(four.frames.peak, one.frames.peak);
    EXPECT_LT(four.frames.index, one.frames.index);
    EXPECT_GT(four.lag, one.lag);
    for (const BlendedFlicker& b : moving->blended)
        std::printf("[ measured ] blend %g intervals: flicker %.5f, roughness %.5f, largest "
                    "change %.5f, lag %.5f\n",
                    b.intervals, b.frames.index, b.frames.roughness, b.frames.peak, b.lag);
}

TEST(StabilitySuite, RandomLightSetsGiveNoNanInfOrNegativeLight) {
    // 99 seeded light sets, 11 per small scene; the full 1,000 are `picbench stability`'s.
    const std::vector<std::string> scenes{"cornell",    "cornell_area",    "closed_box",
                                          "two_floors", "opposite_colors", "small_spot",
                                          "thin_wall",  "furnished_room",  "furnished_study"};
    for (size_t s = 0; s < scenes.size(); ++s) {
        const test::BakedScene& b = small(scenes[s]);
        ASSERT_TRUE(b.ok) << scenes[s];
        std::vector<uint64_t> seeds;
        for (uint64_t k = 0; k < 11; ++k) seeds.push_back(1 + s + scenes.size() * k);
        auto failures = checkRandomLightSets(b.scene, *b.rays, b.bake, scenes[s], seeds, {16, 12});
        ASSERT_TRUE(failures) << failures.error().message;
        for (const RandomSetFailure& f : *failures)
            ADD_FAILURE() << f.scene << " seed " << f.seed << ": " << f.reason;
    }
}

}  // namespace
}  // namespace pic
