// server/progressive.h: the order of a budgeted update's caches, when its parts are due, and
// the estimate each part brings its caches to.

#include "server/progressive.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <vector>

#include "core/color.h"

namespace pic {
namespace {

/// `caches` caches with 2 luma bands and 1 chroma band, every coefficient `f(cache, k)`
/// (k: 0…3 luma, 4 Co, 5 Cg).
template <class F>
CacheValues cachesOf(size_t caches, F f) {
    CacheValues values = CacheValues::zeros(caches, 2, 1);
    for (size_t c = 0; c < caches; ++c) {
        for (size_t k = 0; k < 4; ++k) values.y[c * 4 + k] = f(c, k);
        values.co[c] = f(c, 4);
        values.cg[c] = f(c, 5);
    }
    return values;
}

/// Coefficient k (numbered as in cachesOf) of cache c in a frame's coefficient-major planes.
float valueOf(const HalfFrame& frame, size_t caches, size_t c, size_t k) {
    if (k < 4) return halfToFloat(frame.planes[0][k * caches + c]);
    return halfToFloat(frame.planes[k == 4 ? 1 : 2][c]);
}

TEST(ProgressiveOrder, TheCachesCarryingMostOfTheChangeComeFirstThenAFixedPattern) {
    // Two caches carry 0.9 of the change: they come first, largest first.
    std::vector<float> change(100, 0.01f);
    change[42] = -6.0f;
    change[7] = 3.0f;
    // Σ = 9 + 0.98; 0.9 of it is 8.98: 42 and 7 cover it.
    const std::vector<uint32_t> order = progressiveOrder(change, kProgressiveSeed);
    ASSERT_EQ(order.size(), 100u);
    EXPECT_EQ(order[0], 42u);
    EXPECT_EQ(order[1], 7u);
    EXPECT_EQ(std::set<uint32_t>(order.begin(), order.end()).size(), 100u) << "a permutation";
    // The rest follow the seed's pattern: the same for another change with the same leaders,
    // not the index order, and another seed draws another pattern.
    std::vector<float> other(100, 0.0f);
    other[42] = 1.0f;
    other[7] = 0.5f;
    EXPECT_EQ(progressiveOrder(other, kProgressiveSeed), order);
    EXPECT_FALSE(std::is_sorted(order.begin() + 2, order.end()));
    EXPECT_NE(progressiveOrder(change, kProgressiveSeed + 1), order);
    // No change at all: the pattern alone.
    const std::vector<uint32_t> still = progressiveOrder(std::vector<float>(100, 0.0f), kProgressiveSeed);
    EXPECT_EQ(std::set<uint32_t>(still.begin(), still.end()).size(), 100u);
}

TEST(ProgressiveUpdate, AnUpdateThatFitsTheBudgetOrHasNothingToEstimateFromIsNotSplit) {
    const CacheValues zero = CacheValues::zeros(8, 2, 1);
    const HalfFrame held = halfFrameOf(zero);
    const std::vector<CacheValues> bounces = {zero};
    EXPECT_EQ(ProgressiveUpdate(50.0, 40.0, &held, bounces).plannedParts(), 0u);
    EXPECT_EQ(ProgressiveUpdate(0.0, 40.0, &held, bounces).plannedParts(), 0u);
    EXPECT_EQ(ProgressiveUpdate(10.0, 40.0, nullptr, bounces).plannedParts(), 0u);
    EXPECT_EQ(ProgressiveUpdate(10.0, 40.0, &held, {}).plannedParts(), 0u);
    ProgressiveUpdate split(10.0, 40.0, &held, bounces);
    EXPECT_EQ(split.plannedParts(), 3u) << "⌈40 / 10⌉ parts, the last being the final state";
    // The last bounce makes no part: the final state follows at once.
    EXPECT_FALSE(split.afterBounce(1, zero, 35.0, true));
}

TEST(ProgressiveUpdate, PartsComeWhenDueEachWithItsShareAtThePreviousVersionPlusTheNewBounces) {
    constexpr size_t n = 12;
    // The previous version: final caches P, bounces B1, B2. This one: bounces C1, C2, C3.
    const auto previousFinal = cachesOf(n, [](size_t c, size_t k) { return 1.0f + 0.25f * float(c) + 0.125f * float(k); });
    const std::vector<CacheValues> previousBounces = {
        cachesOf(n, [](size_t c, size_t k) { return 0.5f + 0.25f * float(c % 3) + 0.0625f * float(k); }),
        cachesOf(n, [](size_t c, size_t k) { return 0.75f + 0.25f * float(c % 3) + 0.0625f * float(k); })};
    // Cache 5 changes most, then cache 9; the others a little.
    const auto bounce = [&](int b) {
        return cachesOf(n, [&, b](size_t c, size_t k) {
            float v = previousBounces[size_t(std::min(b, 2) - 1)].y[c * 4 + std::min<size_t>(k, 3)];
            if (k >= 4) v = k == 4 ? previousBounces[size_t(std::min(b, 2) - 1)].co[c]
                                   : previousBounces[size_t(std::min(b, 2) - 1)].cg[c];
            const float shift = c == 5 ? 8.0f : c == 9 ? 4.0f : 0.0625f;
            return v + shift * float(b);
        });
    };
    const HalfFrame held = halfFrameOf(previousFinal);
    // 40 ms expected under 10: three earlier parts, a third of the caches each.
    ProgressiveUpdate update(10.0, 40.0, &held, previousBounces);
    ASSERT_EQ(update.plannedParts(), 3u);

    // Bounce 1 ends before the first part is due: nothing.
    EXPECT_FALSE(update.afterBounce(1, bounce(1), 6.0, false));
    // Bounce 2 at 12 ms: part 1, four caches, led by the two that changed most.
    const CacheValues c2 = bounce(2);
    auto part1 = update.afterBounce(2, c2, 12.0, false);
    ASSERT_TRUE(part1);
    EXPECT_EQ(update.partsMade(), 1u);
    EXPECT_EQ(update.cachesDone(), 4u);
    const auto estimate = [&](const CacheValues& now, int b, size_t c, size_t k) {
        const CacheValues& before = previousBounces[size_t(std::min(b, 2) - 1)];
        const auto at = [&](const CacheValues& v) {
            return k < 4 ? v.y[c * 4 + k] : k == 4 ? v.co[c] : v.cg[c];
        };
        return halfToFloat(floatToHalf(valueOf(held, n, c, k) + at(now) - at(before)));
    };
    std::set<size_t> updated;
    for (size_t c = 0; c < n; ++c) {
        const bool changed = valueOf(*part1, n, c, 0) != valueOf(held, n, c, 0);
        if (changed) updated.insert(c);
        for (size_t k = 0; k < 6; ++k)
            EXPECT_EQ(valueOf(*part1, n, c, k), changed ? estimate(c2, 2, c, k) : valueOf(held, n, c, k))
                << "cache " << c << " coefficient " << k;
    }
    EXPECT_EQ(updated.size(), 4u);
    EXPECT_TRUE(updated.contains(5) && updated.contains(9)) << "the most changed first";

    // Bounce 3 at 31 ms: parts 2 and 3 were both due, so one part brings the other eight
    // caches, from bounce 3 (the previous version ran two: its last stands in), and keeps
    // part 1's caches as they were.
    const CacheValues c3 = bounce(3);
    auto part2 = update.afterBounce(3, c3, 31.0, false);
    ASSERT_TRUE(part2);
    EXPECT_EQ(update.partsMade(), 2u);
    EXPECT_EQ(update.cachesDone(), n);
    for (size_t c = 0; c < n; ++c)
        for (size_t k = 0; k < 6; ++k)
            EXPECT_EQ(valueOf(*part2, n, c, k),
                      updated.contains(c) ? valueOf(*part1, n, c, k) : estimate(c3, 3, c, k))
                << "cache " << c << " coefficient " << k;
    // Every planned part made: no more.
    EXPECT_FALSE(update.afterBounce(4, bounce(4), 45.0, false));
}

TEST(ProgressiveUpdate, AnotherLayoutThanTheHeldOneMakesNoPart) {
    const CacheValues four = CacheValues::zeros(4, 2, 1);
    const HalfFrame held = halfFrameOf(four);
    const std::vector<CacheValues> bounces = {four};
    ProgressiveUpdate update(1.0, 10.0, &held, bounces);
    EXPECT_FALSE(update.afterBounce(1, CacheValues::zeros(5, 2, 1), 5.0, false));
    EXPECT_EQ(update.plannedParts(), 0u);
}

}  // namespace
}  // namespace pic
