#include "server/progressive.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/color.h"

namespace pic {

namespace {

/// splitmix64: a small, portable generator, so the pattern is the same on every platform.
uint64_t nextRandom(uint64_t& state) {
    uint64_t z = (state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

}  // namespace

std::vector<uint32_t> progressiveOrder(std::span<const float> change, uint64_t seed, double share) {
    const size_t n = change.size();
    std::vector<uint32_t> byChange(n);
    std::iota(byChange.begin(), byChange.end(), 0u);
    std::stable_sort(byChange.begin(), byChange.end(), [&](uint32_t a, uint32_t b) {
        return std::abs(change[a]) > std::abs(change[b]);
    });
    double total = 0.0;
    for (const float c : change) total += std::abs(double(c));

    std::vector<uint32_t> order;
    order.reserve(n);
    std::vector<uint8_t> taken(n, 0);
    double covered = 0.0;
    for (const uint32_t cache : byChange) {
        if (!(covered < share * total)) break;
        covered += std::abs(double(change[cache]));
        order.push_back(cache);
        taken[cache] = 1;
    }
    // The rest in the seed's order (Fisher–Yates).
    std::vector<uint32_t> pattern(n);
    std::iota(pattern.begin(), pattern.end(), 0u);
    uint64_t state = seed;
    for (size_t i = n; i > 1; --i) std::swap(pattern[i - 1], pattern[nextRandom(state) % i]);
    for (const uint32_t cache : pattern)
        if (!taken[cache]) order.push_back(cache);
    return order;
}

ProgressiveUpdate::ProgressiveUpdate(double budgetMs, double estimateMs, const HalfFrame* held,
                                     std::span<const CacheValues> heldBounces)
    : mBudgetMs(budgetMs), mHeld(held), mHeldBounces(heldBounces) {
    if (budgetMs > 0.0 && estimateMs > budgetMs && held && !heldBounces.empty())
        mPlanned = uint32_t(std::min(std::ceil(estimateMs / budgetMs) - 1.0, 1e6));
}

std::optional<HalfFrame> ProgressiveUpdate::afterBounce(int bounce, const CacheValues& caches,
                                                        double elapsedMs, bool last) {
    if (mPlanned == 0 || last || bounce < 1) return std::nullopt;
    const uint32_t due = uint32_t(std::min<double>(mPlanned, std::floor(elapsedMs / mBudgetMs)));
    const size_t n = caches.cacheCount();
    const size_t end = n * due / mPlanned;
    if (end <= mDone) return std::nullopt;

    // The held version's bounce with this one's number (or its last, when it ran fewer).
    const CacheValues& before = mHeldBounces[std::min<size_t>(size_t(bounce), mHeldBounces.size()) - 1];
    const std::array<const std::vector<float>*, kFramePlanes> now = {&caches.y, &caches.co, &caches.cg};
    const std::array<const std::vector<float>*, kFramePlanes> then = {&before.y, &before.co, &before.cg};
    for (int p = 0; p < kFramePlanes; ++p) {
        if (now[size_t(p)]->size() != then[size_t(p)]->size() ||
            mHeld->planes[size_t(p)].size() != now[size_t(p)]->size()) {
            mPlanned = 0;  // another layout: nothing to estimate from
            return std::nullopt;
        }
    }
    if (mOrder.empty()) {
        const size_t perCacheY = size_t{caches.bandsY} * caches.bandsY;
        std::vector<float> change(n);
        for (size_t c = 0; c < n; ++c) change[c] = caches.y[c * perCacheY] - before.y[c * perCacheY];
        mOrder = progressiveOrder(change, kProgressiveSeed);
        mState = *mHeld;
    }
    for (int p = 0; p < kFramePlanes; ++p) {
        const std::vector<float>& a = *now[size_t(p)];
        const std::vector<float>& b = *then[size_t(p)];
        const std::vector<uint16_t>& held = mHeld->planes[size_t(p)];
        std::vector<uint16_t>& out = mState.planes[size_t(p)];
        const size_t count = n ? a.size() / n : 0;
        // Cache-major in, coefficient-major on the wire (core/frame_codec.h).
        for (size_t i = mDone; i < end; ++i) {
            const size_t c = mOrder[i];
            for (size_t k = 0; k < count; ++k) {
                const float estimate = halfToFloat(held[k * n + c]) + a[c * count + k] - b[c * count + k];
                out[k * n + c] = floatToHalfClamped(estimate);
            }
        }
    }
    mDone = end;
    ++mMade;
    return mState;
}

}  // namespace pic
