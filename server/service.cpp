#include "server/service.h"

#include <algorithm>
#include <cstdio>
#include <chrono>

#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>

#include "proto/pic.grpc.pb.h"
#include "proto/wire.h"
#include "server/metrics_http.h"
#include "server/relight_pool.h"
#include "server/service_state.h"
#include "server/web_server.h"

namespace pic {

namespace {

/// Whether the caller of operator call `call` (CreateSession, ListBakes, GetScene) presented
/// one of the server's API keys; `credential` says who it is: the key's id, "anonymous" on a
/// server without keys, "none" when refused (UNAUTHENTICATED).
grpc::Status operatorAccess(const PicServer::State& state, const grpc::CallbackServerContext& context,
                            std::string_view call, std::string& credential) {
    credential = "none";
    if (state.options.apiKeys.empty()) {
        credential = "anonymous";
        return grpc::Status::OK;
    }
    const auto& metadata = context.client_metadata();
    const auto it = metadata.find(wire::kAuthorizationMetadata);
    if (it == metadata.end())
        return grpc::Status(grpc::StatusCode::UNAUTHENTICATED,
                            fmt::format("{} needs an operator API key (picclient --api-key KEY or "
                                        "PIC_API_KEY)",
                                        call));
    const auto key = bearerKey(std::string_view(it->second.data(), it->second.size()));
    if (!key)
        return grpc::Status(grpc::StatusCode::UNAUTHENTICATED,
                            "the authorization metadata must be \"Bearer KEY\"");
    const auto id = state.options.apiKeys.find(*key);
    if (!id)
        return grpc::Status(grpc::StatusCode::UNAUTHENTICATED,
                            "the API key is not one of this server's");
    credential = *id;
    return grpc::Status::OK;
}

/// GetScene: the header, then the assets' bytes in chunks, one write at a time.
class SceneWriter final : public grpc::ServerWriteReactor<v1::SceneChunk> {
public:
    SceneWriter(const ServedBake& bake, bool headerOnly) : mBake(bake), mHeaderOnly(headerOnly) {
        *mChunk.mutable_header() = bake.header();
        StartWrite(&mChunk);
    }

    void OnWriteDone(bool ok) override {
        if (!ok) return Finish(grpc::Status(grpc::StatusCode::CANCELLED, "write failed"));
        if (mHeaderOnly) return Finish(grpc::Status::OK);
        const auto& assets = mBake.assetBytes();
        std::string data;
        while (data.size() < kSceneChunkBytes && mAsset < assets.size()) {
            const std::string& bytes = assets[mAsset];
            const size_t n = std::min(kSceneChunkBytes - data.size(), bytes.size() - mOffset);
            data.append(bytes, mOffset, n);
            mOffset += n;
            if (mOffset == bytes.size()) {
                ++mAsset;
                mOffset = 0;
            }
        }
        if (data.empty()) return Finish(grpc::Status::OK);
        mChunk.set_data(std::move(data));
        StartWrite(&mChunk);
    }

    void OnDone() override { delete this; }

private:
    const ServedBake& mBake;
    const bool mHeaderOnly;
    v1::SceneChunk mChunk;
    size_t mAsset = 0;
    size_t mOffset = 0;
};

/// Subscribe: takes the newest update from its latest-wins slot whenever no write is in
/// flight, so a slow client skips versions and holds at most one frame in the server.
class FrameWriter final : public grpc::ServerWriteReactor<v1::Frame> {
public:
    /// `onDone` runs once the stream is over.
    FrameWriter(std::shared_ptr<Session> session, std::shared_ptr<Metrics> metrics,
                std::function<void()> onDone)
        : mSession(std::move(session)), mMetrics(std::move(metrics)), mOnDone(std::move(onDone)) {
        // The slot may wake after this reactor is gone (a publish that copied the slot list
        // before unsubscribe); the link tells it so.
        mLink = std::make_shared<Link>();
        mLink->writer = this;
        auto slot = mSession->subscribe([link = mLink] {
            std::lock_guard lock(link->mutex);
            if (link->writer) link->writer->pump();
        });
        // A publish may wake the link before this runs; pump() waits for the slot.
        std::lock_guard lock(mLink->mutex);
        mSlot = std::move(slot);
        pump();
    }

