#pragma once
/// Starting civetweb (Debian's libcivetweb), the embedded HTTP/WebSocket server behind
/// picserver's metrics (server/metrics_http.h) and browser (server/web_server.h) endpoints.

#include <string>
#include <utility>
#include <vector>

#include "core/error.h"

struct mg_context;

namespace pic {

struct CivetwebServer {
    mg_context* context = nullptr;
    std::string address;  ///< "HOST:PORT" with the port actually bound
};

/// civetweb listening on `listen` ("HOST:PORT"; port 0 picks a free one) with `options`
/// (civetweb's names and values) besides the port, its own messages kept out of the server's
/// log. InvalidInput naming `flag` and the address when it is not HOST:PORT or cannot be
/// listened on.
Result<CivetwebServer> startCivetweb(const std::string& flag, const std::string& listen,
                                     const std::vector<std::pair<std::string, std::string>>& options);

}  // namespace pic
