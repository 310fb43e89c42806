#include "server/web_server.h"

#include <algorithm>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>

#include <civetweb.h>

#include "server/civetweb_server.h"
#include "server/service_state.h"

namespace pic {

namespace {

/// WebSocket close codes 4000–4999 are the application's: 4000 + a gRPC status code.
constexpr int kCloseBase = 4000;

/// One browser's stream: authorised when the socket connects, fed by a sender thread of its
/// own from the session's latest-wins slot, so that a slow browser holds up nobody else.
struct WebStream {
    std::shared_ptr<PicServer::State> state;
    std::string sessionId;
    std::string peer;        ///< the connection's remote host
    std::string forwarded;   ///< its X-Forwarded-For header, empty without one
    std::string client;      ///< the host it counts against for the per-host quota
    Access access;
    bool counted = false;    ///< holds one of its host's streams

    mg_connection* connection = nullptr;
    std::shared_ptr<SubscriberSlot> slot;
    std::thread sender;
    std::mutex mutex;
    std::condition_variable changed;
    bool pending = false;  ///< the slot was put into, or the stream is to end
    bool stop = false;

    void wake() {
        {
            std::lock_guard lock(mutex);
            pending = true;
        }
        changed.notify_one();
    }

    /// Sends the close frame: code 4000 + `status`'s code, its message (clipped to the 123
    /// bytes a close reason may hold) as the reason.
    void close(const grpc::Status& status) const {
        std::string payload(2, '\0');
        const int code = kCloseBase + int(status.error_code());
        payload[0] = char((code >> 8) & 0xff);
        payload[1] = char(code & 0xff);
        payload += clipped(status.error_message(), 120);
        mg_websocket_write(connection, MG_WEBSOCKET_OPCODE_CONNECTION_CLOSE, payload.data(),
                           payload.size());
    }

