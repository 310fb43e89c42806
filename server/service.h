#pragma once
/// The gRPC server (proto/pic.proto): the bakes it serves, its sessions and the Pic service,
/// plus gRPC health checking and server reflection, on one listening address.

#include <chrono>
#include <cstddef>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <grpcpp/server.h>

#include "core/error.h"
#include "server/api_keys.h"
#include "server/limits.h"
#include "server/metrics_http.h"
#include "server/served_bake.h"
#include "server/session.h"

namespace pic {

class WebServer;

/// Where the browsers' endpoint finds its pages without --web-root: the source tree's
/// client/web, compiled in.
std::string defaultWebRoot();

struct ServerOptions {
    SessionOptions session;
    size_t maxSessions = 64;   ///< CreateSession beyond this: RESOURCE_EXHAUSTED
    std::string tlsCertPem;    ///< with tlsKeyPem: serve TLS with this certificate chain (PEM)
    std::string tlsKeyPem;     ///< the certificate's private key (PEM); both empty: plaintext
    /// A session without subscribers that no client used for this long is removed (its
    /// tokens then get NOT_FOUND).
    std::chrono::milliseconds sessionIdle = std::chrono::hours(1);
    /// Where to serve the Prometheus metrics (GET /metrics; server/metrics.h), "HOST:PORT";
    /// empty: nowhere.
    std::string metricsListen;
    /// Where to serve browsers (server/web_server.h): the session streams over WebSocket, the
    /// scene, light sets and pages over HTTP; "HOST:PORT", empty: nowhere.
    std::string webListen;
    /// The folder of the pages, scripts and their libraries (node_modules/) the browsers'
    /// endpoint serves under GET /; one that does not exist serves none.
    std::string webRoot = defaultWebRoot();
    /// Called once the server listens, with its address, before it restores the sessions of
    /// the database: whatever it prints comes before any update the restored sessions log.
    std::function<void(const std::string& address)> onListening;
    /// The session database (server/session_store.h): an SQLite file or a PostgreSQL URI;
    /// empty: sessions end with the server.
    std::string dbPath;
    /// Operator keys that CreateSession, ListBakes and GetScene need (server/api_keys.h);
    /// empty: those calls are open, which start() allows only on a loopback address unless
    /// allowUnauthenticated.
    ApiKeys apiKeys;
    bool allowUnauthenticated = false;
    /// Where to append the audit log (server/audit_log.h); empty: nowhere.
    std::string auditLog;
    /// A ping to a client after this long without traffic; a client that does not answer
    /// within as long (at most 20 s) is disconnected and its streams end.
    std::chrono::milliseconds keepalive = std::chrono::seconds(30);
    /// Sessions one client may hold: one API key, or one peer host on a server without keys
    /// (counted while this server holds them). 0: only maxSessions.
    size_t maxSessionsPerClient = 0;
    /// Load balancers in front of this server: for a call through one of them, the peer host
    /// that quotas count is the client address in X-Forwarded-For (server/limits.h).
    TrustedProxies trustedProxies;
    /// Subscribe streams one peer host may hold open at once.
    size_t maxStreamsPerPeer = 1000;
    /// A connection older than this is asked to go (HTTP/2 GOAWAY): its calls finish, new ones
    /// take a new connection, so that clients spread over replicas added since. 0: never.
    std::chrono::milliseconds maxConnectionAge = std::chrono::hours(1);
    /// Threads that compute the sessions' versions (server/relight_pool.h), whatever the
    /// number of sessions; 0: one per bake plus one, so that every bake can relight while
    /// another version is encoded.
    unsigned relightThreads = 0;
};

class PicServer {
public:
    /// Serves `bakes` (at least one; the first is the default) on `listen` ("HOST:PORT"; port 0
    /// picks a free one), restoring the sessions of an SQLite `options.dbPath` (a shared
    /// PostgreSQL database's sessions are taken over on their first request instead).
    /// InvalidInput for an address gRPC cannot bind, a non-loopback address without API keys
    /// (unless allowUnauthenticated), an audit log that cannot be opened or a database path
    /// that cannot hold the database, Corrupt for an unreadable database, Io for one that cannot be reached.
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
    /// Drains: health NOT_SERVING, new calls refused (UNAVAILABLE), every stream ended
    /// (UNAVAILABLE), versions not yet computed abandoned, then the gRPC server stopped,
    /// within about two seconds plus one update whatever the number of sessions.
    /// Idempotent; safe from any thread but a gRPC handler.
    void shutdown();

    /// "HOST:PORT" of the metrics endpoint, empty without one.
    std::string metricsAddress() const { return mMetricsServer ? mMetricsServer->address() : std::string(); }
    /// "HOST:PORT" of the browsers' endpoint, empty without one.
    std::string webAddress() const;

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
    std::unique_ptr<MetricsServer> mMetricsServer;
    std::unique_ptr<WebServer> mWebServer;
};

}  // namespace pic
