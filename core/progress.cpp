#include "core/progress.h"

#include <cstdio>
#include <unistd.h>

namespace pic {

namespace {
std::atomic<bool> gEnabled{true};
constexpr int64_t kQuietMs = 1000;    // stages shorter than this print nothing
constexpr int64_t kRefreshMs = 100;   // terminal refresh interval
}  // namespace

void Progress::setEnabled(bool enabled) { gEnabled = enabled; }

Progress::Progress(std::string label, uint64_t total)
    : mLabel(std::move(label)), mTotal(total ? total : 1),
      mStart(std::chrono::steady_clock::now()), mTty(isatty(STDERR_FILENO) != 0) {}

Progress::~Progress() { finish(); }

double Progress::seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - mStart).count();
}

void Progress::advance(uint64_t n) {
    uint64_t done = mDone.fetch_add(n, std::memory_order_relaxed) + n;
    if (!gEnabled) return;
    int64_t ms = static_cast<int64_t>(seconds() * 1000.0);
    if (ms < kQuietMs) return;
    int64_t last = mLastPrintMs.load(std::memory_order_relaxed);
    if (last >= 0 && ms - last < kRefreshMs) return;
    if (!mLastPrintMs.compare_exchange_strong(last, ms)) return;
    print(done, false);
}

void Progress::finish() {
    std::lock_guard lock(mMutex);
    if (mFinished) return;
    mFinished = true;
    if (mPrinted && gEnabled) {
        mPrinted = false;  // let print() emit the closing line
        uint64_t done = mDone.load();
        double s = seconds();
        if (mTty) std::fprintf(stderr, "\r\033[K");
        std::fprintf(stderr, "%-22s %llu/%llu done in %.1f s\n", mLabel.c_str(),
                     static_cast<unsigned long long>(done), static_cast<unsigned long long>(mTotal), s);
    }
}

void Progress::print(uint64_t done, bool final) {
    std::lock_guard lock(mMutex);
    if (mFinished) return;
    double fraction = std::min(1.0, static_cast<double>(done) / static_cast<double>(mTotal));
    double s = seconds();
    double eta = fraction > 0.0 ? s * (1.0 - fraction) / fraction : 0.0;
    if (mTty) {
        constexpr int kWidth = 30;
        int filled = static_cast<int>(fraction * kWidth);
        std::string bar(static_cast<size_t>(filled), '#');
        bar.resize(kWidth, '.');
        std::fprintf(stderr, "\r\033[K%-22s [%s] %5.1f%%  %.1f s, eta %.1f s", mLabel.c_str(),
                     bar.c_str(), fraction * 100.0, s, eta);
        std::fflush(stderr);
    } else {
        int decile = static_cast<int>(fraction * 10.0);
        if (decile == mLastDecile && !final) return;
        mLastDecile = decile;
        std::fprintf(stderr, "%-22s %5.1f%%  %.1f s, eta %.1f s\n", mLabel.c_str(),
                     fraction * 100.0, s, eta);
    }
    mPrinted = true;
}

}  // namespace pic
