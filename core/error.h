#pragma once
/// Errors in three tiers (STYLE.md 17-20): PIC_CHECK for programming bugs,
/// std::expected<T, Error> for expected failures, exit codes for tools.

#include <cstdio>
#include <cstdlib>
#include <expected>
#include <string>
#include <string_view>
#include <utility>

#include <fmt/format.h>

namespace pic {

/// What kind of failure an Error is; decides the exit code and the gRPC status.
enum class ErrorCode {
    InvalidInput,  ///< the user's input is malformed or out of range (exit 2)
    NotFound,      ///< a named file or object does not exist (exit 2)
    Corrupt,       ///< a file failed its format, version or checksum checks (exit 2)
    Unsupported,   ///< valid input that pic does not handle, e.g. non-triangle primitives (exit 2)
    Io,            ///< reading or writing failed for reasons outside the input (exit 1)
    Internal,      ///< a runtime failure of pic or a library it uses (exit 1)
};

/// A failure with a message that names the problem and the offending value.
struct Error {
    ErrorCode code = ErrorCode::Internal;
    std::string message;
};

/// Result of an operation that can fail in an expected way.
template <class T>
using Result = std::expected<T, Error>;

/// Builds an unexpected Error with a fmt-formatted message.
template <class... Args>
std::unexpected<Error> fail(ErrorCode code, fmt::format_string<Args...> format, Args&&... args) {
    return std::unexpected(Error{code, fmt::format(format, std::forward<Args>(args)...)});
}

/// Process exit code for an error: 2 for bad usage or bad input, 1 for runtime failures.
inline int exitCode(const Error& error) {
    switch (error.code) {
    case ErrorCode::InvalidInput:
    case ErrorCode::NotFound:
    case ErrorCode::Corrupt:
    case ErrorCode::Unsupported: return 2;
    case ErrorCode::Io:
    case ErrorCode::Internal: return 1;
    }
    return 1;
}

/// Short lower-case name of an error code, for messages.
const char* toString(ErrorCode code);

/// Text from a client or a file as a message shows it: at most `maxBytes` (cut at a UTF-8
/// character boundary) and "..." when cut, so that a megabyte of input never fills a log.
std::string clipped(std::string_view text, size_t maxBytes = 64);

}  // namespace pic

/// Aborts with the failed condition; for invariants that only a bug can break.
#define PIC_CHECK(cond)                                                                    \
    do {                                                                                   \
        if (!(cond)) {                                                                     \
            std::fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #cond); \
            std::abort();                                                                  \
        }                                                                                  \
    } while (0)

/// Aborts printing both operands when a op b does not hold.
#define PIC_CHECK_OP(a, op, b)                                                                \
    do {                                                                                      \
        const auto& picA_ = (a);                                                              \
        const auto& picB_ = (b);                                                              \
        if (!(picA_ op picB_)) {                                                              \
            std::fprintf(stderr, "%s:%d: check failed: %s %s %s (%s vs %s)\n", __FILE__,      \
                         __LINE__, #a, #op, #b, fmt::format("{}", picA_).c_str(),             \
                         fmt::format("{}", picB_).c_str());                                   \
            std::abort();                                                                     \
        }                                                                                     \
    } while (0)
#define PIC_CHECK_EQ(a, b) PIC_CHECK_OP(a, ==, b)
#define PIC_CHECK_LT(a, b) PIC_CHECK_OP(a, <, b)
#define PIC_CHECK_LE(a, b) PIC_CHECK_OP(a, <=, b)

#ifdef NDEBUG
#define PIC_DCHECK(cond) ((void)0)
#else
#define PIC_DCHECK(cond) PIC_CHECK(cond)
#endif

/// Returns the error of a Result<void> (or any Result whose value is not needed).
#define PIC_TRY(expr)                                                  \
    do {                                                               \
        auto picTryResult_ = (expr);                                   \
        if (!picTryResult_) return std::unexpected(picTryResult_.error()); \
    } while (false)

/// Propagates the error of an expression returning Result<T>; yields the value otherwise.
#define PIC_TRY_ASSIGN(lhs, expr)                                    \
    auto PIC_CONCAT_(picTry_, __LINE__) = (expr);                    \
    if (!PIC_CONCAT_(picTry_, __LINE__))                             \
        return std::unexpected(PIC_CONCAT_(picTry_, __LINE__).error()); \
    lhs = std::move(*PIC_CONCAT_(picTry_, __LINE__))
#define PIC_CONCAT_INNER_(a, b) a##b
#define PIC_CONCAT_(a, b) PIC_CONCAT_INNER_(a, b)
