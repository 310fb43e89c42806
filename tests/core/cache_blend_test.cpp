// Temporal blending of cache versions (core/cache_blend.h): the first version shows at once,
// later ones move every coefficient monotonically to the new value and reach it exactly
// after the blend time; a version arriving mid-blend starts from what is shown; bad input is
// refused.

#include "core/cache_blend.h"

#include <cmath>

#include <gtest/gtest.h>

namespace pic {
namespace {

/// Caches of bands y 2, c 1 whose every value is `value` plus a per-value offset.
CacheValues filled(size_t caches, float value) {
    CacheValues values = CacheValues::zeros(caches, 2, 1);
    for (size_t i = 0; i < values.y.size(); ++i) values.y[i] = value + 0.01f * float(i);
    for (size_t i = 0; i < values.co.size(); ++i) values.co[i] = -value;
    for (size_t i = 0; i < values.cg.size(); ++i) values.cg[i] = 0.5f * value;
    return values;
}

TEST(CacheBlend, TheFirstVersionShowsAtOnce) {
    CacheBlend blend(0.5);
    EXPECT_EQ(blend.at(0.0), nullptr);
    ASSERT_TRUE(blend.push(filled(3, 1.0f), 10.0));
    const CacheValues* shown = blend.at(10.0);
    ASSERT_NE(shown, nullptr);
    EXPECT_EQ(shown->y, filled(3, 1.0f).y);
    EXPECT_TRUE(blend.settled(10.0));
}

TEST(CacheBlend, EveryValueMovesMonotonicallyAndArrivesExactly) {
    CacheBlend blend(0.4);
    const CacheValues from = filled(4, 1.0f), to = filled(4, 3.0f);
    ASSERT_TRUE(blend.push(from, 0.0));
    ASSERT_TRUE(blend.push(to, 1.0));
    CacheValues previous = from;
    for (int step = 0; step <= 10; ++step) {
        const double now = 1.0 + 0.04 * step;
        const CacheValues* shown = blend.at(now);
        ASSERT_NE(shown, nullptr);
        for (size_t i = 0; i < to.y.size(); ++i) {
            // Between the two, never further from the target than a moment earlier.
            EXPECT_GE(shown->y[i], from.y[i]);
            EXPECT_LE(shown->y[i], to.y[i]);
            EXPECT_GE(shown->y[i], previous.y[i]) << step;
        }
        for (size_t i = 0; i < to.co.size(); ++i) EXPECT_LE(shown->co[i], previous.co[i]) << step;
        // Halfway in time, halfway in value.
        if (step == 5) {
            EXPECT_NEAR(shown->cg[0], 0.5f * (from.cg[0] + to.cg[0]), 1e-6f);
        }
        previous = *shown;
    }
    // At the blend time and after: the new version, bit for bit.
    for (const double now : {1.4, 2.0, 100.0}) {
        const CacheValues* shown = blend.at(now);
        EXPECT_TRUE(blend.settled(now));
        EXPECT_EQ(shown->y, to.y);
        EXPECT_EQ(shown->co, to.co);
        EXPECT_EQ(shown->cg, to.cg);
    }
    EXPECT_FALSE(blend.settled(1.39));
}

TEST(CacheBlend, AVersionArrivingMidBlendStartsFromWhatIsShown) {
    CacheBlend blend(1.0);
    ASSERT_TRUE(blend.push(filled(2, 0.0f), 0.0));
    ASSERT_TRUE(blend.push(filled(2, 4.0f), 1.0));
    const float midway = blend.at(1.25)->y[0];  // a quarter of the way: 1
    EXPECT_NEAR(midway, 1.0f, 1e-6f);
    ASSERT_TRUE(blend.push(filled(2, 2.0f), 1.25));
    // No jump: the new blend starts where the screen was, then heads for the newest version.
    EXPECT_NEAR(blend.at(1.25)->y[0], midway, 1e-6f);
    EXPECT_NEAR(blend.at(1.75)->y[0], 1.5f, 1e-6f);
    EXPECT_EQ(blend.at(2.25)->y, filled(2, 2.0f).y);
}

TEST(CacheBlend, ZeroSecondsShowsEveryVersionAtOnce) {
    CacheBlend blend(0.0);
    ASSERT_TRUE(blend.push(filled(2, 1.0f), 0.0));
    ASSERT_TRUE(blend.push(filled(2, 5.0f), 0.0));
    EXPECT_EQ(blend.at(0.0)->y, filled(2, 5.0f).y);
}

TEST(CacheBlend, RefusesBadTimesShapesAndValues) {
    EXPECT_FALSE(CacheBlend::check(-1.0));
    EXPECT_FALSE(CacheBlend::check(std::nan("")));
    EXPECT_FALSE(CacheBlend::check(INFINITY));
    EXPECT_FALSE(CacheBlend(-1.0).push(filled(2, 1.0f), 0.0));

    CacheBlend blend(0.5);
    ASSERT_TRUE(blend.push(filled(2, 1.0f), 5.0));
    const auto other = blend.push(filled(3, 1.0f), 6.0);
    ASSERT_FALSE(other);
    EXPECT_EQ(other.error().code, ErrorCode::InvalidInput);
    EXPECT_NE(other.error().message.find("cannot blend"), std::string::npos);
    const auto earlier = blend.push(filled(2, 1.0f), 4.0);
    ASSERT_FALSE(earlier);
    EXPECT_NE(earlier.error().message.find("before the previous one"), std::string::npos);
    CacheValues nan = filled(2, 1.0f);
    nan.co[1] = std::nanf("");
    const auto notFinite = blend.push(nan, 6.0);
    ASSERT_FALSE(notFinite);
    EXPECT_NE(notFinite.error().message.find("Co"), std::string::npos);
    // The refusals changed nothing.
    EXPECT_EQ(blend.at(7.0)->y, filled(2, 1.0f).y);
}

}  // namespace
}  // namespace pic
