#include "client/load_test.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <map>
#include <numeric>
#include <mutex>
#include <thread>
#include <vector>

#include <glm/gtc/constants.hpp>

#include "proto/wire.h"

namespace pic {

namespace {

using Clock = std::chrono::steady_clock;

double percentile(std::vector<double> values, double p) {
    if (values.empty()) return 0.0;
    std::sort(values.begin(), values.end());
    const size_t index = size_t(std::ceil(p * double(values.size()))) ;
    return values[std::min(values.size() - 1, index == 0 ? 0 : index - 1)];
}

/// A state a subscriber came to hold (a version's final state, or an earlier part: part ≥ 1).
struct Held {
    uint64_t version = 0;
    uint32_t part = 0;
    Clock::time_point when;
};

/// What one subscriber saw: when it held each state, and what frames cost.
struct Received {
    std::vector<Held> versions;  ///< in arrival order
    uint64_t keyBytes = 0, keyFrames = 0, deltaBytes = 0, deltaFrames = 0;
    uint64_t skipped = 0;
    uint64_t partialFrames = 0;  ///< earlier parts of budgeted versions
    std::vector<std::string> errors;
    std::map<uint64_t, std::pair<double, double>> serverMs;  ///< version → update, encode ms
};

void subscribeLoop(FrameStream& stream, const v1::SceneHeader& header, Received& received,
                   std::atomic<uint32_t>& ready, std::mutex& mutex) {
    FrameDecoder decoder(header);
    v1::Frame frame;
    bool first = true;
    while (stream.next(frame)) {
        const bool key = frame.base_version() == 0;
        const std::pair<double, double> serverMs{frame.update_ms(), frame.encode_ms()};
        size_t bytes = 0;
        for (const v1::Plane& plane : frame.planes()) bytes += plane.data().size();
        const uint64_t previous = decoder.version();
        auto applied = decoder.apply(frame);
        const auto now = Clock::now();
        std::lock_guard lock(mutex);
        if (!applied) {
            received.errors.push_back(applied.error().message);
            continue;
        }
        if (first && !key) received.errors.push_back("the first frame was not a key frame");
        if (!first && frame.version() > previous + 1) received.skipped += frame.version() - previous - 1;
        (key ? received.keyBytes : received.deltaBytes) += bytes;
        ++(key ? received.keyFrames : received.deltaFrames);
        received.versions.push_back({frame.version(), frame.part(), now});
        if (frame.part() == 0) received.serverMs[frame.version()] = serverMs;
        else ++received.partialFrames;
        if (first) ready.fetch_add(1);
        first = false;
    }
    grpc::Status status = stream.status();
    if (!status.ok() && status.error_code() != grpc::StatusCode::CANCELLED) {
        std::lock_guard lock(mutex);
        received.errors.push_back(wire::fromStatus(status, "Subscribe").message);
    }
}

/// Whether the subscriber held `version`'s final state or any state of a newer version.
bool holdsFinal(const Received& received, uint64_t version) {
    if (received.versions.empty()) return false;
    const Held& last = received.versions.back();
    return last.version > version || (last.version == version && last.part == 0);
}

}  // namespace

LightSet movedLightSet(const LightSet& base, uint64_t step, const LoadOptions& options) {
    LightSet lights = base;
    if (lights.lights.empty()) return lights;
    Light& light = lights.lights.front();
    const float angle = 0.35f * float(step);  // about 20° of the circle per change
    if (light.type == LightType::Directional) {
        const float swing = glm::radians(options.turnDegrees) * std::sin(angle);
        const float c = std::cos(swing), s = std::sin(swing);
        const glm::vec3 d = light.direction;
        light.direction = glm::normalize(glm::vec3(c * d.x + s * d.z, d.y, -s * d.x + c * d.z));
    } else {
        light.position += options.moveMetres *
                          glm::vec3(std::cos(angle) - 1.0f, 0.0f, std::sin(angle));
    }
    return lights;
}

Result<nlohmann::ordered_json> runLoadTest(PicConnection& connection, const LoadOptions& options) {
    if (options.clients == 0) return fail(ErrorCode::InvalidInput, "--clients must be ≥ 1");
    if (!(options.durationSeconds > 0.0) || !(options.updateRate >= 0.0))
        return fail(ErrorCode::InvalidInput, "--duration must be > 0 and --update-rate ≥ 0, got {} and {}",
                    options.durationSeconds, options.updateRate);
    std::string session = options.session;
    std::string editor = options.editorToken;
    if (session.empty()) {
        PIC_TRY_ASSIGN(v1::CreateSessionResponse created, connection.createSession());
        session = created.session();
        editor = created.editor_token();
    }
    PIC_TRY_ASSIGN(v1::JoinSessionResponse joined, connection.joinSession(session, editor));
    if (options.updateRate > 0.0 && joined.role() != v1::EDITOR)
        return fail(ErrorCode::InvalidInput, "changing lights needs an editor token");
    PIC_TRY_ASSIGN(LightSet base, wire::fromProto(joined.lights()));
    PIC_TRY_ASSIGN(const v1::SceneHeader header, connection.sceneHeader(joined.bake_id()));
    if (options.updateRate > 0.0 && base.lights.empty())
        return fail(ErrorCode::InvalidInput,
                    "session {} has no light to move; set one first (picclient lights)", session);

    // Subscribers first, each holding its first (key) frame before the editor starts.
    std::mutex mutex;
    std::atomic<uint32_t> ready{0};
    std::vector<std::unique_ptr<FrameStream>> streams;
    std::vector<Received> received(options.clients);
    std::vector<std::thread> threads;
    for (uint32_t i = 0; i < options.clients; ++i) {
        streams.push_back(connection.subscribe(session, editor, connection.patience()));
        threads.emplace_back(subscribeLoop, std::ref(*streams.back()), std::cref(header),
                             std::ref(received[i]), std::ref(ready), std::ref(mutex));
    }
    const auto waitStart = Clock::now();
    while (ready.load() < options.clients && Clock::now() - waitStart < std::chrono::seconds(60))
        std::this_thread::sleep_for(std::chrono::milliseconds(5));

    std::map<uint64_t, Clock::time_point> sent;  // version → when the editor called
    std::vector<std::string> editorErrors;
    uint64_t lastVersion = joined.version();
    if (options.onChangesStart) options.onChangesStart();
    const auto start = Clock::now();
    if (options.updateRate > 0.0) {
        const auto period = std::chrono::duration<double>(1.0 / options.updateRate);
        for (uint64_t step = 1;; ++step) {
            const auto due = start + std::chrono::duration_cast<Clock::duration>(period * double(step - 1));
            if (due - start >= std::chrono::duration<double>(options.durationSeconds)) break;
            std::this_thread::sleep_until(due);
            const auto call = Clock::now();
            auto version = connection.setLights(session, editor, movedLightSet(base, step, options));
            if (!version) {
                editorErrors.push_back(version.error().message);
                continue;
            }
            sent[*version] = call;
            lastVersion = *version;
        }
    } else {
        std::this_thread::sleep_for(std::chrono::duration<double>(options.durationSeconds));
    }
    // Every subscriber must end up with the last version; give it time, then stop.
    const auto holdsLast = [&] {
        std::lock_guard lock(mutex);
        for (const Received& r : received)
            if (!holdsFinal(r, lastVersion)) return false;
        return true;
    };
    const auto drainStart = Clock::now();
    while (!holdsLast() && Clock::now() - drainStart < std::chrono::seconds(30))
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
    if (options.onChangesEnd) options.onChangesEnd();
    for (auto& stream : streams) stream->cancel();
    for (auto& thread : threads) thread.join();

    std::vector<double> latencies, firstChanges;
    std::map<uint64_t, std::pair<double, double>> serverMs;
    uint64_t frames = 0, skipped = 0, keyBytes = 0, keyFrames = 0, deltaBytes = 0, deltaFrames = 0;
    uint64_t partialFrames = 0;
    uint64_t missingLast = 0;
    std::vector<std::string> errors = editorErrors;
    for (const Received& r : received) {
        frames += r.versions.size();
        skipped += r.skipped;
        keyBytes += r.keyBytes;
        keyFrames += r.keyFrames;
        deltaBytes += r.deltaBytes;
        deltaFrames += r.deltaFrames;
        partialFrames += r.partialFrames;
        errors.insert(errors.end(), r.errors.begin(), r.errors.end());
        for (const auto& [version, ms] : r.serverMs)
            if (sent.contains(version)) serverMs[version] = ms;
        if (!holdsFinal(r, lastVersion)) ++missingLast;
        // Each version the editor set counts once per subscriber: the time until the
        // subscriber held its final state or any state of a newer version, and (the first
        // visible change) until it held any state of it or of a newer one.
        const auto ms = [](Clock::time_point when, Clock::time_point call) {
            return std::chrono::duration<double, std::milli>(when - call).count();
        };
        auto next = sent.begin(), nextSeen = sent.begin();
        for (const Held& held : r.versions) {
            for (; nextSeen != sent.end() && nextSeen->first <= held.version; ++nextSeen)
                firstChanges.push_back(ms(held.when, nextSeen->second));
            for (; next != sent.end() && (next->first < held.version ||
                                          (next->first == held.version && held.part == 0));
                 ++next)
                latencies.push_back(ms(held.when, next->second));
        }
    }
    if (missingLast > 0)
        errors.push_back(fmt::format("{} subscribers never received the last version {}",
                                     missingLast, lastVersion));

    nlohmann::ordered_json report;
    report["session"] = session;
    report["clients"] = options.clients;
    report["duration_s"] = elapsed;
    report["update_rate"] = options.updateRate;
    report["updates"] = sent.size();
    report["first_change_ms"] = {{"p50", percentile(firstChanges, 0.50)},
                                 {"p95", percentile(firstChanges, 0.95)},
                                 {"p99", percentile(firstChanges, 0.99)}};
    report["latency_ms"] = {{"p50", percentile(latencies, 0.50)},
                            {"p95", percentile(latencies, 0.95)},
                            {"p99", percentile(latencies, 0.99)},
                            {"max", latencies.empty() ? 0.0 : *std::max_element(latencies.begin(), latencies.end())},
                            {"mean", latencies.empty() ? 0.0 : std::accumulate(latencies.begin(), latencies.end(), 0.0) / double(latencies.size())},
                            {"samples", latencies.size()}};
    std::vector<double> updateMs, encodeMs;
    for (const auto& [version, ms] : serverMs) {
        updateMs.push_back(ms.first);
        encodeMs.push_back(ms.second);
    }
    // Where the latency goes: the server's own time per computed version (frames say it).
    report["server_ms"] = {{"update_p50", percentile(updateMs, 0.5)},
                           {"encode_p50", percentile(encodeMs, 0.5)},
                           {"versions_computed", serverMs.size()}};
    report["frames_received"] = frames;
    report["partial_frames"] = partialFrames;
    report["versions_skipped"] = skipped;
    report["bytes_per_frame"] = {{"key", keyFrames ? double(keyBytes) / double(keyFrames) : 0.0},
                                 {"delta", deltaFrames ? double(deltaBytes) / double(deltaFrames) : 0.0},
                                 {"key_frames", keyFrames},
                                 {"delta_frames", deltaFrames}};
    report["errors"] = errors.size();
    report["subscribers_without_last"] = missingLast;
    std::vector<std::string> shownErrors(errors.begin(), errors.begin() + std::min<size_t>(errors.size(), 10));
    report["error_messages"] = shownErrors;
    return report;
}

}  // namespace pic
