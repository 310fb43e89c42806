#pragma once
/// The gRPC server (proto/pic.proto): the bakes it serves, its sessions and the Pic service,
/// plus gRPC health checking and server reflection, on one listening address.

#include <chrono>
#include <cstddef>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <grpcpp/server.h>

#include "core/error.h"
#include "server/served_bake.h"
#include "server/session.h"

namespace pic {

struct ServerOptions {
    SessionOptions session;
    size_t maxSessions = 64;   ///< CreateSession beyond this: RESOURCE_EXHAUSTED
    std::string tlsCertPem;    ///< with tlsKeyPem: serve TLS with this certificate chain (PEM)
    std::string tlsKeyPem;     ///< the certificate's private key (PEM); both empty: plaintext
    /// A session without subscribers that no client used for this long is removed (its
    /// tokens then get NOT_FOUND).
    std::chrono::milliseconds sessionIdle = std::chrono::hours(1);
    /// The session database (server/session_store.h); empty: sessions end with the server.
    std::string dbPath;
};

class PicServer {
public:
    /// Serves `bakes` (at least one; the first is the default) on `listen` ("HOST:PORT"; port 0
    /// picks a free one), restoring the sessions of `options.dbPath` whose bake is served.
    /// InvalidInput for an address gRPC cannot bind, Corrupt for an unreadable database.
    static Result<std::unique_ptr<PicServer>> start(std::vector<std::unique_ptr<ServedBake>> bakes,
                                                    const std::string& listen,
                                                    ServerOptions options);
    /// Shuts down (see shutdown()).
    ~PicServer();
    PicServer(const PicServer&) = delete;
    PicServer& operator=(const PicServer&) = delete;

    /// "HOST:PORT" with the port actually bound.
    const std::string& address() const { return mAddress; }
    /// Blocks until shutdown() has finished.
    void wait();
    /// Stops accepting calls, ends every stream (UNAVAILABLE) and stops the sessions.
    /// Idempotent; safe from any thread but a gRPC handler.
    void shutdown();

    /// A session by id (null when none): for tests and the log.
    std::shared_ptr<Session> session(const std::string& id) const;

    /// What the service reads; internal.
    struct State;

private:
    PicServer() = default;

    std::string mAddress;
    std::shared_ptr<State> mState;
    std::unique_ptr<grpc::Service> mService;
    std::unique_ptr<grpc::Server> mServer;
    std::mutex mShutdownMutex;
    bool mShutDown = false;
    std::thread mReaper;  ///< housekeeping: idle sessions, the database; until shutdown
};

}  // namespace pic
