#pragma once
/// What keeps one client from crowding out the others: a fair lock for the bake's runtime, a
/// token bucket for request rates, and the peer's host for per-peer counts.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <string_view>

namespace pic {

/// A mutex handed over in the order it was asked for (a ticket lock). Each session has one
/// worker that waits for at most one relight at a time, so under this lock the sessions of a
/// bake take their turns round robin: one session's stream of light sets cannot starve
/// another's, as it can under std::mutex, which lets the thread that just unlocked take it
/// again.
class FairMutex {
public:
    void lock();
    void unlock();

private:
    std::mutex mMutex;
    std::condition_variable mTurn;
    uint64_t mNextTicket = 0;
    uint64_t mServing = 0;
};

/// A token bucket: `perSecond` tokens a second, at most `burst` held (full at the start).
/// Thread-safe.
class TokenBucket {
public:
    TokenBucket(double perSecond, double burst);
    /// Takes a token: zero when there was one, else how long until there will be (nothing is
    /// taken then).
    std::chrono::milliseconds take();

private:
    std::mutex mMutex;
    double mPerSecond;
    double mBurst;
    double mTokens;
    std::chrono::steady_clock::time_point mLast = std::chrono::steady_clock::now();
};

/// The host of a gRPC peer address, its port dropped: "ipv4:10.0.0.7:5123" → "10.0.0.7",
/// "ipv6:[::1]:5123" → "::1"; anything else as it is.
std::string peerHost(std::string_view peer);

}  // namespace pic
