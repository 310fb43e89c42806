#include "server/metrics.h"

#include <fmt/format.h>

namespace pic {

namespace {

/// `name{labels}` or `name` alone.
std::string series(const std::string& name, const std::string& labels) {
    return labels.empty() ? name : name + "{" + labels + "}";
}

/// `labels` with one more label.
std::string withLabel(const std::string& labels, const std::string& label) {
    return labels.empty() ? label : labels + "," + label;
}

void header(std::string& out, const char* name, const char* type, const char* help) {
    out += fmt::format("# HELP {} {}\n# TYPE {} {}\n", name, help, name, type);
}

}  // namespace

void MsHistogram::observe(double ms) {
    for (size_t i = 0; i < kBounds.size(); ++i)
        if (ms <= kBounds[i]) {
            ++mCounts[i];
            break;
        }
    ++mCount;
    mSum += ms;
}

void MsHistogram::render(std::string& out, const std::string& name, const std::string& labels) const {
    uint64_t cumulative = 0;
    for (size_t i = 0; i < kBounds.size(); ++i) {
        cumulative += mCounts[i];
        out += fmt::format("{} {}\n",
                           series(name + "_bucket", withLabel(labels, fmt::format("le=\"{}\"", kBounds[i]))),
                           cumulative);
    }
    out += fmt::format("{} {}\n", series(name + "_bucket", withLabel(labels, "le=\"+Inf\"")), mCount);
    out += fmt::format("{} {}\n", series(name + "_sum", labels), mSum);
    out += fmt::format("{} {}\n", series(name + "_count", labels), mCount);
}

void Metrics::recordUpdate(const std::string& session, const std::map<std::string, double>& passMs,
                           double updateMs, double encodeMs, uint64_t frameBytes, bool keyFrame) {
    std::lock_guard lock(mMutex);
    ++mUpdates;
    mKeyFrames += keyFrame ? 1 : 0;
    mFrameBytes += frameBytes;
    ++mVersionsBySession[session];
    for (const auto& [pass, ms] : passMs) mPassMs[pass].observe(ms);
    mUpdateMs.observe(updateMs);
    mEncodeMs.observe(encodeMs);
}

void Metrics::forgetSession(const std::string& session) {
    std::lock_guard lock(mMutex);
    mVersionsBySession.erase(session);
}

void Metrics::recordStore(const std::string& op, double ms, bool failed) {
    std::lock_guard lock(mMutex);
    mStoreMs[op].observe(ms);
    if (failed) ++mStoreErrors[op];
}

void Metrics::recordCall(std::string_view call, std::string_view code) {
    std::lock_guard lock(mMutex);
    ++mCalls[{std::string(call), std::string(code)}];
}

void Metrics::recordSent(uint64_t bytes) {
    std::lock_guard lock(mMutex);
    ++mFramesSent;
    mBytesSent += bytes;
}

void Metrics::setGauges(std::function<Gauges()> read) {
    std::lock_guard lock(mMutex);
    mGauges = std::move(read);
}

std::string Metrics::render() const {
    // The gauges first, outside the lock: reading them takes the server's own locks.
    std::function<Gauges()> read;
    {
        std::lock_guard lock(mMutex);
        read = mGauges;
    }
    const Gauges gauges = read ? read() : Gauges{};
    std::string out;
    header(out, "pic_sessions", "gauge", "Sessions this server holds.");
    out += fmt::format("pic_sessions {}\n", gauges.sessions);
    header(out, "pic_subscribers", "gauge", "Subscribe streams open on this server.");
    out += fmt::format("pic_subscribers {}\n", gauges.subscribers);
    header(out, "pic_versions_skipped", "gauge",
           "Versions the subscribers of the sessions held now skipped (latest wins).");
    out += fmt::format("pic_versions_skipped {}\n", gauges.versionsSkipped);
    header(out, "pic_store_up", "gauge",
           "1 while the session database answers, 0 while it fails (health NOT_SERVING).");
    out += fmt::format("pic_store_up {}\n", gauges.storeFailing ? 0 : 1);
    header(out, "pic_relight_threads", "gauge", "Threads that compute the sessions' versions.");
    out += fmt::format("pic_relight_threads {}\n", gauges.relightThreads);
    header(out, "pic_relight_queued", "gauge",
           "Sessions with a light set waiting for a relight thread or for their bake.");
    out += fmt::format("pic_relight_queued {}\n", gauges.relightQueued);

    std::lock_guard lock(mMutex);
    header(out, "pic_updates_total", "counter", "Versions computed and encoded.");
    out += fmt::format("pic_updates_total {}\n", mUpdates);
    header(out, "pic_session_versions_computed_total", "counter",
           "Versions computed on this server, per session it holds.");
    for (const auto& [session, count] : mVersionsBySession)
        out += fmt::format("pic_session_versions_computed_total{{session=\"{}\"}} {}\n", session, count);
    header(out, "pic_key_frames_total", "counter", "Versions broadcast as key frames.");
    out += fmt::format("pic_key_frames_total {}\n", mKeyFrames);
    header(out, "pic_frame_bytes_total", "counter", "Bytes of the broadcast frames, encoded.");
    out += fmt::format("pic_frame_bytes_total {}\n", mFrameBytes);
    header(out, "pic_frames_sent_total", "counter", "Frames written to subscribers.");
    out += fmt::format("pic_frames_sent_total {}\n", mFramesSent);
    header(out, "pic_bytes_sent_total", "counter", "Frame bytes written to subscribers.");
    out += fmt::format("pic_bytes_sent_total {}\n", mBytesSent);
    header(out, "pic_update_ms", "histogram", "Milliseconds per update, all passes.");
    mUpdateMs.render(out, "pic_update_ms", "");
    header(out, "pic_pass_ms", "histogram", "Milliseconds per update in each pass.");
    for (const auto& [pass, histogram] : mPassMs)
        histogram.render(out, "pic_pass_ms", fmt::format("pass=\"{}\"", pass));
    header(out, "pic_encode_ms", "histogram", "Milliseconds to encode a version's frame.");
    mEncodeMs.render(out, "pic_encode_ms", "");
    header(out, "pic_store_ms", "histogram", "Milliseconds per session database call.");
    for (const auto& [op, histogram] : mStoreMs)
        histogram.render(out, "pic_store_ms", fmt::format("op=\"{}\"", op));
    header(out, "pic_store_errors_total", "counter", "Session database calls that failed.");
    for (const auto& [op, count] : mStoreErrors)
        out += fmt::format("pic_store_errors_total{{op=\"{}\"}} {}\n", op, count);
    header(out, "pic_calls_total", "counter",
           "Calls answered, by method and gRPC status: refusals show as UNAUTHENTICATED, "
           "PERMISSION_DENIED, RESOURCE_EXHAUSTED (quotas, rates) and INVALID_ARGUMENT.");
    for (const auto& [key, count] : mCalls)
        out += fmt::format("pic_calls_total{{call=\"{}\",code=\"{}\"}} {}\n", key.first, key.second, count);
    return out;
}

}  // namespace pic
