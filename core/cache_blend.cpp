#include "core/cache_blend.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace pic {
namespace {

/// Whether `a` and `b` hold the same bands and caches.
bool sameShape(const CacheValues& a, const CacheValues& b) {
    return a.bandsY == b.bandsY && a.bandsC == b.bandsC && a.y.size() == b.y.size() &&
           a.co.size() == b.co.size() && a.cg.size() == b.cg.size();
}

Result<void> checkFinite(const std::vector<float>& values, const char* channel) {
    for (size_t i = 0; i < values.size(); ++i)
        if (!std::isfinite(values[i]))
            return fail(ErrorCode::InvalidInput, "cache value {} of {} is {}", i, channel,
                        values[i]);
    return {};
}

/// out = from + w·(to − from) per value.
void mix(const std::vector<float>& from, const std::vector<float>& to, float w,
         std::vector<float>& out) {
    out.resize(to.size());
    for (size_t i = 0; i < to.size(); ++i) out[i] = from[i] + w * (to[i] - from[i]);
}

}  // namespace

Result<void> CacheBlend::check(double seconds) {
    if (!(seconds >= 0.0 && std::isfinite(seconds)))
        return fail(ErrorCode::InvalidInput, "blend time {} s must be finite and ≥ 0", seconds);
    return {};
}

Result<void> CacheBlend::push(CacheValues values, double now) {
    PIC_TRY(check(mSeconds));
    if (mPushed && !sameShape(values, mTo))
        return fail(ErrorCode::InvalidInput,
                    "caches of bands y {} c {} with {} luma values cannot blend with bands y {} "
                    "c {} and {}",
                    values.bandsY, values.bandsC, values.y.size(), mTo.bandsY, mTo.bandsC,
                    mTo.y.size());
    if (!std::isfinite(now) || (mPushed && now < mStart))
        return fail(ErrorCode::InvalidInput, "version pushed at {} s, before the previous one at {} s",
                    now, mStart);
    PIC_TRY(checkFinite(values.y, "Y"));
    PIC_TRY(checkFinite(values.co, "Co"));
    PIC_TRY(checkFinite(values.cg, "Cg"));
    // What is on screen now is where the new blend starts.
    if (mPushed) {
        const CacheValues* shown = at(now);
        mFrom = *shown;
    } else {
        mFrom = values;
    }
    mFrom.irradiance.clear();
    values.irradiance.clear();  // not shaded from (core/cache_values.h)
    // The first version has nothing to blend from.
    mEnd = mPushed ? now + mSeconds : now;
    mTo = std::move(values);
    mStart = now;
    mPushed = true;
    return {};
}

const CacheValues* CacheBlend::at(double now) {
    if (!mPushed) return nullptr;
    if (settled(now)) return &mTo;
    const float w = float(std::clamp((now - mStart) / (mEnd - mStart), 0.0, 1.0));
    mShown.bandsY = mTo.bandsY;
    mShown.bandsC = mTo.bandsC;
    mix(mFrom.y, mTo.y, w, mShown.y);
    mix(mFrom.co, mTo.co, w, mShown.co);
    mix(mFrom.cg, mTo.cg, w, mShown.cg);
    return &mShown;
}

}  // namespace pic
