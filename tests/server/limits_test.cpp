// The rate primitives of server/limits.h.

#include "server/limits.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <thread>
#include <vector>

namespace pic {
namespace {

using namespace std::chrono_literals;

TEST(TokenBucket, AllowsABurstThenTellsHowLongToWait) {
    TokenBucket bucket(10.0, 3.0);  // 10 a second, 3 at once
    for (int i = 0; i < 3; ++i) EXPECT_EQ(bucket.take(), 0ms) << i;
    const auto wait = bucket.take();
    EXPECT_GT(wait, 0ms);
    EXPECT_LE(wait, 100ms);
    std::this_thread::sleep_for(wait + 5ms);
    EXPECT_EQ(bucket.take(), 0ms) << "a token came back";
    EXPECT_GT(bucket.take(), 0ms);
}

TEST(PeerHost, DropsThePort) {
    EXPECT_EQ(peerHost("ipv4:10.0.0.7:5123"), "10.0.0.7");
    EXPECT_EQ(peerHost("ipv6:[::1]:5123"), "::1");
    EXPECT_EQ(peerHost("ipv6:[fe80::1%eth0]:80"), "fe80::1%eth0");
    EXPECT_EQ(peerHost("unix:/tmp/socket"), "unix:/tmp/socket");
}

// Behind a load balancer every client has the balancer's address: per-peer quotas then count
// them all as one peer unless the balancer is trusted to name the client.
TEST(TrustedProxies, TheClientIsTheRightmostAddressNoTrustedProxyAppended) {
    TrustedProxies proxies;
    ASSERT_TRUE(proxies.add("127.0.0.1"));
    ASSERT_TRUE(proxies.add("10.0.0.0/8"));
    ASSERT_TRUE(proxies.add("fd00::/8"));
    EXPECT_TRUE(proxies.contains("10.200.3.4"));
    EXPECT_FALSE(proxies.contains("11.0.0.1"));
    EXPECT_TRUE(proxies.contains("fd12::7"));
    EXPECT_FALSE(proxies.contains("fe80::1"));
    EXPECT_FALSE(proxies.contains("127.0.0.2"));
    EXPECT_FALSE(proxies.contains("not an address"));

    // An untrusted peer's header is ignored.
    EXPECT_EQ(proxies.clientHost("ipv4:192.0.2.5:4000", "198.51.100.1"), "192.0.2.5");
    // Through the balancer: the address it appended.
    EXPECT_EQ(proxies.clientHost("ipv4:127.0.0.1:4000", "198.51.100.1"), "198.51.100.1");
    // A client that writes its own header cannot pick its address: the balancer appends the
    // real one last, and only the proxies' own entries are skipped.
    EXPECT_EQ(proxies.clientHost("ipv4:127.0.0.1:4000", "203.0.113.9, 198.51.100.1, 10.1.2.3"),
              "198.51.100.1");
    EXPECT_EQ(proxies.clientHost("ipv6:[fd00::1]:4000", "2001:db8::5"), "2001:db8::5");
    // Nothing usable: the proxy itself.
    EXPECT_EQ(proxies.clientHost("ipv4:127.0.0.1:4000", ""), "127.0.0.1");
    EXPECT_EQ(proxies.clientHost("ipv4:127.0.0.1:4000", "garbage"), "127.0.0.1");
    EXPECT_EQ(proxies.clientHost("ipv4:127.0.0.1:4000", "198.51.100.1, garbage"), "127.0.0.1");

    for (const char* bad : {"", "10.0.0.0/33", "fd00::/129", "10.0.0.0/", "10.0.0.0/x", "host.example", "10.0.0.1/-1"}) {
        TrustedProxies refused;
        const auto added = refused.add(bad);
        ASSERT_FALSE(added) << bad;
        EXPECT_NE(added.error().message.find("trusted proxy"), std::string::npos) << added.error().message;
    }
}

}  // namespace
}  // namespace pic
