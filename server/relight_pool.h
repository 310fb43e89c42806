#pragma once
/// The threads that compute every session's versions: a fixed number, whatever the number of
/// sessions, taking the sessions in turns.
///
/// A job (a session) is in one group (its bake): the jobs of a group share one runtime, so at
/// most one of them computes at a time, while jobs of other groups compute on other threads.
/// Each step of a job has two parts: compute() with the group held (the relight), then
/// finish() with the group free for its next job (encoding and publishing).
///
/// Fairness. Groups are served round robin, and so are the jobs of a group: a job that has
/// more work after a step goes to the back of its group's queue, behind every job that was
/// waiting. So one session's stream of light sets cannot starve another session of its bake,
/// nor one busy bake the sessions of another.

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <thread>
#include <unordered_map>
#include <vector>

namespace pic {

class RelightPool {
public:
    /// What a session gives the pool. Both parts of a step run on a pool thread, never two
    /// steps of one job at once.
    class Job {
    public:
        virtual ~Job() = default;
        /// The part that needs the group: with nothing to do (the work went away since the
        /// job was marked ready), it returns at once.
        virtual void compute() = 0;
        /// The part that does not.
        virtual void finish() = 0;
    };

    /// Starts `threads` threads (at least one).
    explicit RelightPool(unsigned threads);
    /// Joins the threads; a step in progress finishes first, queued ones are dropped.
    ~RelightPool();
    RelightPool(const RelightPool&) = delete;
    RelightPool& operator=(const RelightPool&) = delete;

    /// `job` of `group` has work: it is queued at the back of its group's queue, unless it is
    /// queued already; while one of its steps runs, it is queued again once that step ends.
    void ready(Job& job, const void* group);
    /// The pool forgets `job`: it leaves its queue; a step of it that runs is waited for.
    /// Never from the job's own step.
    void forget(Job& job);

    unsigned threads() const { return unsigned(mThreads.size()); }
    /// Jobs waiting for a thread (for the metrics).
    size_t queued() const;

private:
    struct Group {
        const void* key = nullptr;
        std::deque<Job*> queue;
        bool busy = false;  ///< one of its jobs is in compute()
    };
    struct JobState {
        size_t group = 0;      ///< index into mGroups
        bool queued = false;
        bool running = false;
        bool again = false;    ///< marked ready while running
    };

    void work();
    /// A job to run next, round robin over the groups (under mMutex); null when none may.
    Job* next(size_t& group);

    mutable std::mutex mMutex;
    std::condition_variable mWork;   ///< a job was queued, a group freed, or stopping
    std::condition_variable mIdle;   ///< a step ended (forget waits on it)
    std::vector<Group> mGroups;
    size_t mNextGroup = 0;  ///< where the round robin over groups goes on
    std::unordered_map<Job*, JobState> mJobs;
    size_t mQueued = 0;
    bool mStopping = false;
    std::vector<std::thread> mThreads;
};

}  // namespace pic
