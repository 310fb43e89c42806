#pragma once
/// The audit log (`picserver --audit-log FILE`): one JSON object per line for every call,
/// appended as it is answered:
///   {"time": "2026-11-28T01:02:03.456Z", "peer": "ipv4:10.0.0.7:51234", "call": "SetLights",
///    "credential": "editor", "session": "0123456789abcdef", "outcome": "OK"}
/// plus "message" (the status message, clipped to 256 bytes) when the outcome is not OK and
/// "forwarded_for" when the call carried x-forwarded-for (a load balancer's client address).
/// `credential` is the API key's id (server/api_keys.h) for operator calls, "anonymous" on a
/// server without keys, "editor" or "viewer" for a session token, "none" when the call
/// presented none that counts. Never a token or a key: the log may be read by more people
/// than the server's clients.

#include <memory>
#include <mutex>
#include <string>
#include <string_view>

#include "core/error.h"

namespace pic {

struct AuditEntry {
    std::string_view peer;
    std::string_view forwardedFor;  ///< empty: none
    std::string_view call;
    std::string_view credential;
    std::string_view session;       ///< empty: the call names none
    std::string_view outcome;       ///< the gRPC status code's name (wire::statusName)
    std::string_view message;       ///< the status message, for outcomes other than OK
};

class AuditLog {
public:
    /// Opens `path` for appending (created 0600); InvalidInput naming it when it cannot be.
    static Result<std::unique_ptr<AuditLog>> open(const std::string& path);
    ~AuditLog();
    AuditLog(const AuditLog&) = delete;
    AuditLog& operator=(const AuditLog&) = delete;

    /// Appends one line (O_APPEND, under a lock), so that lines never interleave.
    void record(const AuditEntry& entry);

private:
    explicit AuditLog(int fd) : mFd(fd) {}
    int mFd;
    std::mutex mMutex;
};

}  // namespace pic
