#include "server/web_server.h"

#include <algorithm>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <mutex>
#include <string_view>
#include <thread>
#include <utility>
#include <vector>

#include <civetweb.h>
#include <nlohmann/json.hpp>

#include "core/light_set.h"
#include "embedded/pic_proto_text.h"
#include "embedded/sh_basis_text.h"
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

/// An HTTP reply: `status`, the body's type and length, `headers`, then `body` (none for a
/// HEAD request).
void reply(mg_connection* connection, int status, const char* contentType, std::string_view body,
           const std::vector<std::pair<const char*, std::string>>& headers = {}) {
    mg_response_header_start(connection, status);
    mg_response_header_add(connection, "Content-Type", contentType, -1);
    const std::string length = std::to_string(body.size());
    mg_response_header_add(connection, "Content-Length", length.c_str(), -1);
    for (const auto& [name, value] : headers)
        mg_response_header_add(connection, name, value.c_str(), int(value.size()));
    mg_response_header_send(connection);
    if (std::string_view(mg_get_request_info(connection)->request_method) != "HEAD" &&
        !body.empty())
        mg_write(connection, body.data(), body.size());
}

/// The HTTP status of a refusal with gRPC code `code`.
int httpStatusOf(grpc::StatusCode code) {
    switch (code) {
    case grpc::StatusCode::INVALID_ARGUMENT: return 400;
    case grpc::StatusCode::UNAUTHENTICATED: return 401;
    case grpc::StatusCode::PERMISSION_DENIED: return 403;
    case grpc::StatusCode::NOT_FOUND: return 404;
    case grpc::StatusCode::RESOURCE_EXHAUSTED: return 429;
    case grpc::StatusCode::UNAVAILABLE: return 503;
    default: return 500;
    }
}

/// Answers a refusal: {"error": message, "code": code name} with `httpStatus`, and with the
/// wait rounded up to whole seconds as Retry-After when there is one.
int refuse(mg_connection* connection, const grpc::Status& status, int httpStatus,
           std::chrono::milliseconds retryAfter = std::chrono::milliseconds(0)) {
    const nlohmann::json body = {{"error", status.error_message()},
                                 {"code", wire::statusName(status.error_code())}};
    std::vector<std::pair<const char*, std::string>> headers = {{"Cache-Control", "no-store"}};
    if (retryAfter.count() > 0)
        headers.push_back({"Retry-After", std::to_string((retryAfter.count() + 999) / 1000)});
    reply(connection, httpStatus, "application/json",
          body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), headers);
    return httpStatus;
}

int refuse(mg_connection* connection, const grpc::Status& status,
           std::chrono::milliseconds retryAfter = std::chrono::milliseconds(0)) {
    return refuse(connection, status, httpStatusOf(status.error_code()), retryAfter);
}

/// Refuses a request whose method the route does not take (405, naming those it takes).
int wrongMethod(mg_connection* connection, const char* allowed) {
    const nlohmann::json body = {
        {"error", fmt::format("{} takes only {}", mg_get_request_info(connection)->local_uri,
                              allowed)},
        {"code", wire::statusName(grpc::StatusCode::UNIMPLEMENTED)}};
    reply(connection, 405, "application/json", body.dump(), {{"Allow", allowed}});
    return 405;
}

/// A session route's request: who sent it and for which session, or why it cannot be one.
struct SessionRequest {
    std::string sessionId;
    std::string token;
    std::string peer;       ///< the connection's remote host
    std::string forwarded;  ///< its X-Forwarded-For header, empty without one
    grpc::Status status;    ///< INVALID_ARGUMENT without a session or token
};

SessionRequest sessionRequestOf(const mg_connection* connection) {
    const mg_request_info* request = mg_get_request_info(connection);
    SessionRequest out;
    out.sessionId = queryVariable(request, "session");
    out.token = queryVariable(request, "token");
    out.peer = request->remote_addr;
    if (const char* forwarded = mg_get_header(connection, "X-Forwarded-For"))
        out.forwarded = forwarded;
    if (out.sessionId.empty())
        out.status = grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                                  "the query needs the parameter session=ID");
    else if (out.token.empty())
        out.status = grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                                  "the query needs the parameter token=T");
    return out;
}

/// The session and role `request` names, or its refusal (the request's own first).
Access authoriseRequest(PicServer::State& state, const SessionRequest& request) {
    if (!request.status.ok()) {
        Access refused;
        refused.status = request.status;
        return refused;
    }
    return authorise(state, request.sessionId, request.token);
}

