#include "server/service.h"

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstdio>
#include <chrono>
#include <random>

#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>

#include "proto/pic.grpc.pb.h"
#include "proto/wire.h"
#include "server/session_store.h"
#include "server/token_digest.h"

namespace pic {

struct PicServer::State {
    std::vector<std::unique_ptr<ServedBake>> bakes;
    ServerOptions options;
    mutable std::mutex mutex;
    std::map<std::string, std::shared_ptr<Session>> sessions;
    std::atomic<bool> stopping{false};
    std::condition_variable wake;     ///< notified (under mutex) when stopping or dirty is set
    bool dirty = false;               ///< sessions changed since the database was written
    std::random_device random;  ///< the OS's entropy (/dev/urandom): tokens must not be predictable
    std::unique_ptr<SessionStore> store;  ///< null without --db
    std::mutex persistMutex;              ///< snapshots are written in the order they are taken

    /// Asks the housekeeping thread to write the database soon: handlers never wait for a disk.
    void markDirty() {
        if (!store) return;
        {
            std::lock_guard lock(mutex);
            dirty = true;
        }
        wake.notify_all();
    }

    /// Writes every session to the database (when there is one); a failure is logged, not
    /// fatal: the sessions go on, only not durably.
    void saveNow() {
        if (!store) return;
        std::lock_guard persisting(persistMutex);
        std::vector<StoredSession> snapshot;
        {
            std::lock_guard lock(mutex);
            for (const auto& [id, session] : sessions)
                snapshot.push_back({id, session->editorDigest(), session->viewerDigest(),
                                    session->bake().id(), session->latestVersion(),
                                    session->latestLights()});
        }
        if (auto saved = store->save(snapshot); !saved)
            std::fprintf(stderr, "picserver: %s\n", saved.error().message.c_str());
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
};

namespace {

/// Compares token digests in time independent of where they differ.
bool sameDigest(const std::string& a, const std::string& b) {
    if (a.size() != b.size()) return false;
    unsigned char diff = 0;
    for (size_t i = 0; i < a.size(); ++i) diff |= (unsigned char)(a[i] ^ b[i]);
    return diff == 0;
}

/// The session `id` and the role `token` grants in it, or the status to fail with.
struct Access {
    std::shared_ptr<Session> session;
    v1::Role role = v1::ROLE_UNSPECIFIED;
    grpc::Status status;
};

Access authorise(const PicServer::State& state, const std::string& id, const std::string& token) {
    Access access;
    if (state.stopping) {
        access.status = grpc::Status(grpc::StatusCode::UNAVAILABLE, "the server is shutting down");
        return access;
    }
    access.session = state.findSession(id);
    if (!access.session) {
        access.status = grpc::Status(grpc::StatusCode::NOT_FOUND,
                                     fmt::format("no session \"{}\"", id));
        return access;
    }
    const std::string digest = tokenDigest(token);
    if (sameDigest(digest, access.session->editorDigest()))
        access.role = v1::EDITOR;
    else if (sameDigest(digest, access.session->viewerDigest()))
        access.role = v1::VIEWER;
    else
        access.status = grpc::Status(grpc::StatusCode::UNAUTHENTICATED,
                                     fmt::format("the token is not one of session \"{}\"", id));
    return access;
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
    explicit FrameWriter(std::shared_ptr<Session> session) : mSession(std::move(session)) {
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
        std::shared_ptr<const Update> update = mSlot->take();
        if (!update) return;
        std::shared_ptr<const v1::Frame> frame = update->frameFor(mHeld);
        if (!frame) {
            finishOnce(grpc::Status(grpc::StatusCode::INTERNAL,
                                    fmt::format("no frame for version {}", update->version)));
            return;
        }
        mHeld = update->version;
        uint64_t bytes = 0;
        for (const v1::Plane& plane : frame->planes()) bytes += plane.data().size();
        mSession->countSent(bytes);
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
    std::shared_ptr<Link> mLink;
    std::shared_ptr<SubscriberSlot> mSlot;
    std::shared_ptr<const v1::Frame> mInFlight;  ///< alive until its write is done
    uint64_t mHeld = 0;                          ///< version the client holds
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
        for (const auto& bake : mState->bakes) *response->add_bakes() = bake->summary();
        response->set_backend(mState->bakes.front()->device().empty() ? "cpu" : "gpu");
        response->set_device(mState->bakes.front()->device());
        return finish(context, grpc::Status::OK);
    }

    grpc::ServerWriteReactor<v1::SceneChunk>* GetScene(grpc::CallbackServerContext*,
                                                       const v1::GetSceneRequest* request) override {
        const ServedBake* bake = mState->findBake(request->bake_id());
        if (!bake)
            return new grpc::internal::FinishOnlyReactor<grpc::ServerWriteReactor<v1::SceneChunk>>(
                grpc::Status(grpc::StatusCode::NOT_FOUND,
                             fmt::format("no bake \"{}\"", request->bake_id())));
        return new SceneWriter(*bake, request->header_only());
    }

    grpc::ServerUnaryReactor* CreateSession(grpc::CallbackServerContext* context,
                                            const v1::CreateSessionRequest* request,
                                            v1::CreateSessionResponse* response) override {
        if (mState->stopping)
            return finish(context, grpc::Status(grpc::StatusCode::UNAVAILABLE,
                                                "the server is shutting down"));
        ServedBake* bake = mState->findBake(request->bake_id());
        if (!bake)
            return finish(context, grpc::Status(grpc::StatusCode::NOT_FOUND,
                                                fmt::format("no bake \"{}\"", request->bake_id())));
        std::shared_ptr<Session> session;
        std::string editorToken, viewerToken;
        {
            std::lock_guard lock(mState->mutex);
            if (mState->sessions.size() >= mState->options.maxSessions)
                return finish(context,
                              grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED,
                                           fmt::format("the server holds its maximum of {} sessions",
                                                       mState->options.maxSessions)));
            std::string id = mState->randomHex(2);
            while (mState->sessions.contains(id)) id = mState->randomHex(2);
            editorToken = mState->randomHex(4);
            viewerToken = mState->randomHex(4);
            session =
                std::make_shared<Session>(id, tokenDigest(editorToken), tokenDigest(viewerToken),
                                          *bake, mState->options.session);
            mState->sessions[id] = session;
        }
        mState->markDirty();
        // The only time the tokens leave the server; it keeps their digests.
        response->set_session(session->id());
        response->set_editor_token(editorToken);
        response->set_viewer_token(viewerToken);
        response->set_bake_id(bake->id());
        response->set_version(session->latestVersion());
        return finish(context, grpc::Status::OK);
    }

