#include "server/audit_log.h"

#include <cerrno>
#include <chrono>
#include <cstring>
#include <ctime>

#include <fcntl.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

namespace pic {

namespace {

/// "2026-11-28T01:02:03.456Z"
std::string utcNow() {
    const auto now = std::chrono::system_clock::now();
    const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count();
    const std::time_t seconds = static_cast<std::time_t>(ms / 1000);
    std::tm utc{};
    gmtime_r(&seconds, &utc);
    char text[32];
    std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%S", &utc);
    return fmt::format("{}.{:03}Z", text, ms % 1000);
}

}  // namespace

Result<std::unique_ptr<AuditLog>> AuditLog::open(const std::string& path) {
    const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0600);
    if (fd < 0)
        return fail(ErrorCode::InvalidInput, "--audit-log {}: cannot open it for appending: {}", path,
                    std::strerror(errno));
    return std::unique_ptr<AuditLog>(new AuditLog(fd));
}

AuditLog::~AuditLog() { ::close(mFd); }

void AuditLog::record(const AuditEntry& entry) {
    nlohmann::ordered_json line;
    line["time"] = utcNow();
    line["peer"] = entry.peer;
    if (!entry.forwardedFor.empty()) line["forwarded_for"] = clipped(entry.forwardedFor, 256);
    line["call"] = entry.call;
    line["credential"] = entry.credential;
    if (!entry.session.empty()) line["session"] = clipped(entry.session, 64);
    line["outcome"] = entry.outcome;
    if (entry.outcome != "OK" && !entry.message.empty()) line["message"] = clipped(entry.message, 256);
    // Bytes that are not UTF-8 (a client's session id may hold anything) are replaced.
    const std::string text = line.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
    std::lock_guard lock(mMutex);
    size_t written = 0;
    while (written < text.size()) {
        const ssize_t n = ::write(mFd, text.data() + written, text.size() - written);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) return;  // a full disk must not stop the server; the line is lost
        written += static_cast<size_t>(n);
    }
}

}  // namespace pic