/// GET /v1/scene?session=ID&token=T: the session's bake as server/web_scene.h lays it out.
int serveScene(mg_connection* connection, void* data) {
    if (std::string_view(mg_get_request_info(connection)->request_method) != "GET")
        return wrongMethod(connection, "GET");
    PicServer::State& state = **static_cast<std::shared_ptr<PicServer::State>*>(data);
    const SessionRequest request = sessionRequestOf(connection);
    Access access = authoriseRequest(state, request);
    const Result<std::string>* scene = nullptr;
    if (access.status.ok()) {
        access.session->touch();
        scene = &access.session->bake().webScene();
        // The bake's fault, not the request's: INTERNAL whatever the error.
        if (!*scene)
            access.status = grpc::Status(grpc::StatusCode::INTERNAL,
                                         fmt::format("the scene of bake {} cannot be sent: {}",
                                                     access.session->bake().id(),
                                                     scene->error().message));
    }
    state.recordCall(request.peer, request.forwarded, "WebScene", roleName(access.role),
                     request.sessionId, access.status);
    if (!access.status.ok()) return refuse(connection, access.status);
    // The bake's id names the bytes: a browser that holds them asks with If-None-Match.
    const std::string etag = "\"" + access.session->bake().id() + "\"";
    std::vector<std::pair<const char*, std::string>> headers = {
        {"Cache-Control", "private, max-age=3600"}, {"ETag", etag}};
    if (const char* held = mg_get_header(connection, "If-None-Match"); held && etag == held) {
        mg_response_header_start(connection, 304);
        for (const auto& [name, value] : headers)
            mg_response_header_add(connection, name, value.c_str(), int(value.size()));
        mg_response_header_send(connection);
        return 304;
    }
    reply(connection, 200, "application/octet-stream", **scene, headers);
    return 200;
}

/// Reads the request's body into `body`, up to one byte more than a request may hold (as
/// gRPC's largest message); whether it holds more.
bool readBody(mg_connection* connection, std::string& body) {
    if (mg_get_request_info(connection)->content_length > int64_t(wire::kMaxRequestBytes))
        return true;
    char buffer[16384];
    for (int n; (n = mg_read(connection, buffer, sizeof buffer)) > 0;) {
        body.append(buffer, size_t(n));
        if (body.size() > wire::kMaxRequestBytes) return true;
    }
    return false;
}

/// The refusal of a body over wire::kMaxRequestBytes (answered 413).
grpc::Status tooLargeStatus() {
    return grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED,
                        fmt::format("a light set takes at most {} bytes", wire::kMaxRequestBytes));
}

/// A light set as a JSON object: its toJson form.
nlohmann::json lightsJson(const LightSet& lights) {
    return nlohmann::json::parse(toJson(lights));
}

/// Every preset as {"name", "lights"}, in name order.
nlohmann::json presetsJson(const LightPresets& presets) {
    nlohmann::json list = nlohmann::json::array();
    for (const auto& [name, lights] : presets)
        list.push_back({{"name", name}, {"lights", lightsJson(lights)}});
    return list;
}

/// A 200 reply of `body` as JSON, not to be cached.
int replyJson(mg_connection* connection, const nlohmann::json& body) {
    reply(connection, 200, "application/json",
          body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace),
          {{"Cache-Control", "no-store"}});
    return 200;
}

/// GET /v1/session?session=ID&token=T: what a browser shows of the session, for any token:
/// its role, bake, newest version and light set, and its presets.
int serveSession(mg_connection* connection, void* data) {
    if (std::string_view(mg_get_request_info(connection)->request_method) != "GET")
        return wrongMethod(connection, "GET");
    PicServer::State& state = **static_cast<std::shared_ptr<PicServer::State>*>(data);
    const SessionRequest request = sessionRequestOf(connection);
    Access access = authoriseRequest(state, request);
    state.recordCall(request.peer, request.forwarded, "WebSession", roleName(access.role),
                     request.sessionId, access.status);
    if (!access.status.ok()) return refuse(connection, access.status);
    const Session& session = *access.session;
    access.session->touch();
    const auto [version, lights] = session.latest();
    return replyJson(connection, {{"session", session.id()},
                                  {"role", roleName(access.role)},
                                  {"bake_id", session.bake().id()},
                                  {"version", version},
                                  {"lights", lightsJson(lights)},
                                  {"presets", presetsJson(session.presets())}});
}

