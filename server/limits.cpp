#include "server/limits.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <arpa/inet.h>

namespace pic {

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

namespace {

/// `text` as an IPv4 or IPv6 address: its family and bytes; 0 when it is neither.
int parseAddress(std::string_view text, unsigned char bytes[16]) {
    if (text.empty() || text.size() > 45) return 0;
    const std::string copy(text);
    if (inet_pton(AF_INET, copy.c_str(), bytes) == 1) return AF_INET;
    if (inet_pton(AF_INET6, copy.c_str(), bytes) == 1) return AF_INET6;
    return 0;
}

std::string_view trimmed(std::string_view text) {
    while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.remove_prefix(1);
    while (!text.empty() && (text.back() == ' ' || text.back() == '\t')) text.remove_suffix(1);
    return text;
}

}  // namespace

Result<void> TrustedProxies::add(std::string_view cidr) {
    Range range;
    const size_t slash = cidr.find('/');
    range.family = parseAddress(cidr.substr(0, slash), range.bytes);
    if (range.family == 0)
        return fail(ErrorCode::InvalidInput,
                    "trusted proxy \"{}\" is not an IPv4 or IPv6 address (ADDRESS or ADDRESS/PREFIX)",
                    clipped(cidr));
    const int bits = range.family == AF_INET ? 32 : 128;
    range.prefix = bits;
    if (slash != std::string_view::npos) {
        const std::string_view prefix = cidr.substr(slash + 1);
        int value = -1;
        if (!prefix.empty() && prefix.size() <= 3 &&
            prefix.find_first_not_of("0123456789") == std::string_view::npos)
            value = std::stoi(std::string(prefix));
        if (value < 0 || value > bits)
            return fail(ErrorCode::InvalidInput, "trusted proxy \"{}\": the prefix must be 0 to {}",
                        clipped(cidr), bits);
        range.prefix = value;
    }
    mRanges.push_back(range);
    return {};
}

bool TrustedProxies::contains(std::string_view host) const {
    unsigned char bytes[16] = {};
    const int family = parseAddress(host, bytes);
    if (family == 0) return false;
    for (const Range& range : mRanges) {
        if (range.family != family) continue;
        const int whole = range.prefix / 8, rest = range.prefix % 8;
        if (std::memcmp(bytes, range.bytes, size_t(whole)) != 0) continue;
        if (rest != 0) {
            const unsigned char mask = (unsigned char)(0xff << (8 - rest));
            if ((bytes[whole] & mask) != (range.bytes[whole] & mask)) continue;
        }
        return true;
    }
    return false;
}

std::string TrustedProxies::clientHost(std::string_view peer, std::string_view forwardedFor) const {
    std::string host = peerHost(peer);
    if (!contains(host)) return host;
    while (!forwardedFor.empty()) {
        const size_t comma = forwardedFor.rfind(',');
        const std::string_view entry =
            trimmed(comma == std::string_view::npos ? forwardedFor : forwardedFor.substr(comma + 1));
        forwardedFor = comma == std::string_view::npos ? std::string_view() : forwardedFor.substr(0, comma);
        unsigned char bytes[16];
        if (parseAddress(entry, bytes) == 0) break;  // not an address: believe nothing further
        host = std::string(entry);
        if (!contains(host)) break;
    }
    return host;
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
