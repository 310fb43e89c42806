#include "server/metrics_http.h"

#include <mutex>

#include <civetweb.h>

namespace pic {

int MetricsServer::serve(mg_connection* connection, void* self) {
    const mg_request_info* request = mg_get_request_info(connection);
    if (std::string(request->request_method) != "GET") {
        mg_send_http_error(connection, 405, "only GET /metrics");
        return 405;
    }
    const std::string body = static_cast<const MetricsServer*>(self)->mMetrics.render();
    mg_send_http_ok(connection, "text/plain; version=0.0.4; charset=utf-8",
                    static_cast<long long>(body.size()));
    mg_write(connection, body.data(), body.size());
    return 200;
}

Result<std::unique_ptr<MetricsServer>> MetricsServer::start(const std::string& listen,
                                                            const Metrics& metrics) {
    const size_t colon = listen.rfind(':');
    if (colon == std::string::npos || colon == 0 || colon + 1 == listen.size())
        return fail(ErrorCode::InvalidInput, "--metrics-listen must be HOST:PORT, got \"{}\"",
                    listen);
    static std::once_flag initialised;
    std::call_once(initialised, [] { mg_init_library(0); });
    std::unique_ptr<MetricsServer> server(new MetricsServer(metrics));
    const char* options[] = {"listening_ports", listen.c_str(), "num_threads", "2", nullptr};
    mg_callbacks callbacks{};
    // civetweb's own messages (a port in use, say) stay out of the server's log: the start's
    // result says what failed.
    callbacks.log_message = [](const mg_connection*, const char*) { return 1; };
    server->mContext = mg_start(&callbacks, nullptr, options);
    if (!server->mContext)
        return fail(ErrorCode::InvalidInput,
                    "--metrics-listen: cannot listen on \"{}\" (address in use or invalid)", listen);
    mg_set_request_handler(server->mContext, "/metrics$", &MetricsServer::serve, server.get());
    mg_server_port port{};
    if (mg_get_server_ports(server->mContext, 1, &port) != 1)
        return fail(ErrorCode::Internal, "--metrics-listen {}: no port bound", listen);
    server->mAddress = listen.substr(0, colon) + ":" + std::to_string(port.port);
    return server;
}

MetricsServer::~MetricsServer() {
    if (mContext) mg_stop(mContext);
}

}  // namespace pic
