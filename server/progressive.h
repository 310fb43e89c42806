#pragma once
/// Budgeted, progressive updates (`picserver --update-budget-ms M`; paper 003 §5.3, Enlighten's
/// budgeted solver).
///
/// Exactness fixes what can be split: every bounce reads all of the previous bounce's caches,
/// so no cache has its final value before the last bounce. What a budgeted update streams
/// early is an estimate, and what it streams last is exact:
/// - every M ms (checked after each bounce's cache pass) the next part is streamed: its share
///   of the caches, the most changed first, then the rest in a fixed pseudo-random pattern
///   that spreads every part over the whole scene, takes the estimate
///       Ĉ_b = C_prev + (C_b − C_b,prev),
///   the previous version's final caches with this update's first b bounces in place of the
///   previous version's first b bounces: exact for the light the computed bounces carry, the
///   higher bounces (and the direct sky, which follows the last bounce) still the previous
///   version's. A light switched on from darkness (C_prev = C_b,prev = 0) shows b bounces;
/// - the last part is the final state, bit for bit the caches an unbudgeted update streams.
/// An update that is expected to fit in M (the session's previous one did) is not split.

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "core/cache_values.h"
#include "core/frame_codec.h"

namespace pic {

/// The order in which a budgeted update brings caches up to date: the caches carrying `share`
/// of the summed |change| first, largest first, then every other cache in the pseudo-random
/// order `seed` draws (the same for every update of a bake, so parts tile the caches evenly).
std::vector<uint32_t> progressiveOrder(std::span<const float> change, uint64_t seed,
                                       double share = 0.9);

/// The pattern's seed: fixed, so a bake's parts are the same from update to update.
inline constexpr uint64_t kProgressiveSeed = 0x9e3779b97f4a7c15ull;

/// The parts of one budgeted update, made from the bounces as the runtime computes them.
class ProgressiveUpdate {
public:
    /// An update expected to take `estimateMs` under a budget of `budgetMs`: the final state
    /// plus ⌈estimate / budget⌉ − 1 earlier parts, each with an equal share of the caches;
    /// none when it fits or when nothing is held. `held`: the previous version's final state
    /// (what subscribers hold); `heldBounces`: that version's bounce caches (its estimates'
    /// baseline). Both must outlive this object.
    ProgressiveUpdate(double budgetMs, double estimateMs, const HalfFrame* held,
                      std::span<const CacheValues> heldBounces);

    /// Earlier parts planned (0: the update is not split).
    uint32_t plannedParts() const { return mPlanned; }
    /// Earlier parts made so far.
    uint32_t partsMade() const { return mMade; }

    /// After bounce `bounce`'s cache pass, `elapsedMs` into the update: the state of the next
    /// part when one is due (elapsed ≥ its number × budget; several due at once are one part)
    /// and the bounce is not the last, else nothing. The part's state is the previous part's
    /// (the held state at first) with its caches at the estimate Ĉ_bounce.
    std::optional<HalfFrame> afterBounce(int bounce, const CacheValues& caches, double elapsedMs,
                                         bool last);

    /// Caches brought up to date by the parts so far.
    size_t cachesDone() const { return mDone; }

private:
    double mBudgetMs = 0.0;
    uint32_t mPlanned = 0;
    uint32_t mMade = 0;
    const HalfFrame* mHeld = nullptr;
    std::span<const CacheValues> mHeldBounces;
    std::vector<uint32_t> mOrder;  ///< set by the first part
    size_t mDone = 0;
    HalfFrame mState;              ///< the last part's state
};

}  // namespace pic
