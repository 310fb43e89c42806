// server/relight_pool.h: a fixed number of threads, one step per group at a time, groups and
// the jobs of a group taken in turns.

#include "server/relight_pool.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

namespace pic {
namespace {

using namespace std::chrono_literals;

/// Records what ran, when and on which thread; `steps` more steps are asked for after each.
struct Recorder {
    std::mutex mutex;
    std::vector<std::string> order;          ///< job names in the order compute() ran
    std::set<std::thread::id> threads;
    std::map<const void*, int> computing;   ///< per group, steps in compute() now
    int computingNow = 0;
    int maxComputing = 0;
    bool overlapInGroup = false;
};

class FakeJob : public RelightPool::Job {
public:
    FakeJob(std::string name, const void* group, Recorder& recorder, RelightPool& pool,
            int moreSteps = 0, std::chrono::milliseconds work = 2ms)
        : mName(std::move(name)), mGroup(group), mRecorder(recorder), mPool(pool),
          mMoreSteps(moreSteps), mWork(work) {}
    ~FakeJob() override { mPool.forget(*this); }

    void compute() override {
        {
            std::lock_guard lock(mRecorder.mutex);
            mRecorder.order.push_back(mName);
            mRecorder.threads.insert(std::this_thread::get_id());
            if (++mRecorder.computing[mGroup] > 1) mRecorder.overlapInGroup = true;
            mRecorder.maxComputing = std::max(mRecorder.maxComputing, ++mRecorder.computingNow);
        }
        std::this_thread::sleep_for(mWork);
        if (gate.valid()) gate.wait();
        std::lock_guard lock(mRecorder.mutex);
        --mRecorder.computing[mGroup];
        --mRecorder.computingNow;
    }
    void finish() override {
        ++steps;
        // A session whose editor sent another light set while this one computed.
        if (mMoreSteps > 0) {
            --mMoreSteps;
            mPool.ready(*this, mGroup);
        }
    }

