#pragma once
/// The browsers' endpoint (`picserver --web-listen HOST:PORT`), on civetweb (Debian's
/// libcivetweb). Browsers cannot make gRPC's streaming calls and gRPC-Web needs a proxy Debian
/// does not ship, so picserver speaks to them itself:
///
///     ws://HOST:PORT/v1/stream?session=ID&token=T
///
/// Every binary message the server sends is one v1::Frame serialised as on the gRPC stream:
/// the same frames, encoded once per version for every subscriber of either transport, with
/// the same latest-wins delivery (a browser that falls behind skips to the newest state and
/// gets its key frame) and a key frame first on every new connection. Tokens, sessions, the
/// database's take-over, per-host stream quotas, metrics and the audit log are the gRPC
/// service's (server/service_state.h). A refusal or the end of the stream closes the socket
/// with code 4000 + the gRPC status code and its message as the reason: 4016 for a token
/// that is not the session's, 4005 for no such session, 4014 when the server stops or the
/// session moved (subscribe again), 4008 over the per-host stream quota.
///
/// Beside the stream, over HTTP:
///
///     GET  /v1/scene?session=ID&token=T    the session's scene (server/web_scene.h), any token
///     POST /v1/lights?session=ID&token=T   a light set (core/light_set.h JSON), editor token:
///                                          the gRPC SetLights, answering {"version": N}
///     GET  /v1/session?session=ID&token=T  any token: {"session", "role", "bake_id",
///                                          "version", "lights", "presets"}, the newest
///                                          version and its light set as a JSON object
///     GET  /v1/presets?session=ID&token=T  any token: {"presets": [{"name", "lights"}]}, in
///                                          name order
///     PUT  /v1/presets?...&name=N          a light set, editor token: saves preset N
///                                          (server/service_state.h setPreset), answering
///                                          {"presets": [names]}
///     DELETE /v1/presets?...&name=N        editor token: deletes preset N, the same answer
///     GET  /v1/pic.proto                   proto/pic.proto's text, no token
///     GET  /PATH                           ServerOptions::webRoot's regular files ("/":
///                                          index.html); none outside it, 404 otherwise
///
/// The session routes answer a refusal with {"error": message, "code": gRPC code name} and
/// HTTP 400 (INVALID_ARGUMENT, or a missing session, token or name), 401 (UNAUTHENTICATED),
/// 403 (PERMISSION_DENIED), 404 (NOT_FOUND), 413 (a body over wire::kMaxRequestBytes), 429
/// (RESOURCE_EXHAUSTED, with Retry-After in whole seconds when the wait is known), 503
/// (UNAVAILABLE) or 500 (any other); their metrics and audit calls are WebScene,
/// WebSetLights, WebSession and WebPresets.

#include <memory>
#include <string>

#include "core/error.h"
#include "server/service.h"

struct mg_context;

namespace pic {

class WebServer {
public:
    /// Serves `state`'s sessions and state->options.webRoot's files on `listen` ("HOST:PORT";
    /// port 0 picks a free one), warning once on stderr when the web root does not exist;
    /// InvalidInput naming the address when it cannot listen there.
    static Result<std::unique_ptr<WebServer>> start(const std::string& listen,
                                                    std::shared_ptr<PicServer::State> state);
    /// Ends every stream (4014) and stops.
    ~WebServer();
    WebServer(const WebServer&) = delete;
    WebServer& operator=(const WebServer&) = delete;

    /// "HOST:PORT" with the port actually bound.
    const std::string& address() const { return mAddress; }

private:
    WebServer() = default;

    std::shared_ptr<PicServer::State> mState;
    std::string mWebRoot;  ///< canonical; empty when the folder does not exist
    mg_context* mContext = nullptr;
    std::string mAddress;
};

}  // namespace pic