    void OnWriteDone(bool ok) override {
        {
            std::lock_guard lock(mLink->mutex);
            mInFlight.reset();
            mWriting = false;
            if (!ok || mCancelled) {
                finishOnce(grpc::Status(grpc::StatusCode::CANCELLED, "the stream ended"));
                return;
            }
            pump();
        }
    }

    void OnCancel() override {
        std::lock_guard lock(mLink->mutex);
        mCancelled = true;
        if (!mWriting) finishOnce(grpc::Status(grpc::StatusCode::CANCELLED, "cancelled"));
    }

    void OnDone() override {
        {
            std::lock_guard lock(mLink->mutex);
            mLink->writer = nullptr;
        }
        mSession->unsubscribe(mSlot.get());
        if (mOnDone) mOnDone();
        delete this;
    }

private:
    struct Link {
        /// Recursive: should gRPC run OnWriteDone inline from StartWrite (it may when a write
        /// completes at once), the reaction re-enters under the same lock on the same thread.
        std::recursive_mutex mutex;
        FrameWriter* writer = nullptr;
    };

    /// Starts the next write if none is in flight (under the link's lock). Everything the
    /// write's reaction reads is set before StartWrite.
    void pump() {
        if (!mSlot || mWriting || mCancelled || mFinished) return;
        if (mSlot->closed()) {
            finishOnce(grpc::Status(grpc::StatusCode::UNAVAILABLE,
                                    fmt::format("session {} closed on this server (it moved, or "
                                                "the server is stopping); subscribe again",
                                                mSession->id())));
            return;
        }
        std::shared_ptr<const Update> update = mSlot->take();
        if (!update) return;
        std::shared_ptr<const v1::Frame> frame = update->frameFor(mHeld);
        if (!frame) {
            finishOnce(grpc::Status(grpc::StatusCode::INTERNAL,
                                    fmt::format("no frame for version {} part {}",
                                                update->version, update->part)));
            return;
        }
        mHeld = update->id();
        uint64_t bytes = 0;
        for (const v1::Plane& plane : frame->planes()) bytes += plane.data().size();
        mSession->countSent(bytes);
        mMetrics->recordSent(bytes);
        mInFlight = std::move(frame);
        mWriting = true;
        StartWrite(mInFlight.get());
    }

    void finishOnce(grpc::Status status) {
        if (mFinished) return;
        mFinished = true;
        Finish(std::move(status));
    }

    std::shared_ptr<Session> mSession;
    std::shared_ptr<Metrics> mMetrics;
    std::function<void()> mOnDone;
    std::shared_ptr<Link> mLink;
    std::shared_ptr<SubscriberSlot> mSlot;
    std::shared_ptr<const v1::Frame> mInFlight;  ///< alive until its write is done
    StateId mHeld;                               ///< the state the client holds
    bool mWriting = false;
    bool mCancelled = false;
    bool mFinished = false;
};

class Service final : public v1::Pic::CallbackService {
public:
    explicit Service(std::shared_ptr<PicServer::State> state) : mState(std::move(state)) {}

    grpc::ServerUnaryReactor* ListBakes(grpc::CallbackServerContext* context,
                                        const v1::ListBakesRequest*,
                                        v1::ListBakesResponse* response) override {
        Call call{"ListBakes"};
        if (auto denied = operatorAccess(*mState, *context, call.name, call.credential); !denied.ok())
            return finish(context, call, denied);
        for (const auto& bake : mState->bakes) *response->add_bakes() = bake->summary();
        response->set_backend(mState->bakes.front()->device().empty() ? "cpu" : "gpu");
        response->set_device(mState->bakes.front()->device());
        return finish(context, call, grpc::Status::OK);
    }

