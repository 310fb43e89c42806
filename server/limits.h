#pragma once
/// What keeps one client from crowding out the others: a token bucket for request rates and the
/// peer's host for per-peer counts (the bake's runtime is shared fairly by server/relight_pool.h).

#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.h"

namespace pic {

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

/// Addresses of proxies whose X-Forwarded-For is believed (`picserver --trusted-proxy`): the
/// load balancers in front of the server. Without them every client behind a balancer is the
/// balancer's address, and per-peer quotas count them all as one peer.
class TrustedProxies {
public:
    /// Parses "ADDRESS" or "ADDRESS/PREFIX" (IPv4 or IPv6, e.g. "127.0.0.1", "10.0.0.0/8",
    /// "fd00::/8"); InvalidInput naming the text otherwise.
    Result<void> add(std::string_view cidr);
    bool empty() const { return mRanges.empty(); }
    /// Whether `host` (an address as peerHost gives it) is one of them.
    bool contains(std::string_view host) const;
    /// The client's host: `peer`'s host, or, when that is a trusted proxy, the rightmost address
    /// of `forwardedFor` (comma-separated, each proxy appending the address it saw) that is not
    /// one, stopping at anything that is not an address. Addresses further left could be
    /// anything the client wrote.
    std::string clientHost(std::string_view peer, std::string_view forwardedFor) const;

private:
    struct Range {
        int family = 0;                  ///< AF_INET or AF_INET6
        unsigned char bytes[16] = {};
        int prefix = 0;                  ///< leading bits that must match
    };
    std::vector<Range> mRanges;
};

/// The host of a gRPC peer address, its port dropped: "ipv4:10.0.0.7:5123" → "10.0.0.7",
/// "ipv6:[::1]:5123" → "::1"; anything else as it is.
std::string peerHost(std::string_view peer);

}  // namespace pic
