#include "bench/server_process.h"

#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include <sys/wait.h>
#include <unistd.h>

namespace pic {

namespace fs = std::filesystem;

ServerProcess::~ServerProcess() {
    if (pid > 0) {
        kill(pid, SIGTERM);
        int status = 0;
        waitpid(pid, &status, 0);
    }
    if (out) std::fclose(out);
}

Result<void> startServer(ServerProcess& server, const std::vector<std::string>& args) {
    int fds[2];
    if (pipe(fds) != 0) return fail(ErrorCode::Io, "pipe failed");
    server.pid = fork();
    if (server.pid == 0) {
        dup2(fds[1], STDOUT_FILENO);
        close(fds[0]);
        close(fds[1]);
        execChild(args);
    }
    close(fds[1]);
    server.out = fdopen(fds[0], "r");
    char line[512];
    if (!server.out || !std::fgets(line, sizeof line, server.out))
        return fail(ErrorCode::Internal, "{} ended before it listened", args[0]);
    std::string text(line);
    const std::string prefix = "listening on ";
    if (!text.starts_with(prefix))
        return fail(ErrorCode::Internal, "{} printed \"{}\" instead of listening on", args[0], text);
    server.address = text.substr(prefix.size());
    while (!server.address.empty() && server.address.back() == '\n') server.address.pop_back();
    // The update log goes on; drain it so the server never blocks on a full pipe.
    std::thread([out = server.out] {
        char discard[4096];
        while (std::fgets(discard, sizeof discard, out)) {
        }
    }).detach();
    server.out = nullptr;  // owned by the draining thread
    return {};
}

double cpuSeconds(pid_t pid) {
    std::ifstream stat(fmt::format("/proc/{}/stat", pid));
    std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
    const size_t close = text.rfind(')');
    if (close == std::string::npos) return 0.0;
    std::istringstream fields(text.substr(close + 2));
    std::string field;
    double ticks = 0.0;
    for (int i = 3; i <= 15 && fields >> field; ++i)
        if (i == 14 || i == 15) ticks += std::stod(field);
    return ticks / double(sysconf(_SC_CLK_TCK));
}

uint64_t residentBytes(pid_t pid) {
    std::ifstream status(fmt::format("/proc/{}/status", pid));
    std::string line;
    while (std::getline(status, line))
        if (line.starts_with("VmRSS:")) return std::stoull(line.substr(6)) * 1024;  // kB
    return 0;
}

void execChild(const std::vector<std::string>& args) {
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    std::fprintf(stderr, "picbench: cannot run %s\n", argv[0]);
    _exit(127);
}

std::string siblingProgram(const char* folder, const char* name) {
    std::error_code ec;
    const fs::path self = fs::read_symlink("/proc/self/exe", ec);
    return (self.parent_path().parent_path() / folder / name).string();
}

}  // namespace pic
