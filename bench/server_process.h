#pragma once
/// The pic programs as child processes of picbench: picserver for the benchmarks that measure
/// it from outside (started on a free loopback port, its update log drained, stopped with
/// SIGTERM when the object goes), and the exec step every child shares.

#include <string>
#include <vector>

#include <sys/types.h>

#include "core/error.h"

namespace pic {

struct ServerProcess {
    pid_t pid = -1;
    FILE* out = nullptr;
    std::string address;  ///< "127.0.0.1:PORT" once started

    ServerProcess() = default;
    ServerProcess(const ServerProcess&) = delete;
    ServerProcess& operator=(const ServerProcess&) = delete;
    ~ServerProcess();
};

/// Runs `args` (args[0] the binary) and waits for its "listening on" line.
Result<void> startServer(ServerProcess& server, const std::vector<std::string>& args);

/// User + system CPU seconds of process `pid` (/proc/PID/stat).
double cpuSeconds(pid_t pid);

/// Resident memory of process `pid` in bytes (/proc/PID/status VmRSS); 0 when gone.
uint64_t residentBytes(pid_t pid);

/// In a forked child: runs `args` (args[0] the binary); on failure says so and exits 127.
[[noreturn]] void execChild(const std::vector<std::string>& args);

/// A program of this build tree, beside picbench's folder: siblingProgram("server", "picserver")
/// is build/server/picserver for build/bench/picbench.
std::string siblingProgram(const char* folder, const char* name);

}  // namespace pic