    grpc::ServerWriteReactor<v1::SceneChunk>* GetScene(grpc::CallbackServerContext* context,
                                                       const v1::GetSceneRequest* request) override {
        using Refusal = grpc::internal::FinishOnlyReactor<grpc::ServerWriteReactor<v1::SceneChunk>>;
        std::string credential;
        grpc::Status status = operatorAccess(*mState, *context, "GetScene", credential);
        const ServedBake* bake = status.ok() ? mState->findBake(request->bake_id()) : nullptr;
        if (status.ok() && !bake)
            status = grpc::Status(grpc::StatusCode::NOT_FOUND,
                                  fmt::format("no bake \"{}\"", clipped(request->bake_id())));
        mState->recordCall(*context, "GetScene", credential, "", status);
        if (!status.ok()) return new Refusal(status);
        return new SceneWriter(*bake, request->header_only());
    }

    grpc::ServerUnaryReactor* CreateSession(grpc::CallbackServerContext* context,
                                            const v1::CreateSessionRequest* request,
                                            v1::CreateSessionResponse* response) override {
        Call call{"CreateSession"};
        call.session = request->session();
        if (auto denied = operatorAccess(*mState, *context, call.name, call.credential); !denied.ok())
            return finish(context, call, denied);
        // Whom the session counts against: the key, or without keys the peer's host.
        const std::string creator = mState->options.apiKeys.empty()
                                        ? "peer " + mState->clientHost(*context)
                                        : call.credential;
        if (mState->stopping)
            return finish(context, call, grpc::Status(grpc::StatusCode::UNAVAILABLE,
                                                "the server is shutting down"));
        ServedBake* bake = mState->findBake(request->bake_id());
        if (!bake)
            return finish(context, call, grpc::Status(grpc::StatusCode::NOT_FOUND,
                                                fmt::format("no bake \"{}\"", clipped(request->bake_id()))));
        // An id the client drew (behind a load balancer: the one it routed by), else ours.
        const std::string& wanted = request->session();
        if (!wanted.empty() && !wire::isSessionId(wanted))
            return finish(context, call, grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                                                fmt::format("session \"{}\" is not 16 lowercase "
                                                            "hex digits",
                                                            clipped(wanted))));
        const grpc::Status taken(grpc::StatusCode::ALREADY_EXISTS,
                                 fmt::format("session \"{}\" exists already", wanted));
        {
            std::lock_guard lock(mState->mutex);
            if (!wanted.empty() && mState->sessions.contains(wanted)) return finish(context, call, taken);
            if (!mState->hasRoom())
                return finish(context, call,
                              grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED,
                                           fmt::format("the server holds its maximum of {} sessions",
                                                       mState->options.maxSessions)));
            if (const size_t most = mState->options.maxSessionsPerClient; most > 0) {
                const size_t held = size_t(std::ranges::count_if(
                    mState->sessions, [&](const auto& entry) { return entry.second->creator() == creator; }));
                if (held >= most)
                    return finish(context, call,
                                  grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED,
                                               fmt::format("{} holds {} sessions, the most one client may "
                                                           "(--max-sessions-per-client)",
                                                           creator, held)));
            }
            ++mState->creating;
        }
        // The session is in the database before anyone hears of it; an id of ours that
        // another server's session holds is drawn again.
        std::string id, editorToken, viewerToken;
        grpc::Status status(grpc::StatusCode::UNAVAILABLE, "no free session id");
        for (int attempt = 0; attempt < 4 && !status.ok(); ++attempt) {
            {
                std::lock_guard lock(mState->mutex);
                if (wanted.empty()) {
                    do id = mState->randomHex(2);
                    while (mState->sessions.contains(id));
                } else {
                    id = wanted;
                }
                editorToken = mState->randomHex(4);
                viewerToken = mState->randomHex(4);
            }
            if (!mState->store) {
                status = grpc::Status::OK;
                break;
            }
            const StoredSession row{id, tokenDigest(editorToken), tokenDigest(viewerToken),
                                    bake->id(), 1, defaultLightSet(bake->scene())};
            auto created = mState->timedStore("create", [&](SessionStore& db) { return db.create(row); });
            if (!created) {
                status = mState->storeFailed(created.error());
                break;
            }
            if (*created) {
                status = grpc::Status::OK;
            } else if (!wanted.empty()) {  // the client's id is another server's session
                status = taken;
                break;
            }
        }
        std::shared_ptr<Session> session;
        {
            std::lock_guard lock(mState->mutex);
            --mState->creating;
            if (status.ok() && mState->sessions.contains(id)) status = taken;  // raced for it
            if (status.ok()) {
                session = std::make_shared<Session>(id, tokenDigest(editorToken),
                                                    tokenDigest(viewerToken), *bake,
                                                    *mState->pool, mState->options.session,
                                                    SessionStart{.creator = creator});
                mState->sessions[id] = session;
            }
        }
        if (!status.ok()) return finish(context, call, status);
        // The only time the tokens leave the server; it keeps their digests.
        call.session = session->id();
        response->set_session(session->id());
        response->set_editor_token(editorToken);
        response->set_viewer_token(viewerToken);
        response->set_bake_id(bake->id());
        response->set_version(session->latestVersion());
        return finish(context, call, grpc::Status::OK);
    }

    grpc::ServerUnaryReactor* JoinSession(grpc::CallbackServerContext* context,
                                          const v1::JoinSessionRequest* request,
                                          v1::JoinSessionResponse* response) override {
        Access access = authorise(*mState, request->session(), request->token());
        const Call call{"JoinSession", roleName(access.role), request->session()};
        if (!access.status.ok()) return finish(context, call, access.status);
        access.session->touch();
        response->set_role(access.role);
        response->set_bake_id(access.session->bake().id());
        response->set_version(access.session->latestVersion());
        *response->mutable_lights() = wire::toProto(access.session->latestLights());
        return finish(context, call, grpc::Status::OK);
    }

    grpc::ServerUnaryReactor* SetLights(grpc::CallbackServerContext* context,
                                        const v1::SetLightsRequest* request,
                                        v1::SetLightsResponse* response) override {
        Access access = authorise(*mState, request->session(), request->token());
        const Call call{"SetLights", roleName(access.role), request->session()};
        if (!access.status.ok()) return finish(context, call, access.status);
        const SetLightsOutcome outcome =
            setLights(*mState, access, [&] { return wire::fromProto(request->lights()); });
        // The delay goes in the trailing metadata too, for clients that wait and retry.
        if (outcome.retryAfter.count() > 0)
            context->AddTrailingMetadata(wire::kRetryAfterMetadata,
                                         std::to_string(outcome.retryAfter.count()));
        if (outcome.status.ok()) response->set_version(outcome.version);
        return finish(context, call, outcome.status);
    }

    grpc::ServerWriteReactor<v1::Frame>* Subscribe(grpc::CallbackServerContext* context,
                                                   const v1::SubscribeRequest* request) override {
        Access access = authorise(*mState, request->session(), request->token());
        const std::string peer = mState->clientHost(*context);
        if (access.status.ok()) {
            std::lock_guard lock(mState->mutex);
            size_t& open = mState->streamsByPeer[peer];
            if (open >= mState->options.maxStreamsPerPeer)
                access.status = grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED,
                                             fmt::format("{} holds {} streams, the most one peer may "
                                                         "(--max-streams-per-peer)",
                                                         peer, open));
            else
                ++open;
        }
        mState->recordCall(*context, "Subscribe", roleName(access.role), request->session(),
                           access.status);
        if (!access.status.ok())
            return new grpc::internal::FinishOnlyReactor<grpc::ServerWriteReactor<v1::Frame>>(
                access.status);
        return new FrameWriter(std::move(access.session), mState->metrics, [state = mState, peer] {
            std::lock_guard lock(state->mutex);
            if (auto it = state->streamsByPeer.find(peer); it != state->streamsByPeer.end() && --it->second == 0)
                state->streamsByPeer.erase(it);
        });
    }

    grpc::ServerUnaryReactor* GetStats(grpc::CallbackServerContext* context,
                                       const v1::GetStatsRequest* request,
                                       v1::SessionStats* response) override {
        Access access = authorise(*mState, request->session(), request->token());
        const Call call{"GetStats", roleName(access.role), request->session()};
        if (!access.status.ok()) return finish(context, call, access.status);
        *response = access.session->stats();
        return finish(context, call, grpc::Status::OK);
    }

