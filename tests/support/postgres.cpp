#include "tests/support/postgres.h"

#include <cstdio>
#include <cstdlib>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <pwd.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

namespace pic::test {

namespace fs = std::filesystem;

namespace {

/// The newest installed PostgreSQL's bin directory (Debian: /usr/lib/postgresql/N/bin), or "".
std::string postgresBin() {
    std::error_code ec;
    int newest = 0;
    for (const auto& entry : fs::directory_iterator("/usr/lib/postgresql", ec)) {
        const int version = std::atoi(entry.path().filename().c_str());
        if (version > newest && fs::exists(entry.path() / "bin" / "pg_ctl")) newest = version;
    }
    return newest ? "/usr/lib/postgresql/" + std::to_string(newest) + "/bin" : std::string();
}

/// A port free on 127.0.0.1 now (the kernel's pick for port 0).
int freePort() {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t size = sizeof address;
    int port = 0;
    if (::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0 &&
        ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &size) == 0)
        port = ntohs(address.sin_port);
    ::close(fd);
    return port;
}

}  // namespace

int PostgresServer::runAsOwner(const std::string& command, std::string& output) const {
    // As root, through runuser to the package's `postgres` user.
    const std::string line =
        (::geteuid() == 0 ? "runuser -u postgres -- " : "") + command + " 2>&1";
    FILE* pipe = ::popen(line.c_str(), "r");
    if (!pipe) return -1;
    char buffer[4096];
    while (size_t n = std::fread(buffer, 1, sizeof buffer, pipe)) output.append(buffer, n);
    const int status = ::pclose(pipe);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::unique_ptr<PostgresServer> PostgresServer::start(std::string& why) {
    std::unique_ptr<PostgresServer> server(new PostgresServer());
    server->mBin = postgresBin();
    if (server->mBin.empty()) {
        why = "no PostgreSQL under /usr/lib/postgresql (scripts/install_deps.sh installs it)";
        return nullptr;
    }
    std::string dir = (fs::temp_directory_path() / "pic_pg_XXXXXX").string();
    if (!::mkdtemp(dir.data())) {
        why = "mkdtemp failed";
        return nullptr;
    }
    server->mDir = dir;
    if (::geteuid() == 0) {
        const passwd* owner = ::getpwnam("postgres");
        if (!owner || ::chown(dir.c_str(), owner->pw_uid, owner->pw_gid) != 0) {
            why = "no `postgres` user to run the server as (it comes with Debian's postgresql)";
            return nullptr;
        }
    }
    // Trust on loopback: a throwaway cluster only this test reaches. fsync stays on: the
    // tests are about durability.
    std::string output;
    if (server->runAsOwner(server->mBin + "/initdb --no-sync -A trust -U pic -E UTF8 -D " +
                               dir + "/data",
                           output) != 0) {
        why = "initdb failed: " + output;
        return nullptr;
    }
    server->mPort = freePort();
    if (!server->resume()) {
        why = "pg_ctl start failed: " + startLog(*server);
        return nullptr;
    }
    return server;
}

std::string PostgresServer::startLog(const PostgresServer& server) {
    std::string output;
    server.runAsOwner("cat " + (server.mDir / "log").string(), output);
    return output;
}

bool PostgresServer::resume() {
    std::string output;
    const std::string options = "-c listen_addresses=127.0.0.1 -p " + std::to_string(mPort) +
                                " -k " + mDir.string();
    mRunning = runAsOwner(mBin + "/pg_ctl -w -t 60 -D " + (mDir / "data").string() + " -l " +
                              (mDir / "log").string() + " -o '" + options + "' start",
                          output) == 0;
    return mRunning;
}

bool PostgresServer::stop() {
    std::string output;
    const bool stopped =
        runAsOwner(mBin + "/pg_ctl -w -t 60 -m fast -D " + (mDir / "data").string() + " stop",
                   output) == 0;
    if (stopped) mRunning = false;
    return stopped;
}

PostgresServer::~PostgresServer() {
    if (mRunning) {
        std::string output;
        runAsOwner(mBin + "/pg_ctl -w -t 60 -m immediate -D " + (mDir / "data").string() + " stop",
                   output);
    }
    std::error_code ignored;
    if (!mDir.empty()) fs::remove_all(mDir, ignored);
}

std::string PostgresServer::uri() const {
    return "postgresql://pic@127.0.0.1:" + std::to_string(mPort) + "/postgres";
}

}  // namespace pic::test
