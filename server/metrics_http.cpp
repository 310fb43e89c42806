#include "server/metrics_http.h"

#include <civetweb.h>

#include "server/civetweb_server.h"

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
    PIC_TRY_ASSIGN(CivetwebServer started,
                   startCivetweb("--metrics-listen", listen, {{"num_threads", "2"}}));
    std::unique_ptr<MetricsServer> server(new MetricsServer(metrics));
    server->mContext = started.context;
    server->mAddress = std::move(started.address);
    mg_set_request_handler(server->mContext, "/metrics$", &MetricsServer::serve, server.get());
    return server;
}

MetricsServer::~MetricsServer() {
    if (mContext) mg_stop(mContext);
}

}  // namespace pic
