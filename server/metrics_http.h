#pragma once
/// The metrics endpoint (`picserver --metrics-listen HOST:PORT`): GET /metrics answers with
/// the Prometheus text exposition of server/metrics.h, on civetweb (Debian's libcivetweb), an
/// embedded HTTP server with its own threads. Any other path is 404.

#include <memory>
#include <string>

#include "core/error.h"
#include "server/metrics.h"

struct mg_context;
struct mg_connection;

namespace pic {

class MetricsServer {
public:
    /// Serves `metrics` on `listen` ("HOST:PORT"; port 0 picks a free one); InvalidInput
    /// naming the address when it cannot listen there.
    static Result<std::unique_ptr<MetricsServer>> start(const std::string& listen,
                                                        const Metrics& metrics);
    /// Stops serving (waits for requests in progress).
    ~MetricsServer();
    MetricsServer(const MetricsServer&) = delete;
    MetricsServer& operator=(const MetricsServer&) = delete;

    /// "HOST:PORT" with the port actually bound.
    const std::string& address() const { return mAddress; }

private:
    explicit MetricsServer(const Metrics& metrics) : mMetrics(metrics) {}
    static int serve(::mg_connection* connection, void* self);

    const Metrics& mMetrics;
    mg_context* mContext = nullptr;
    std::string mAddress;
};

}  // namespace pic
