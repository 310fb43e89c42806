#include "server/civetweb_server.h"

#include <mutex>

#include <civetweb.h>

namespace pic {

Result<CivetwebServer> startCivetweb(const std::string& flag, const std::string& listen,
                                     const std::vector<std::pair<std::string, std::string>>& options) {
    const size_t colon = listen.rfind(':');
    if (colon == std::string::npos || colon == 0 || colon + 1 == listen.size())
        return fail(ErrorCode::InvalidInput, "{} must be HOST:PORT, got \"{}\"", flag, listen);
    static std::once_flag initialised;
    std::call_once(initialised, [] { mg_init_library(MG_FEATURES_WEBSOCKET); });
    std::vector<const char*> names = {"listening_ports", listen.c_str()};
    for (const auto& [name, value] : options) {
        names.push_back(name.c_str());
        names.push_back(value.c_str());
    }
    names.push_back(nullptr);
    mg_callbacks callbacks{};
    // civetweb's own messages (a port in use, say) stay out of the server's log: the result
    // says what failed.
    callbacks.log_message = [](const mg_connection*, const char*) { return 1; };
    CivetwebServer server;
    server.context = mg_start(&callbacks, nullptr, names.data());
    if (!server.context)
        return fail(ErrorCode::InvalidInput, "{}: cannot listen on \"{}\" (address in use or invalid)",
                    flag, listen);
    mg_server_port port{};
    if (mg_get_server_ports(server.context, 1, &port) != 1) {
        mg_stop(server.context);
        return fail(ErrorCode::Internal, "{} {}: no port bound", flag, listen);
    }
    server.address = listen.substr(0, colon) + ":" + std::to_string(port.port);
    return server;
}

}  // namespace pic