private:
    /// What the audit log says of a unary call.
    struct Call {
        const char* name;
        std::string credential = "none";
        std::string session;
    };

    grpc::ServerUnaryReactor* finish(grpc::CallbackServerContext* context, const Call& call,
                                     grpc::Status status) {
        mState->recordCall(*context, call.name, call.credential, call.session, status);
        grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
        reactor->Finish(std::move(status));
        return reactor;
    }

    std::shared_ptr<PicServer::State> mState;
};

/// The server's background work until it stops: removes sessions without subscribers that
/// nobody used for options.sessionIdle (checking a few times per idle period) from the server
/// and the database, and while the database fails, asks it every second whether it answers.
void housekeeping(PicServer::State& state) {
    const auto idle = state.options.sessionIdle;
    const auto period = std::clamp<std::chrono::steady_clock::duration>(
        idle / 4, std::chrono::milliseconds(10), std::chrono::seconds(30));
    std::unique_lock lock(state.mutex);
    for (;;) {
        if (state.storeFailing)
            state.wake.wait_for(lock, std::chrono::seconds(1), [&] { return state.stopping.load(); });
        else
            state.wake.wait_for(lock, period,
                                [&] { return state.stopping || state.storeFailing; });
        if (state.stopping) return;
        std::vector<std::shared_ptr<Session>> expired;
        for (auto it = state.sessions.begin(); it != state.sessions.end();) {
            if (it->second->subscribers() == 0 && it->second->idleFor() > idle) {
                expired.push_back(std::move(it->second));
                it = state.sessions.erase(it);
            } else {
                ++it;
            }
        }
        // Stopping a session joins its worker, and the database may be slow: neither under
        // the lock the handlers need.
        lock.unlock();
        if (state.store && state.storeFailing) {
            if (state.timedStore("ping", [](SessionStore& db) { return db.ping(); }))
                state.storeRecovered();
        }
        for (const auto& session : expired) {
            std::fprintf(stderr, "picserver: session %s removed after %.1f s unused\n",
                         session->id().c_str(),
                         std::chrono::duration<double>(session->idleFor()).count());
            session->close();
            state.metrics->forgetSession(session->id());
            // Unless another server has taken it over since (a newer version).
            if (state.store)
                if (auto removed = state.timedStore("remove", [&](SessionStore& db) {
                        return db.remove(session->id(), session->latestVersion());
                    });
                    !removed)
                    state.storeFailed(removed.error());
        }
        expired.clear();
        lock.lock();
    }
}

