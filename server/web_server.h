#pragma once
/// The browsers' transport (`picserver --web-listen HOST:PORT`): a session's stream over a
/// WebSocket, on civetweb (Debian's libcivetweb). Browsers cannot make gRPC's streaming calls
/// and gRPC-Web needs a proxy Debian does not ship, so picserver speaks to them itself:
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

#include <memory>
#include <string>

#include "core/error.h"
#include "server/service.h"

struct mg_context;

namespace pic {

class WebServer {
public:
    /// Serves `state`'s sessions on `listen` ("HOST:PORT"; port 0 picks a free one);
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
    mg_context* mContext = nullptr;
    std::string mAddress;
};

}  // namespace pic
