#pragma once
/// Operator API keys (`picserver --api-keys FILE`): the credential that CreateSession,
/// ListBakes and GetScene need once a server has keys. Clients send one in the request metadata
/// `authorization: Bearer KEY` (wire::kAuthorizationMetadata). The server keeps only the
/// keys' SHA-256 digests and names each key by a short id derived from its digest, which the
/// audit log and messages show instead of the key.

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.h"

namespace pic {

/// Bytes a key may have: long enough not to be guessed, short enough for a header.
inline constexpr size_t kMinApiKeyBytes = 16;
inline constexpr size_t kMaxApiKeyBytes = 256;

class ApiKeys {
public:
    /// The keys of `path`: one per line, printable ASCII without spaces, kMinApiKeyBytes to
    /// kMaxApiKeyBytes long; blank lines and lines starting with '#' are skipped, a key given
    /// twice counts once. NotFound for a missing file; InvalidInput naming the line (never its
    /// text) for a bad key or a file that holds none.
    static Result<ApiKeys> load(const std::string& path);
    /// The same for the text of such a file; `path` names it in messages.
    static Result<ApiKeys> parse(std::string_view text, const std::string& path);

    bool empty() const { return mKeys.empty(); }
    size_t size() const { return mKeys.size(); }
    /// The ids of the keys, in file order ("key-" and 12 hex digits of its SHA-256).
    std::vector<std::string> ids() const;
    /// The id of `key` when it is one of these (compared by digest, in constant time).
    std::optional<std::string> find(std::string_view key) const;

private:
    struct Key {
        std::string id;
        std::string digest;  ///< tokenDigest of the key
    };
    std::vector<Key> mKeys;
};

/// The key of an `authorization` metadata value "Bearer KEY" (the scheme in any case), or
/// nothing when the value has another form.
std::optional<std::string_view> bearerKey(std::string_view authorization);

/// Whether `listen` ("HOST:PORT") binds only a loopback address: 127.0.0.0/8, ::1 or
/// localhost. 0.0.0.0, [::], other addresses and other host names are reachable from
/// elsewhere.
bool isLoopbackListen(std::string_view listen);

/// InvalidInput when a server would listen on `listen` open to anyone: a non-loopback address,
/// no API keys and no explicit allowUnauthenticated.
Result<void> checkOpenListen(std::string_view listen, bool hasKeys, bool allowUnauthenticated);

}  // namespace pic