/// The sessions of a database no other server uses (SQLite), up to the server's cap, the
/// newest first; says what it left in the database and why. A session left there
/// is loaded when a client asks for it and the server can carry it.
Result<void> restore(PicServer::State& state) {
    PIC_TRY_ASSIGN(std::vector<StoredSession> stored, state.store->loadAll());
    size_t restored = 0;
    size_t overCap = 0;
    std::vector<std::string> refused;
    // loadAll gives the oldest first: the newest get the room.
    for (auto it = stored.rbegin(); it != stored.rend(); ++it) {
        StoredSession& entry = *it;
        if (const std::string why = state.unusable(entry); !why.empty()) {
            refused.push_back(fmt::format("session {}: {}", entry.id, why));
            continue;
        }
        std::lock_guard lock(state.mutex);
        if (state.sessions.contains(entry.id)) {  // a client asked for it first
            ++restored;
            continue;
        }
        if (!state.hasRoom()) {
            ++overCap;
            continue;
        }
        state.sessions[entry.id] = std::make_shared<Session>(
            entry.id, entry.editorDigest, entry.viewerDigest, *state.findBake(entry.bakeId),
            *state.pool, state.options.session,
            SessionStart{entry.version + 1, std::move(entry.lights), std::move(entry.presets)});
        ++restored;
    }
    if (stored.empty()) return {};
    std::fprintf(stderr, "picserver: %zu of %zu sessions restored from %s\n", restored,
                 stored.size(), state.store->describe().c_str());
    if (overCap > 0)
        std::fprintf(stderr,
                     "picserver: %zu sessions left in the database: the server holds at most %zu "
                     "(--max-sessions); each is loaded when a client asks for it and there is room\n",
                     overCap, state.options.maxSessions);
    for (const std::string& why : refused)
        std::fprintf(stderr, "picserver: %s; it stays in the database, not served\n", why.c_str());
    return {};
}

}  // namespace