/// /v1/presets?session=ID&token=T: GET, any token: {"presets": [{"name", "lights"}]}; PUT
/// &name=N with a light set's JSON, or DELETE &name=N, editor token: saves or deletes the
/// preset, answering {"presets": [names]}.
int servePresets(mg_connection* connection, void* data) {
    const mg_request_info* info = mg_get_request_info(connection);
    const std::string_view method = info->request_method;
    if (method != "GET" && method != "PUT" && method != "DELETE")
        return wrongMethod(connection, "GET, PUT, DELETE");
    PicServer::State& state = **static_cast<std::shared_ptr<PicServer::State>*>(data);
    const SessionRequest request = sessionRequestOf(connection);
    const std::string name = queryVariable(info, "name");
    std::string body;
    const bool tooLarge = method == "PUT" && readBody(connection, body);
    Access access;
    grpc::Status status = request.status;
    bool refusedTooLarge = false;
    if (status.ok() && method != "GET" && name.empty()) {
        status = grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                              "the query needs the parameter name=N");
    } else if (status.ok() && tooLarge) {
        status = tooLargeStatus();
        refusedTooLarge = true;
    }
    nlohmann::json answer;
    std::chrono::milliseconds retryAfter{0};
    if (status.ok()) {
        access = authorise(state, request.sessionId, request.token);
        status = access.status;
    }
    if (status.ok() && method == "GET") {
        access.session->touch();
        answer = {{"presets", presetsJson(access.session->presets())}};
    } else if (status.ok()) {
        const PresetsOutcome outcome =
            method == "PUT" ? setPreset(state, access, name, [&] { return parseLightSet(body); })
                            : removePreset(state, access, name);
        status = outcome.status;
        retryAfter = outcome.retryAfter;
        answer = {{"presets", outcome.names}};
    }
    state.recordCall(request.peer, request.forwarded, "WebPresets", roleName(access.role),
                     request.sessionId, status);
    if (refusedTooLarge) return refuse(connection, status, 413);
    if (!status.ok()) return refuse(connection, status, retryAfter);
    return replyJson(connection, answer);
}

/// POST /v1/lights?session=ID&token=T with a light set's JSON: the gRPC SetLights.
int serveLights(mg_connection* connection, void* data) {
    const mg_request_info* info = mg_get_request_info(connection);
    if (std::string_view(info->request_method) != "POST") return wrongMethod(connection, "POST");
    PicServer::State& state = **static_cast<std::shared_ptr<PicServer::State>*>(data);
    const SessionRequest request = sessionRequestOf(connection);
    std::string body;
    const bool tooLarge = readBody(connection, body);
    Access access;
    SetLightsOutcome outcome;
    if (!request.status.ok()) {
        outcome.status = request.status;
    } else if (tooLarge) {
        outcome.status = tooLargeStatus();
    } else {
        access = authorise(state, request.sessionId, request.token);
        outcome.status = access.status;
        if (access.status.ok())
            outcome = setLights(state, access, [&] { return parseLightSet(body); });
    }
    state.recordCall(request.peer, request.forwarded, "WebSetLights", roleName(access.role),
                     request.sessionId, outcome.status);
    if (tooLarge && request.status.ok()) return refuse(connection, outcome.status, 413);
    if (!outcome.status.ok()) return refuse(connection, outcome.status, outcome.retryAfter);
    return replyJson(connection, {{"version", outcome.version}});
}

/// GET of a text built into the server (`text` is the handler's data): /v1/pic.proto, the
/// API's wire contract; /v1/sh_basis.glsl, the shaders' SH basis for the browser's shaders.
int serveText(mg_connection* connection, void* text) {
    const std::string_view method = mg_get_request_info(connection)->request_method;
    if (method != "GET" && method != "HEAD") return wrongMethod(connection, "GET, HEAD");
    reply(connection, 200, "text/plain; charset=utf-8", *static_cast<const std::string_view*>(text),
          {{"Cache-Control", "no-cache"}});
    return 200;
}

/// The Content-Type of a page's file, by its extension.
const char* contentTypeOf(const std::filesystem::path& file) {
    static const std::pair<std::string_view, const char*> kTypes[] = {
        {".html", "text/html; charset=utf-8"},
        {".js", "text/javascript; charset=utf-8"},
        {".mjs", "text/javascript; charset=utf-8"},
        {".css", "text/css; charset=utf-8"},
        {".json", "application/json"},
        {".map", "application/json"},
        {".png", "image/png"},
        {".svg", "image/svg+xml"},
        {".wasm", "application/wasm"},
        {".proto", "text/plain; charset=utf-8"},
    };
    const std::string extension = file.extension().string();
    for (const auto& [known, type] : kTypes)
        if (extension == known) return type;
    return "application/octet-stream";
}

