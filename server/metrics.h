#pragma once
/// The server's metrics in the Prometheus text exposition format (version 0.0.4), served on
/// `picserver --metrics-listen HOST:PORT` at /metrics (server/metrics_http.h).
///
/// Counters and histograms are kept here as the server runs; gauges (sessions, subscribers)
/// are read at scrape time from a callback. Every series is documented by its # HELP line.

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace pic {

/// A histogram of milliseconds with fixed bucket bounds.
class MsHistogram {
public:
    /// Bucket upper bounds in ms: 0.5 to 10 s, about ×2 apart.
    static constexpr std::array<double, 15> kBounds = {0.5, 1,   2,   5,    10,   20,   50,  100,
                                                       200, 500, 1000, 2000, 5000, 10000, 30000};
    void observe(double ms);
    /// The series of the histogram `name` (buckets, sum, count) with `labels` ("" or
    /// `key="value"`), appended to `out`.
    void render(std::string& out, const std::string& name, const std::string& labels) const;

private:
    std::array<uint64_t, kBounds.size()> mCounts{};  ///< per bucket, not cumulative
    uint64_t mCount = 0;
    double mSum = 0.0;
};

class Metrics {
public:
    /// Gauges read at scrape time.
    struct Gauges {
        size_t sessions = 0;
        size_t subscribers = 0;
        uint64_t versionsSkipped = 0;  ///< by the subscribers of the sessions held now
        bool storeFailing = false;
        unsigned relightThreads = 0;
        size_t relightQueued = 0;  ///< sessions waiting for a relight thread
    };

    /// One computed version of `session`: its pass times, update and encode ms, frame bytes.
    void recordUpdate(const std::string& session, const std::map<std::string, double>& passMs,
                      double updateMs, double encodeMs, uint64_t frameBytes, bool keyFrame);
    /// The session left this server: its per-session series go.
    void forgetSession(const std::string& session);
    /// One call of the session database `op` (create, save, find, remove, ping).
    void recordStore(const std::string& op, double ms, bool failed);
    /// A call answered with the gRPC status `code` (its name: "OK", "UNAUTHENTICATED", …).
    void recordCall(std::string_view call, std::string_view code);
    /// A frame written to a subscriber.
    void recordSent(uint64_t bytes);
    /// How the gauges are read (the server's state).
    void setGauges(std::function<Gauges()> read);

    /// The exposition text.
    std::string render() const;

private:
    mutable std::mutex mMutex;
    uint64_t mUpdates = 0;
    uint64_t mKeyFrames = 0;
    uint64_t mFrameBytes = 0;
    uint64_t mFramesSent = 0;
    uint64_t mBytesSent = 0;
    std::map<std::string, uint64_t> mVersionsBySession;  ///< versions computed per session id
    std::map<std::string, MsHistogram> mPassMs;
    MsHistogram mUpdateMs;
    MsHistogram mEncodeMs;
    std::map<std::string, MsHistogram> mStoreMs;
    std::map<std::string, uint64_t> mStoreErrors;
    std::map<std::pair<std::string, std::string>, uint64_t> mCalls;  ///< by (call, code)
    std::function<Gauges()> mGauges;
};

}  // namespace pic
