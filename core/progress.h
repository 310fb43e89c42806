#pragma once
/// Progress bars on stderr for long stages: silent for the first second, then a bar
/// (on a terminal) or a line every 10 % (in logs). Thread-safe `advance`.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>

namespace pic {

/// One stage's progress; prints nothing if the stage ends within a second.
class Progress {
public:
    Progress(std::string label, uint64_t total);
    ~Progress();
    Progress(const Progress&) = delete;
    Progress& operator=(const Progress&) = delete;

    /// Adds n finished units; may print.
    void advance(uint64_t n = 1);
    /// Marks the stage finished and prints the final line if anything was printed.
    void finish();
    /// Seconds since construction.
    double seconds() const;

    /// Globally silences all progress output (for tests and --quiet).
    static void setEnabled(bool enabled);

private:
    void print(uint64_t done, bool final);

    std::string mLabel;
    uint64_t mTotal;
    std::atomic<uint64_t> mDone{0};
    std::chrono::steady_clock::time_point mStart;
    std::atomic<int64_t> mLastPrintMs{-1};
    int mLastDecile = -1;
    bool mPrinted = false;
    bool mFinished = false;
    bool mTty = false;
    std::mutex mMutex;
};

}  // namespace pic
