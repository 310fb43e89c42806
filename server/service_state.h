#pragma once
/// What the server's transports share (internal to server/): the served bakes, the sessions,
/// the database, the metrics and the audit log, and who may do what in a session. The gRPC
/// service (server/service.cpp) and the browsers' endpoint (server/web_server.cpp) both
/// answer from it, so a browser meets the same tokens, quotas and sessions as picclient.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>

#include "proto/pic.pb.h"
#include "proto/wire.h"
#include "server/audit_log.h"
#include "server/limits.h"
#include "server/metrics.h"
#include "server/served_bake.h"
#include "server/service.h"
#include "server/session.h"
#include "server/session_store.h"
#include "server/token_digest.h"

namespace pic {

struct PicServer::State {
    std::vector<std::unique_ptr<ServedBake>> bakes;
    ServerOptions options;
    /// Computes every session's versions (declared before the sessions: they leave it first).
    std::unique_ptr<RelightPool> pool;
    mutable std::mutex mutex;
    std::map<std::string, std::shared_ptr<Session>> sessions;
    size_t creating = 0;  ///< sessions being written to the database, counted against the cap
    std::atomic<bool> stopping{false};
    std::condition_variable wake;     ///< notified when stopping or storeFailing is set
    std::random_device random;  ///< the OS's entropy (/dev/urandom): tokens must not be predictable
    std::unique_ptr<SessionStore> store;  ///< null without --db
    std::atomic<bool> storeFailing{false};  ///< the last database call failed: health NOT_SERVING
    std::mutex takeoverMutex;               ///< one session loaded from the database at a time
    grpc::HealthCheckServiceInterface* health = nullptr;
    std::shared_ptr<Metrics> metrics = std::make_shared<Metrics>();
    std::unique_ptr<AuditLog> audit;        ///< null without --audit-log
    std::map<std::string, size_t> streamsByPeer;  ///< open Subscribe streams per peer host (under mutex)

    /// The X-Forwarded-For header of a call, empty without one.
    static std::string_view forwardedFor(const grpc::CallbackServerContext& context) {
        auto it = context.client_metadata().find("x-forwarded-for");
        if (it == context.client_metadata().end()) return {};
        return std::string_view(it->second.data(), it->second.size());
    }

    /// The host a call counts against for per-peer quotas: its peer's, or behind a trusted
    /// load balancer the client's it forwarded.
    std::string clientHost(const grpc::CallbackServerContext& context) const {
        return options.trustedProxies.clientHost(context.peer(), forwardedFor(context));
    }

    /// The audit line of a call answered with `status` (server/audit_log.h).
    void recordCall(const grpc::CallbackServerContext& context, std::string_view call,
                    std::string_view credential, std::string_view session,
                    const grpc::Status& status) const {
        recordCall(context.peer(), forwardedFor(context), call, credential, session, status);
    }
    /// The same for a call of another transport (the browsers' WebSocket, server/web_server.h).
    void recordCall(std::string_view peer, std::string_view forwarded, std::string_view call,
                    std::string_view credential, std::string_view session,
                    const grpc::Status& status) const {
        metrics->recordCall(call, wire::statusName(status.error_code()));
        if (!audit) return;
        audit->record({std::string(peer), forwarded, call, credential, session,
                       wire::statusName(status.error_code()), status.error_message()});
    }

    /// `call()` on the database, timed and counted in the metrics as `op`.
    template <class Call>
    auto timedStore(const char* op, Call call) {
        const auto start = std::chrono::steady_clock::now();
        auto result = call(*store);
        metrics->recordStore(
            op, std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count(),
            !result);
        return result;
    }

    /// The bake `id` names, or the first one when `id` is empty.
    ServedBake* findBake(const std::string& id) const {
        if (id.empty()) return bakes.front().get();
        for (const auto& bake : bakes)
            if (bake->id() == id) return bake.get();
        return nullptr;
    }

    std::shared_ptr<Session> findSession(const std::string& id) const {
        std::lock_guard lock(mutex);
        auto it = sessions.find(id);
        return it == sessions.end() ? nullptr : it->second;
    }

    /// `words` × 32 random bits as hex (under `mutex`). Never a seeded generator: a viewer who
    /// could recover its state from its own token could derive the editor token.
    std::string randomHex(int words) {
        std::string hex;
        for (int i = 0; i < words; ++i) hex += fmt::format("{:08x}", uint32_t(random()));
        return hex;
    }

