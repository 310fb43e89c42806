#include "server/limits.h"

#include <algorithm>
#include <cmath>

namespace pic {

void FairMutex::lock() {
    std::unique_lock lock(mMutex);
    const uint64_t ticket = mNextTicket++;
    mTurn.wait(lock, [&] { return mServing == ticket; });
}

void FairMutex::unlock() {
    {
        std::lock_guard lock(mMutex);
        ++mServing;
    }
    mTurn.notify_all();
}

TokenBucket::TokenBucket(double perSecond, double burst)
    : mPerSecond(perSecond), mBurst(std::max(burst, 1.0)), mTokens(mBurst) {}

std::chrono::milliseconds TokenBucket::take() {
    std::lock_guard lock(mMutex);
    const auto now = std::chrono::steady_clock::now();
    mTokens = std::min(mBurst, mTokens + mPerSecond * std::chrono::duration<double>(now - mLast).count());
    mLast = now;
    if (mTokens >= 1.0) {
        mTokens -= 1.0;
        return std::chrono::milliseconds(0);
    }
    return std::chrono::milliseconds(int64_t(std::ceil(1000.0 * (1.0 - mTokens) / mPerSecond)));
}

std::string peerHost(std::string_view peer) {
    for (std::string_view scheme : {"ipv4:", "ipv6:"}) {
        if (!peer.starts_with(scheme)) continue;
        std::string_view address = peer.substr(scheme.size());
        const size_t colon = address.rfind(':');
        if (colon != std::string_view::npos) address = address.substr(0, colon);
        if (address.size() >= 2 && address.front() == '[' && address.back() == ']')
            address = address.substr(1, address.size() - 2);
        return std::string(address);
    }
    return std::string(peer);
}

}  // namespace pic
