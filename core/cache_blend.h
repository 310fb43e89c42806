#pragma once
/// Temporal blending of streamed cache versions on a client (paper 001 §3): when a version
/// arrives, the caches shown move from what is on screen to the new ones over a fixed time,
/// so that a light change fades in instead of jumping and a moving light's version-to-version
/// noise is smoothed. Paper 001 keeps an exponential moving average per frame, which depends
/// on the frame rate and never reaches the new state; here the move is linear in time from
/// the caches shown when the version arrived, so every coefficient goes monotonically from
/// where it was to the new value and reaches it exactly after the blend time. A version that
/// arrives mid-blend starts a new blend from what is shown at that moment.

#include "core/cache_values.h"
#include "core/error.h"

namespace pic {

class CacheBlend {
public:
    /// Blends over `seconds` (≥ 0 and finite; 0 shows every version at once). InvalidInput
    /// otherwise, from check().
    explicit CacheBlend(double seconds) : mSeconds(seconds) {}
    static Result<void> check(double seconds);

    /// A version's caches arriving at time `now` (seconds on any clock that does not go
    /// back): the first is shown at once, a later one starts a blend from what is shown at
    /// `now`. InvalidInput when its band counts or cache count differ from the first's, a
    /// value is not finite, or `now` is earlier than the previous push.
    Result<void> push(CacheValues values, double now);

    /// The caches to show at `now` (not before the last push; null before the first): the
    /// newest version itself once the blend is over.
    const CacheValues* at(double now);

    /// Whether at `now` the caches shown are the newest version's.
    bool settled(double now) const { return mPushed && now >= mEnd; }
    double seconds() const { return mSeconds; }

private:
    double mSeconds;
    bool mPushed = false;
    double mStart = 0.0;   ///< when the newest version arrived
    double mEnd = 0.0;     ///< when its blend ends
    CacheValues mFrom;     ///< shown when it arrived
    CacheValues mTo;       ///< the newest version
    CacheValues mShown;    ///< the last blend at()
};

}  // namespace pic
