// The fairness and rate primitives of server/limits.h.

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

// Threads that ask for the lock get it in the order they asked. std::mutex makes no such
// promise: there the thread that unlocks may take it again at once, which starved the other
// sessions of a bake while one session's worker relit back to back.
TEST(FairMutex, HandsItselfOverInTheOrderAsked) {
    FairMutex mutex;
    std::vector<int> order;
    std::mutex orderMutex;
    mutex.lock();
    std::vector<std::thread> waiters;
    std::atomic<int> asked{0};
    for (int i = 0; i < 4; ++i) {
        // Each waiter asks only after the one before it has asked (and is blocked).
        while (asked.load() < i) std::this_thread::yield();
        waiters.emplace_back([&, i] {
            asked.fetch_add(1);
            mutex.lock();
            {
                std::lock_guard lock(orderMutex);
                order.push_back(i);
            }
            mutex.unlock();
        });
        std::this_thread::sleep_for(20ms);  // let it block in lock()
    }
    mutex.unlock();
    for (auto& t : waiters) t.join();
    EXPECT_EQ(order, (std::vector<int>{0, 1, 2, 3}));
}

// Two workers, one relocking at once in a loop: with the fair lock the other gets every
// second turn.
TEST(FairMutex, AWorkerThatRelocksAtOnceDoesNotStarveAnother) {
    FairMutex mutex;
    std::atomic<bool> stop{false}, counting{false};
    std::atomic<int> greedy{0}, patient{0};
    std::thread hog([&] {
        while (!stop) {
            std::lock_guard lock(mutex);
            if (counting) ++greedy;
            std::this_thread::sleep_for(1ms);
        }
    });
    std::this_thread::sleep_for(5ms);
    counting = true;  // the hog's turns from the patient worker's first request on
    for (int i = 0; i < 20; ++i) {
        std::lock_guard lock(mutex);
        ++patient;
    }
    stop = true;
    hog.join();
    EXPECT_EQ(patient.load(), 20);
    EXPECT_LE(greedy.load(), 2 * 20 + 10) << "the other worker waited for many turns of the first";
}

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

}  // namespace
}  // namespace pic