    grpc::ServerUnaryReactor* JoinSession(grpc::CallbackServerContext* context,
                                          const v1::JoinSessionRequest* request,
                                          v1::JoinSessionResponse* response) override {
        Access access = authorise(*mState, request->session(), request->token());
        if (!access.status.ok()) return finish(context, access.status);
        access.session->touch();
        response->set_role(access.role);
        response->set_bake_id(access.session->bake().id());
        response->set_version(access.session->latestVersion());
        *response->mutable_lights() = wire::toProto(access.session->latestLights());
        return finish(context, grpc::Status::OK);
    }

    grpc::ServerUnaryReactor* SetLights(grpc::CallbackServerContext* context,
                                        const v1::SetLightsRequest* request,
                                        v1::SetLightsResponse* response) override {
        Access access = authorise(*mState, request->session(), request->token());
        if (!access.status.ok()) return finish(context, access.status);
        if (access.role != v1::EDITOR)
            return finish(context, grpc::Status(grpc::StatusCode::PERMISSION_DENIED,
                                                "only an editor token may set lights"));
        auto lights = wire::fromProto(request->lights());
        if (!lights) return finish(context, wire::toStatus(lights.error()));
        auto version = access.session->setLights(std::move(*lights));
        if (!version) return finish(context, wire::toStatus(version.error()));
        mState->markDirty();
        response->set_version(*version);
        return finish(context, grpc::Status::OK);
    }

    grpc::ServerWriteReactor<v1::Frame>* Subscribe(grpc::CallbackServerContext*,
                                                   const v1::SubscribeRequest* request) override {
        Access access = authorise(*mState, request->session(), request->token());
        if (!access.status.ok())
            return new grpc::internal::FinishOnlyReactor<grpc::ServerWriteReactor<v1::Frame>>(
                access.status);
        return new FrameWriter(std::move(access.session));
    }

    grpc::ServerUnaryReactor* GetStats(grpc::CallbackServerContext* context,
                                       const v1::GetStatsRequest* request,
                                       v1::SessionStats* response) override {
        Access access = authorise(*mState, request->session(), request->token());
        if (!access.status.ok()) return finish(context, access.status);
        *response = access.session->stats();
        return finish(context, grpc::Status::OK);
    }

private:
    static grpc::ServerUnaryReactor* finish(grpc::CallbackServerContext* context,
                                            grpc::Status status) {
        grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
        reactor->Finish(std::move(status));
        return reactor;
    }