Result<std::unique_ptr<PicServer>> PicServer::start(std::vector<std::unique_ptr<ServedBake>> bakes,
                                                    const std::string& listen,
                                                    ServerOptions options) {
    if (bakes.empty()) return fail(ErrorCode::InvalidInput, "the server needs at least one bake");
    const size_t colon = listen.rfind(':');
    if (colon == std::string::npos || colon == 0 || colon + 1 == listen.size())
        return fail(ErrorCode::InvalidInput, "--listen must be HOST:PORT, got \"{}\"", listen);

    PIC_TRY(checkOpenListen(listen, !options.apiKeys.empty(), options.allowUnauthenticated));

    std::unique_ptr<PicServer> server(new PicServer());
    server->mState = std::make_shared<State>();
    if (!options.auditLog.empty()) {
        PIC_TRY_ASSIGN(server->mState->audit, AuditLog::open(options.auditLog));
    }
    server->mState->bakes = std::move(bakes);
    server->mState->pool = std::make_unique<RelightPool>(
        options.relightThreads > 0 ? options.relightThreads : unsigned(server->mState->bakes.size() + 1));
    // Every computed version goes into the metrics (a budgeted one's earlier parts count in
    // the bytes sent only), then every version and part to the caller's log.
    options.session.log = [metrics = server->mState->metrics,
                           log = std::move(options.session.log)](const UpdateLog& entry) {
        const Update& update = *entry.update;
        if (update.part == 0) {
            uint64_t bytes = 0;
            for (const v1::Plane& plane : update.broadcast->planes()) bytes += plane.data().size();
            metrics->recordUpdate(entry.session, update.stats.passMs, update.broadcast->update_ms(),
                                  update.encodeMs, bytes, update.base.version == 0);
        }
        if (log) log(entry);
    };
    server->mState->options = options;
    server->mState->metrics->setGauges([state = server->mState.get()] {
        Metrics::Gauges gauges;
        std::lock_guard lock(state->mutex);
        gauges.sessions = state->sessions.size();
        for (const auto& [id, session] : state->sessions) {
            const v1::SessionStats stats = session->stats();
            gauges.subscribers += stats.subscribers();
            gauges.versionsSkipped += stats.versions_skipped();
        }
        gauges.storeFailing = state->storeFailing;
        gauges.relightThreads = state->pool->threads();
        gauges.relightQueued = state->pool->queued();
        return gauges;
    });
    if (!options.metricsListen.empty()) {
        PIC_TRY_ASSIGN(server->mMetricsServer,
                       MetricsServer::start(options.metricsListen, *server->mState->metrics));
    }
    server->mService = std::make_unique<Service>(server->mState);
    if (!options.dbPath.empty()) {
        State& state = *server->mState;
        PIC_TRY_ASSIGN(state.store, SessionStore::open(options.dbPath));
    }

    grpc::EnableDefaultHealthCheckService(true);
    grpc::reflection::InitProtoReflectionServerBuilderPlugin();
    grpc::ServerBuilder builder;
    int port = 0;
    if (options.tlsCertPem.empty() != options.tlsKeyPem.empty())
        return fail(ErrorCode::InvalidInput, "TLS needs both a certificate and its key");
    std::shared_ptr<grpc::ServerCredentials> credentials = grpc::InsecureServerCredentials();
    if (!options.tlsCertPem.empty()) {
        grpc::SslServerCredentialsOptions ssl;
        ssl.pem_key_cert_pairs.push_back({options.tlsKeyPem, options.tlsCertPem});
        credentials = grpc::SslServerCredentials(ssl);
    }
    builder.AddListeningPort(listen, credentials, &port);
    builder.RegisterService(server->mService.get());
    // Requests are light sets and ids; replies are scene chunks of 1 MiB and key frames.
    builder.SetMaxReceiveMessageSize(int(wire::kMaxRequestBytes));
    builder.SetMaxSendMessageSize(int(wire::kMaxReplyBytes));
    const auto clampMs = [](std::chrono::milliseconds ms) { return int(std::min<int64_t>(ms.count(), INT32_MAX)); };
    if (options.keepalive.count() < 1000)
        return fail(ErrorCode::InvalidInput, "keepalive must be at least 1 s, got {} ms", options.keepalive.count());
    builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_TIME_MS, clampMs(options.keepalive));
    builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, std::min(clampMs(options.keepalive), 20000));
    builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, 1);
    builder.AddChannelArgument(GRPC_ARG_HTTP2_MAX_PINGS_WITHOUT_DATA, 0);
    // Clients may ping once a second (picclient --keepalive 1); more often counts as abuse.
    builder.AddChannelArgument(GRPC_ARG_HTTP2_MIN_RECV_PING_INTERVAL_WITHOUT_DATA_MS, 1000);
    if (options.maxConnectionAge.count() > 0)
        builder.AddChannelArgument(GRPC_ARG_MAX_CONNECTION_AGE_MS, clampMs(options.maxConnectionAge));
    server->mServer = builder.BuildAndStart();
    if (!server->mServer || port == 0)
        return fail(ErrorCode::InvalidInput, "cannot listen on \"{}\" (address in use or invalid)",
                    listen);
    server->mAddress = fmt::format("{}:{}", listen.substr(0, colon), port);
    server->mState->health = server->mServer->GetHealthCheckService();
    if (server->mState->health) server->mState->health->SetServingStatus(true);
    if (!options.webListen.empty()) {
        PIC_TRY_ASSIGN(server->mWebServer, WebServer::start(options.webListen, server->mState));
    }
    if (options.onListening) options.onListening(server->mAddress);
    // Sessions come back once the server listens; a request for one before is served by
    // loading it from the database, and restore() passes over it.
    if (State& state = *server->mState; state.store) {
        if (state.store->shared())
            std::fprintf(stderr,
                         "picserver: sessions in %s: each is taken over from it on its first "
                         "request here\n",
                         state.store->describe().c_str());
        else
            PIC_TRY(restore(state));
    }
    server->mReaper = std::thread([state = server->mState] { housekeeping(*state); });
    return server;
}