    /// Whether the server can take one more session (under `mutex`).
    bool hasRoom() const { return sessions.size() + creating < options.maxSessions; }

    /// The database failed: health says NOT_SERVING until housekeeping reaches it again
    /// (woken now to ask it every second). Not under `mutex`.
    grpc::Status storeFailed(const Error& error) {
        bool first = false;
        {
            std::lock_guard lock(mutex);
            first = !storeFailing.exchange(true);
        }
        wake.notify_all();
        if (first) {
            std::fprintf(stderr, "picserver: %s (health NOT_SERVING until it answers again)\n",
                         error.message.c_str());
            if (health) health->SetServingStatus(false);
        }
        return grpc::Status(grpc::StatusCode::UNAVAILABLE,
                            fmt::format("the session database failed: {}", error.message));
    }

    /// Housekeeping reached the database again.
    void storeRecovered() {
        if (!storeFailing.exchange(false)) return;
        std::fprintf(stderr, "picserver: %s answers again; health SERVING\n",
                     store->describe().c_str());
        if (health && !stopping) health->SetServingStatus(true);
    }

    /// Drops `session` from this server (its streams end UNAVAILABLE): another server holds a
    /// newer version of it.
    void evict(const std::shared_ptr<Session>& session) {
        {
            std::lock_guard lock(mutex);
            auto it = sessions.find(session->id());
            if (it != sessions.end() && it->second == session) sessions.erase(it);
        }
        session->close();
        metrics->forgetSession(session->id());
        std::fprintf(stderr, "picserver: session %s moved to another server\n",
                     session->id().c_str());
    }

    /// What `session` is in the database at `version` with `lights` and `presets`.
    static StoredSession row(const Session& session, uint64_t version, LightSet lights,
                             LightPresets presets) {
        return {session.id(), session.editorDigest(), session.viewerDigest(), session.bake().id(),
                version,      std::move(lights),      std::move(presets)};
    }

    /// Why this server cannot carry `stored` on (bake not served, light set or a preset
    /// refused by the scene), or empty.
    std::string unusable(const StoredSession& stored) const {
        const ServedBake* bake = findBake(stored.bakeId);
        if (!bake || stored.bakeId.empty())
            return fmt::format("its bake {} is not served here", stored.bakeId);
        if (auto checked = bake->checkLights(stored.lights); !checked)
            return checked.error().message;
        for (const auto& [name, lights] : stored.presets)
            if (auto checked = bake->checkLights(lights); !checked)
                return fmt::format("preset \"{}\": {}", name, checked.error().message);
        return {};
    }

    /// Session `id` from the database, when it is not on this server (a replica that went
    /// away held it, or the server restarted): claims it by writing the version after the
    /// stored one, so that a server still holding an older copy learns at its next write that
    /// the session moved.
    /// Only a caller holding one of its tokens (`digest`) has it loaded.
    grpc::Status takeOver(const std::string& id, const std::string& digest,
                          std::shared_ptr<Session>& out) {
        const grpc::Status notFound(grpc::StatusCode::NOT_FOUND, fmt::format("no session \"{}\"", clipped(id)));
        // Ids of another form were never drawn: not worth a database query.
        if (!store || !wire::isSessionId(id)) return notFound;
        std::lock_guard loading(takeoverMutex);
        for (int attempt = 0; attempt < 3; ++attempt) {
            if ((out = findSession(id))) return grpc::Status::OK;
            auto found = timedStore("find", [&](SessionStore& db) { return db.find(id); });
            if (!found) return storeFailed(found.error());
            if (!*found) return notFound;
            StoredSession stored = std::move(**found);
            if (!sameDigest(digest, stored.editorDigest) && !sameDigest(digest, stored.viewerDigest))
                return grpc::Status(grpc::StatusCode::UNAUTHENTICATED,
                                    fmt::format("the token is not one of session \"{}\"", clipped(id)));
            if (const std::string why = unusable(stored); !why.empty())
                return grpc::Status(grpc::StatusCode::FAILED_PRECONDITION,
                                    fmt::format("session \"{}\" cannot be served here: {}", id, why));
            {
                std::lock_guard lock(mutex);
                if (!hasRoom())
                    return grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED,
                                        fmt::format("the server holds its maximum of {} sessions",
                                                    options.maxSessions));
                ++creating;
            }
            const uint64_t version = stored.version + 1;
            stored.version = version;
            auto claimed = timedStore("save", [&](SessionStore& db) { return db.save(stored); });
            if (!claimed || !*claimed) {
                {
                    std::lock_guard lock(mutex);
                    --creating;
                }
                if (!claimed) return storeFailed(claimed.error());
                continue;  // another server claimed it first: read it again
            }
            std::lock_guard lock(mutex);
            --creating;
            if (auto it = sessions.find(id); it != sessions.end()) {  // restored meanwhile
                out = it->second;
                return grpc::Status::OK;
            }
            out = std::make_shared<Session>(
                id, stored.editorDigest, stored.viewerDigest, *findBake(stored.bakeId), *pool,
                options.session,
                SessionStart{version, std::move(stored.lights), std::move(stored.presets)});
            sessions[id] = out;
            std::fprintf(stderr, "picserver: session %s taken over from the database at version %llu\n",
                         id.c_str(), (unsigned long long)version);
            return grpc::Status::OK;
        }
        return grpc::Status(grpc::StatusCode::UNAVAILABLE,
                            fmt::format("session \"{}\" is moving between servers; retry", clipped(id)));
    }
};