    std::shared_ptr<PicServer::State> mState;
};

/// The server's background work until it stops: removes sessions without subscribers that
/// nobody used for options.sessionIdle (checking a few times per idle period), and writes the
/// session database when sessions changed (at most once per wake, and once more at the end).
void housekeeping(PicServer::State& state) {
    const auto idle = state.options.sessionIdle;
    const auto period = std::clamp<std::chrono::steady_clock::duration>(
        idle / 4, std::chrono::milliseconds(10), std::chrono::seconds(30));
    std::unique_lock lock(state.mutex);
    for (;;) {
        state.wake.wait_for(lock, period, [&] { return state.stopping.load() || state.dirty; });
        std::vector<std::shared_ptr<Session>> expired;
        for (auto it = state.sessions.begin(); it != state.sessions.end();) {
            if (it->second->subscribers() == 0 && it->second->idleFor() > idle) {
                expired.push_back(std::move(it->second));
                it = state.sessions.erase(it);
            } else {
                ++it;
            }
        }
        const bool save = state.dirty || !expired.empty();
        state.dirty = false;
        const bool stopping = state.stopping;
        // Stopping a session joins its worker, and saving reads every session: neither under
        // the lock the handlers need.
        lock.unlock();
        for (const auto& session : expired)
            std::fprintf(stderr, "picserver: session %s removed after %.1f s unused\n",
                         session->id().c_str(),
                         std::chrono::duration<double>(session->idleFor()).count());
        expired.clear();
        if (save) state.saveNow();
        if (stopping) return;
        lock.lock();
    }
}

}  // namespace

Result<std::unique_ptr<PicServer>> PicServer::start(std::vector<std::unique_ptr<ServedBake>> bakes,
                                                    const std::string& listen,
                                                    ServerOptions options) {
    if (bakes.empty()) return fail(ErrorCode::InvalidInput, "the server needs at least one bake");
    const size_t colon = listen.rfind(':');
    if (colon == std::string::npos || colon == 0 || colon + 1 == listen.size())
        return fail(ErrorCode::InvalidInput, "--listen must be HOST:PORT, got \"{}\"", listen);

    std::unique_ptr<PicServer> server(new PicServer());
    server->mState = std::make_shared<State>();
    server->mState->bakes = std::move(bakes);
    server->mState->options = options;
    server->mService = std::make_unique<Service>(server->mState);
    if (!options.dbPath.empty()) {
        State& state = *server->mState;
        PIC_TRY(SessionStore::checkPath(options.dbPath));
        state.store = std::make_unique<SessionStore>(options.dbPath);
        PIC_TRY_ASSIGN(std::vector<StoredSession> stored, state.store->load());
        for (StoredSession& entry : stored) {
            ServedBake* bake = state.findBake(entry.bakeId);
            if (!bake || entry.bakeId.empty()) {
                std::fprintf(stderr, "picserver: session %s dropped: its bake %s is not served\n",
                             entry.id.c_str(), entry.bakeId.c_str());
                continue;
            }
            if (auto checked = checkRuntimeLights(entry.lights, bake->scene()); !checked) {
                std::fprintf(stderr, "picserver: session %s dropped: %s\n", entry.id.c_str(),
                             checked.error().message.c_str());
                continue;
            }
            SessionStart start{entry.version + 1, std::move(entry.lights)};
            state.sessions[entry.id] =
                std::make_shared<Session>(entry.id, entry.editorDigest, entry.viewerDigest, *bake,
                                          options.session, std::move(start));
        }
        if (!stored.empty())
            std::fprintf(stderr, "picserver: %zu of %zu sessions restored from %s\n",
                         state.sessions.size(), stored.size(), options.dbPath.c_str());
        state.saveNow();
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
    // Scene assets go in 1 MiB chunks, but key frames of large bakes can be bigger.
    builder.SetMaxSendMessageSize(-1);
    server->mServer = builder.BuildAndStart();
    if (!server->mServer || port == 0)
        return fail(ErrorCode::InvalidInput, "cannot listen on \"{}\" (address in use or invalid)",
                    listen);
    server->mAddress = fmt::format("{}:{}", listen.substr(0, colon), port);
    if (auto* health = server->mServer->GetHealthCheckService())
        health->SetServingStatus(true);
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
    {
        std::lock_guard stateLock(mState->mutex);
        mState->stopping = true;
    }
    mState->wake.notify_all();
    if (mReaper.joinable()) mReaper.join();
    if (auto* health = mServer->GetHealthCheckService()) health->SetServingStatus(false);
    // Streams never end on their own: cancel them after a short grace period.
    mServer->Shutdown(std::chrono::system_clock::now() + std::chrono::milliseconds(200));
    mServer->Wait();
    std::map<std::string, std::shared_ptr<Session>> sessions;
    {
        std::lock_guard stateLock(mState->mutex);
        sessions.swap(mState->sessions);
    }
    sessions.clear();  // joins each session's worker
}

std::shared_ptr<Session> PicServer::session(const std::string& id) const {
    return mState->findSession(id);
}

}  // namespace pic