/// Whether `file` lies inside `root` (both canonical).
bool inside(const std::filesystem::path& root, const std::filesystem::path& file) {
    auto r = root.begin(), f = file.begin();
    for (; r != root.end(); ++r, ++f)
        if (f == file.end() || *r != *f) return false;
    return f != file.end();
}

/// GET /PATH: the web root's regular file there ("/": index.html), resolved with its links;
/// 404 for anything else, and for a file whose real place is outside the root.
int serveFile(mg_connection* connection, void* data) {
    namespace fs = std::filesystem;
    const mg_request_info* request = mg_get_request_info(connection);
    const std::string_view method = request->request_method;
    if (method != "GET" && method != "HEAD") return wrongMethod(connection, "GET, HEAD");
    const std::string& root = *static_cast<const std::string*>(data);
    // civetweb has decoded the path's %XX escapes and removed its dot segments already; the
    // file's canonical path decides whatever remains.
    std::string path = request->local_uri ? request->local_uri : "/";
    if (path.ends_with('/')) path += "index.html";
    const auto notFound = [&] {
        reply(connection, 404, "text/plain; charset=utf-8", "no such page\n",
              {{"Cache-Control", "no-cache"}});
        return 404;
    };
    if (root.empty() || path.find('\0') != std::string::npos) return notFound();
    std::error_code error;
    const fs::path file = fs::canonical(fs::path(root) / fs::path(path).relative_path(), error);
    if (error || !inside(fs::path(root), file) || !fs::is_regular_file(file, error))
        return notFound();
    std::ifstream in(file, std::ios::binary);
    const std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    if (!in.good() && !in.eof()) return notFound();
    reply(connection, 200, contentTypeOf(file), bytes,
          {{"Cache-Control", "no-cache"}, {"X-Content-Type-Options", "nosniff"}});
    return 200;
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
    // many threads as one host may hold streams, plus a few for the handshakes and the HTTP
    // requests. A page's files come over one kept-alive connection (every reply says its
    // length).
    const std::string threads =
        std::to_string(std::min<size_t>(state->options.maxStreamsPerPeer, 1000) + 4);
    PIC_TRY_ASSIGN(CivetwebServer started,
                   startCivetweb("--web-listen", listen,
                                 {{"num_threads", threads},
                                  {"websocket_timeout_ms", "3600000"},
                                  {"enable_keep_alive", "yes"}}));
    std::unique_ptr<WebServer> server(new WebServer());
    server->mState = std::move(state);
    server->mContext = started.context;
    server->mAddress = std::move(started.address);
    const std::string& webRoot = server->mState->options.webRoot;
    std::error_code error;
    if (std::filesystem::is_directory(webRoot, error))
        server->mWebRoot = std::filesystem::canonical(webRoot, error).string();
    if (server->mWebRoot.empty())
        std::fprintf(stderr,
                     "picserver: --web-root %s is not a folder: browsers get 404 for pages\n",
                     webRoot.c_str());
    mg_set_websocket_handler(server->mContext, "/v1/stream$", onConnect, onReady, onData, onClose,
                             &server->mState);
    mg_set_request_handler(server->mContext, "/v1/scene$", serveScene, &server->mState);
    mg_set_request_handler(server->mContext, "/v1/lights$", serveLights, &server->mState);
    mg_set_request_handler(server->mContext, "/v1/session$", serveSession, &server->mState);
    mg_set_request_handler(server->mContext, "/v1/presets$", servePresets, &server->mState);
    static const std::string_view proto = kPicProtoText, shBasis = kShBasisText;
    mg_set_request_handler(server->mContext, "/v1/pic.proto$", serveText,
                           const_cast<std::string_view*>(&proto));
    mg_set_request_handler(server->mContext, "/v1/sh_basis.glsl$", serveText,
                           const_cast<std::string_view*>(&shBasis));
    // Last: every other path is a page.
    mg_set_request_handler(server->mContext, "/", serveFile, &server->mWebRoot);
    return server;
}

std::string defaultWebRoot() { return PIC_WEB_ROOT; }

WebServer::~WebServer() {
    if (mContext) mg_stop(mContext);
}

}  // namespace pic