/// The session `id` and the role `token` grants in it, or the status to fail with.
struct Access {
    std::shared_ptr<Session> session;
    v1::Role role = v1::ROLE_UNSPECIFIED;
    grpc::Status status;
};

inline Access authorise(PicServer::State& state, const std::string& id, const std::string& token) {
    Access access;
    if (state.stopping) {
        access.status = grpc::Status(grpc::StatusCode::UNAVAILABLE, "the server is shutting down");
        return access;
    }
    const std::string digest = tokenDigest(token);
    access.session = state.findSession(id);
    if (!access.session) {
        access.status = state.takeOver(id, digest, access.session);
        if (!access.status.ok()) return access;
    }
    if (sameDigest(digest, access.session->editorDigest()))
        access.role = v1::EDITOR;
    else if (sameDigest(digest, access.session->viewerDigest()))
        access.role = v1::VIEWER;
    else
        access.status = grpc::Status(grpc::StatusCode::UNAUTHENTICATED,
                                     fmt::format("the token is not one of session \"{}\"", clipped(id)));
    return access;
}

inline const char* roleName(v1::Role role) {
    return role == v1::EDITOR ? "editor" : role == v1::VIEWER ? "viewer" : "none";
}

/// How a light set sent to a session went.
struct SetLightsOutcome {
    grpc::Status status;
    uint64_t version = 0;  ///< the set's version, when status is OK
    /// When status is RESOURCE_EXHAUSTED by the session's rate limit: how long to wait.
    std::chrono::milliseconds retryAfter{0};
};

/// SetLights for both transports: an editor's light set (else PERMISSION_DENIED) for the
/// session `access` admitted, at most SessionOptions::setLightsPerSecond of them with the
/// preset changes (RESOURCE_EXHAUSTED with the wait), `parse`d only once the rate limit let it through
/// (its error's status), checked against the scene (INVALID_ARGUMENT), committed to the
/// database before it returns, then queued. UNAVAILABLE when the session moved to another
/// server (evicted here; the set was not applied) or closed while it was set, or the
/// database failed. `access.status` must be OK.
SetLightsOutcome setLights(PicServer::State& state, const Access& access,
                           const std::function<Result<LightSet>()>& parse);

/// How a change of a session's presets went.
struct PresetsOutcome {
    grpc::Status status;
    std::vector<std::string> names;  ///< the presets' names after it, when status is OK
    /// When status is RESOURCE_EXHAUSTED by the session's rate limit: how long to wait.
    std::chrono::milliseconds retryAfter{0};
};

/// Creates or replaces preset `name` for both transports: an editor's (else
/// PERMISSION_DENIED) light set for the session `access` admitted, `parse`d (its error's
/// status), checked as SetLights checks a set (INVALID_ARGUMENT, as for a name checkPresetName
/// refuses), at most kMaxPresets of them (RESOURCE_EXHAUSTED), counted against the session's
/// rate of light sets (RESOURCE_EXHAUSTED with the wait), committed to the database
/// before it returns. UNAVAILABLE when the session moved to another server (evicted here;
/// nothing changed) or closed meanwhile, or the database failed. `access.status` must be OK.
PresetsOutcome setPreset(PicServer::State& state, const Access& access, const std::string& name,
                         const std::function<Result<LightSet>()>& parse);

/// Deletes preset `name` (NOT_FOUND naming it when there is none), an editor's call, committed
/// and refused as setPreset.
PresetsOutcome removePreset(PicServer::State& state, const Access& access, const std::string& name);

}  // namespace pic