PicServer::~PicServer() {
    shutdown();
}

void PicServer::wait() {
    if (mServer) mServer->Wait();
}

void PicServer::shutdown() {
    std::lock_guard lock(mShutdownMutex);
    if (mShutDown || !mServer) return;
    mShutDown = true;
    // Drain: health NOT_SERVING and no new calls, every session closed at once (its streams
    // end UNAVAILABLE so clients go to another server; a version not yet computed is
    // abandoned: whoever takes the session over computes it), then gRPC stops.
    std::map<std::string, std::shared_ptr<Session>> sessions;
    {
        std::lock_guard stateLock(mState->mutex);
        mState->stopping = true;
        sessions.swap(mState->sessions);
    }
    if (mState->health) mState->health->SetServingStatus(false);
    mState->wake.notify_all();
    for (const auto& [id, session] : sessions) session->close();
    if (mReaper.joinable()) mReaper.join();
    mServer->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(2));
    mServer->Wait();
    sessions.clear();  // joins each session's worker: at most the computation under way
    mWebServer.reset();  // its streams ended with their sessions (4014)
    mMetricsServer.reset();
}

std::string PicServer::webAddress() const { return mWebServer ? mWebServer->address() : std::string(); }

std::shared_ptr<Session> PicServer::session(const std::string& id) const {
    return mState->findSession(id);
}

}  // namespace pic