    std::atomic<int> steps{0};
    std::shared_future<void> gate;  ///< when set, compute() waits for it

private:
    std::string mName;
    const void* mGroup;
    Recorder& mRecorder;
    RelightPool& mPool;
    int mMoreSteps;
    std::chrono::milliseconds mWork;
};

bool waitFor(const std::function<bool()>& done) {
    for (int i = 0; i < 1000 && !done(); ++i) std::this_thread::sleep_for(5ms);
    return done();
}

// One thread, one bake, three sessions: a session with more work goes behind the others
// waiting, however fast it asks again (a thread per session under a plain mutex let one
// session's worker relock at once and starve the rest).
TEST(RelightPool, JobsOfAGroupTakeTurns) {
    Recorder recorder;
    RelightPool pool(1);
    const int bake = 0;
    // A blocker holds the only thread while the three queue, so that the order is theirs.
    FakeJob blocker("blocker", &bake, recorder, pool, 0, 50ms);
    pool.ready(blocker, &bake);
    ASSERT_TRUE(waitFor([&] { std::lock_guard lock(recorder.mutex); return !recorder.order.empty(); }));
    FakeJob greedy("greedy", &bake, recorder, pool, 3), a("a", &bake, recorder, pool),
        b("b", &bake, recorder, pool);
    pool.ready(greedy, &bake);
    pool.ready(a, &bake);
    pool.ready(b, &bake);
    pool.ready(greedy, &bake);  // queued already: not twice
    ASSERT_TRUE(waitFor([&] { return greedy.steps == 4 && a.steps == 1 && b.steps == 1; }));
    std::lock_guard lock(recorder.mutex);
    EXPECT_EQ(recorder.order, (std::vector<std::string>{"blocker", "greedy", "a", "b", "greedy",
                                                        "greedy", "greedy"}));
}

// One thread: the bakes take turns, one job each.
TEST(RelightPool, BakesTakeTurns) {
    Recorder recorder;
    RelightPool pool(1);
    const int blockerBake = 0, bakeA = 0, bakeB = 0;
    std::promise<void> release;
    FakeJob blocker("blocker", &blockerBake, recorder, pool);
    blocker.gate = release.get_future().share();
    pool.ready(blocker, &blockerBake);
    ASSERT_TRUE(waitFor([&] { std::lock_guard lock(recorder.mutex); return !recorder.order.empty(); }));
    FakeJob a1("a1", &bakeA, recorder, pool), a2("a2", &bakeA, recorder, pool),
        a3("a3", &bakeA, recorder, pool), b1("b1", &bakeB, recorder, pool),
        b2("b2", &bakeB, recorder, pool);
    for (FakeJob* job : {&a1, &a2, &a3}) pool.ready(*job, &bakeA);
    for (FakeJob* job : {&b1, &b2}) pool.ready(*job, &bakeB);
    release.set_value();
    ASSERT_TRUE(waitFor([&] { return a3.steps == 1 && b2.steps == 1; }));
    std::lock_guard lock(recorder.mutex);
    EXPECT_EQ(recorder.order, (std::vector<std::string>{"blocker", "a1", "b1", "a2", "b2", "a3"}));
}

// A bake whose relight is stuck does not hold up another bake's sessions, and however many
// threads there are, the jobs of one bake never compute at once.
TEST(RelightPool, ABusyBakeDoesNotHoldUpAnotherAndComputesOneJobAtATime) {
    Recorder recorder;
    RelightPool pool(4);
    const int busyBake = 0, quietBake = 0;
    std::promise<void> release;
    FakeJob stuck("stuck", &busyBake, recorder, pool);
    stuck.gate = release.get_future().share();
    pool.ready(stuck, &busyBake);
    std::vector<std::unique_ptr<FakeJob>> busy;
    for (int i = 0; i < 8; ++i)
        busy.push_back(std::make_unique<FakeJob>("busy" + std::to_string(i), &busyBake, recorder, pool, 2, 1ms));
    for (auto& job : busy) pool.ready(*job, &busyBake);
    FakeJob quiet("quiet", &quietBake, recorder, pool, 0, 1ms);
    pool.ready(quiet, &quietBake);
    EXPECT_TRUE(waitFor([&] { return quiet.steps == 1; })) << "the quiet bake waited for the busy one";
    EXPECT_EQ(stuck.steps, 0);
    release.set_value();
    ASSERT_TRUE(waitFor([&] {
        for (auto& job : busy)
            if (job->steps != 3) return false;
        return true;
    }));
    std::lock_guard lock(recorder.mutex);
    EXPECT_FALSE(recorder.overlapInGroup) << "two jobs of one bake computed at once";
    EXPECT_LE(recorder.maxComputing, 2) << "one compute per bake at most";
}

// 200 sessions, 3 threads: every session's step runs, on those 3 threads only.
TEST(RelightPool, AFixedNumberOfThreadsServesManyJobs) {
    Recorder recorder;
    RelightPool pool(3);
    std::vector<int> bakes(4);
    std::vector<std::unique_ptr<FakeJob>> jobs;
    for (int i = 0; i < 200; ++i)
        jobs.push_back(std::make_unique<FakeJob>(std::to_string(i), &bakes[i % 4], recorder, pool, 1, 0ms));
    for (int i = 0; i < 200; ++i) pool.ready(*jobs[i], &bakes[i % 4]);
    ASSERT_TRUE(waitFor([&] {
        for (auto& job : jobs)
            if (job->steps != 2) return false;
        return true;
    }));
    EXPECT_EQ(pool.queued(), 0u);
    std::lock_guard lock(recorder.mutex);
    EXPECT_EQ(recorder.order.size(), 400u);
    EXPECT_LE(recorder.threads.size(), 3u);
    EXPECT_FALSE(recorder.overlapInGroup);
}

// forget() waits for a step in progress and drops a queued one; the pool then never calls the
// job again (its memory may be gone).
TEST(RelightPool, ForgetWaitsForTheRunningStepAndDropsTheQueuedOne) {
    Recorder recorder;
    RelightPool pool(1);
    const int bake = 0;
    std::promise<void> release;
    auto running = std::make_unique<FakeJob>("running", &bake, recorder, pool);
    running->gate = release.get_future().share();
    auto queued = std::make_unique<FakeJob>("queued", &bake, recorder, pool);
    pool.ready(*running, &bake);
    ASSERT_TRUE(waitFor([&] { std::lock_guard lock(recorder.mutex); return !recorder.order.empty(); }));
    pool.ready(*queued, &bake);
    EXPECT_EQ(pool.queued(), 1u);
    queued.reset();  // forget: dropped from the queue
    EXPECT_EQ(pool.queued(), 0u);

    std::atomic<bool> forgotten{false};
    std::thread forgetting([&] {
        running.reset();  // forget: waits for the step
        forgotten = true;
    });
    std::this_thread::sleep_for(50ms);
    EXPECT_FALSE(forgotten) << "forget() returned while the job's step was still computing";
    release.set_value();
    forgetting.join();
    EXPECT_TRUE(forgotten);
    std::this_thread::sleep_for(20ms);
    std::lock_guard lock(recorder.mutex);
    EXPECT_EQ(recorder.order, (std::vector<std::string>{"running"}));
}

}  // namespace
}  // namespace pic
