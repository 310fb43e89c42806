#include "server/relight_pool.h"

#include <algorithm>

namespace pic {

RelightPool::RelightPool(unsigned threads) {
    threads = std::max(threads, 1u);
    mThreads.reserve(threads);
    for (unsigned i = 0; i < threads; ++i) mThreads.emplace_back([this] { work(); });
}

RelightPool::~RelightPool() {
    {
        std::lock_guard lock(mMutex);
        mStopping = true;
    }
    mWork.notify_all();
    for (auto& thread : mThreads) thread.join();
}

void RelightPool::ready(Job& job, const void* group) {
    {
        std::lock_guard lock(mMutex);
        auto [it, added] = mJobs.try_emplace(&job);
        JobState& state = it->second;
        if (added) {
            auto found = std::find_if(mGroups.begin(), mGroups.end(),
                                      [group](const Group& g) { return g.key == group; });
            if (found == mGroups.end()) {
                mGroups.push_back(Group{group, {}, false});
                found = mGroups.end() - 1;
            }
            state.group = size_t(found - mGroups.begin());
        }
        if (state.running) {
            state.again = true;
            return;
        }
        if (state.queued) return;
        state.queued = true;
        mGroups[state.group].queue.push_back(&job);
        ++mQueued;
    }
    mWork.notify_one();
}

void RelightPool::forget(Job& job) {
    std::unique_lock lock(mMutex);
    auto it = mJobs.find(&job);
    if (it == mJobs.end()) return;
    if (it->second.queued) {
        std::erase(mGroups[it->second.group].queue, &job);
        --mQueued;
    }
    it->second.queued = false;
    it->second.again = false;
    mIdle.wait(lock, [&] { return !mJobs.at(&job).running; });
    mJobs.erase(&job);
}

size_t RelightPool::queued() const {
    std::lock_guard lock(mMutex);
    return mQueued;
}

RelightPool::Job* RelightPool::next(size_t& group) {
    for (size_t i = 0; i < mGroups.size(); ++i) {
        const size_t g = (mNextGroup + i) % mGroups.size();
        if (mGroups[g].busy || mGroups[g].queue.empty()) continue;
        mNextGroup = (g + 1) % mGroups.size();
        group = g;
        Job* job = mGroups[g].queue.front();
        mGroups[g].queue.pop_front();
        return job;
    }
    return nullptr;
}

void RelightPool::work() {
    std::unique_lock lock(mMutex);
    for (;;) {
        size_t group = 0;
        Job* job = nullptr;
        mWork.wait(lock, [&] { return mStopping || (job = next(group)) != nullptr; });
        if (mStopping) return;
        --mQueued;
        JobState& state = mJobs.at(job);
        state.queued = false;
        state.running = true;
        mGroups[group].busy = true;

        lock.unlock();
        job->compute();
        lock.lock();
        mGroups[group].busy = false;
        // The group is free: another thread may take its next job while this one finishes.
        mWork.notify_one();

        lock.unlock();
        job->finish();
        lock.lock();
        JobState& after = mJobs.at(job);  // forget() waits while running: still there
        after.running = false;
        if (after.again) {
            after.again = false;
            after.queued = true;
            mGroups[group].queue.push_back(job);
            ++mQueued;
            mWork.notify_one();
        }
        mIdle.notify_all();
    }
}

}  // namespace pic
