#pragma once
/// A real PostgreSQL server for tests, from Debian's package: a fresh cluster in a temporary
/// directory, listening on 127.0.0.1 at a free port (and a socket in that directory), run as
/// the `postgres` user when the tests run as root (postgres refuses root), stopped and
/// removed when the object goes.

#include <filesystem>
#include <memory>
#include <string>

namespace pic::test {

class PostgresServer {
public:
    /// Starts one; null with `why` set when it cannot (no PostgreSQL installed, initdb or
    /// pg_ctl failed: `why` holds their output).
    static std::unique_ptr<PostgresServer> start(std::string& why);
    ~PostgresServer();
    PostgresServer(const PostgresServer&) = delete;
    PostgresServer& operator=(const PostgresServer&) = delete;

    /// postgresql://pic@127.0.0.1:PORT/postgres
    std::string uri() const;
    int port() const { return mPort; }

    /// Stops the server (fast shutdown) and starts it again on the same port, for tests of
    /// what clients do while it is away. Both return whether pg_ctl succeeded.
    bool stop();
    bool resume();

private:
    PostgresServer() = default;
    /// Runs `command` as the cluster's owner; its exit code, output in `output`.
    int runAsOwner(const std::string& command, std::string& output) const;
    /// The server's log, for failures.
    static std::string startLog(const PostgresServer& server);

    std::filesystem::path mDir;   ///< holds data/, the log and the socket
    std::string mBin;             ///< PostgreSQL's bin directory
    int mPort = 0;
    bool mRunning = false;
};

}  // namespace pic::test