    /// Writes the newest update whenever the last write is done, until the socket or the
    /// session ends.
    void send() {
        StateId held;
        for (;;) {
            {
                std::unique_lock lock(mutex);
                changed.wait(lock, [&] { return pending || stop; });
                if (stop) return;
                pending = false;
            }
            if (slot->closed()) {
                close(grpc::Status(grpc::StatusCode::UNAVAILABLE,
                                   fmt::format("session {} closed on this server (it moved, or "
                                               "the server is stopping); subscribe again",
                                               sessionId)));
                return;
            }
            const std::shared_ptr<const Update> update = slot->take();
            if (!update) continue;
            const std::shared_ptr<const v1::Frame> frame = update->frameFor(held);
            if (!frame) {
                close(grpc::Status(grpc::StatusCode::INTERNAL,
                                   fmt::format("no frame for version {} part {}", update->version,
                                               update->part)));
                return;
            }
            held = update->id();
            const std::string bytes = frame->SerializeAsString();
            if (mg_websocket_write(connection, MG_WEBSOCKET_OPCODE_BINARY, bytes.data(),
                                   bytes.size()) <= 0)
                return;  // the browser went
            uint64_t planes = 0;
            for (const v1::Plane& plane : frame->planes()) planes += plane.data().size();
            access.session->countSent(planes);
            state->metrics->recordSent(planes);
        }
    }
};

WebStream* streamOf(const mg_connection* connection) {
    return static_cast<WebStream*>(mg_get_user_connection_data(connection));
}

/// A query variable of the request, empty without it.
std::string queryVariable(const mg_request_info* request, const char* name) {
    if (!request->query_string) return {};
    const std::string query = request->query_string;
    std::string value(query.size() + 1, '\0');
    const int length = mg_get_var(query.data(), query.size(), name, value.data(), value.size());
    return length < 0 ? std::string() : value.substr(0, size_t(length));
}

/// The socket connects: who is it, and may it subscribe? Every socket is accepted, so that a
/// refusal can say why in its close frame (a refused handshake tells a browser nothing).
int onConnect(const mg_connection* connection, void* data) {
    auto* server = static_cast<std::shared_ptr<PicServer::State>*>(data);
    auto stream = std::make_unique<WebStream>();
    stream->state = *server;
    PicServer::State& state = *stream->state;
    const mg_request_info* request = mg_get_request_info(connection);
    stream->sessionId = queryVariable(request, "session");
    stream->peer = request->remote_addr;
    if (const char* forwarded = mg_get_header(connection, "X-Forwarded-For")) stream->forwarded = forwarded;
    stream->client = state.options.trustedProxies.clientHost(stream->peer, stream->forwarded);
    stream->access = authorise(state, stream->sessionId, queryVariable(request, "token"));
    mg_set_user_connection_data(connection, stream.release());
    return 0;
}

/// The handshake is done (from here on the close handler runs): the refusal's close frame,
/// or the session's frames from now on.
void onReady(mg_connection* connection, void*) {
    WebStream* stream = streamOf(connection);
    if (!stream) return;
    stream->connection = connection;
    PicServer::State& state = *stream->state;
    if (stream->access.status.ok()) {
        std::lock_guard lock(state.mutex);
        size_t& open = state.streamsByPeer[stream->client];
        if (open >= state.options.maxStreamsPerPeer) {
            stream->access.status = grpc::Status(
                grpc::StatusCode::RESOURCE_EXHAUSTED,
                fmt::format("{} holds {} streams, the most one peer may (--max-streams-per-peer)",
                            stream->client, open));
        } else {
            ++open;
            stream->counted = true;
        }
    }
    state.recordCall(stream->peer, stream->forwarded, "WebSubscribe",
                     roleName(stream->access.role), stream->sessionId, stream->access.status);
    if (!stream->access.status.ok()) {
        stream->close(stream->access.status);
        return;
    }
    stream->slot = stream->access.session->subscribe([stream] { stream->wake(); });
    stream->pending = true;  // the slot starts with the newest update
    stream->sender = std::thread([stream] { stream->send(); });
}

/// Nothing a browser sends is read; its close frame ends the connection.
int onData(mg_connection*, int bits, char*, size_t, void*) {
    return (bits & 0x0f) == MG_WEBSOCKET_OPCODE_CONNECTION_CLOSE ? 0 : 1;
}

/// The socket closed: the sender stops before the connection goes.
void onClose(const mg_connection* connection, void*) {
    std::unique_ptr<WebStream> stream(streamOf(connection));
    if (!stream) return;
    mg_set_user_connection_data(connection, nullptr);
    {
        std::lock_guard lock(stream->mutex);
        stream->stop = true;
    }
    stream->changed.notify_one();
    if (stream->sender.joinable()) stream->sender.join();
    if (stream->slot) stream->access.session->unsubscribe(stream->slot.get());
    if (stream->counted) {
        PicServer::State& state = *stream->state;
        std::lock_guard lock(state.mutex);
        if (auto it = state.streamsByPeer.find(stream->client);
            it != state.streamsByPeer.end() && --it->second == 0)
            state.streamsByPeer.erase(it);
    }
}

}  // namespace

Result<std::unique_ptr<WebServer>> WebServer::start(const std::string& listen,
                                                    std::shared_ptr<PicServer::State> state) {
    // civetweb gives every open WebSocket a thread of its own for the connection's life: as
    // many threads as one host may hold streams, plus a few for the handshakes.
    const std::string threads =
        std::to_string(std::min<size_t>(state->options.maxStreamsPerPeer, 1000) + 4);
    PIC_TRY_ASSIGN(CivetwebServer started,
                   startCivetweb("--web-listen", listen,
                                 {{"num_threads", threads}, {"websocket_timeout_ms", "3600000"}}));
    std::unique_ptr<WebServer> server(new WebServer());
    server->mState = std::move(state);
    server->mContext = started.context;
    server->mAddress = std::move(started.address);
    mg_set_websocket_handler(server->mContext, "/v1/stream$", onConnect, onReady, onData, onClose,
                             &server->mState);
    return server;
}

WebServer::~WebServer() {
    if (mContext) mg_stop(mContext);
}

}  // namespace pic
