#include "server/api_keys.h"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <iterator>

#include "server/token_digest.h"

namespace pic {

Result<ApiKeys> ApiKeys::load(const std::string& path) {
    std::ifstream file(path, std::ios::binary);
    if (!file) return fail(ErrorCode::NotFound, "--api-keys {}: cannot open the file", path);
    const std::string text{std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
    if (file.bad()) return fail(ErrorCode::Io, "--api-keys {}: cannot read the file", path);
    return parse(text, path);
}

Result<ApiKeys> ApiKeys::parse(std::string_view text, const std::string& path) {
    ApiKeys keys;
    size_t lineNumber = 0;
    while (!text.empty()) {
        const size_t end = std::min(text.find('\n'), text.size());
        std::string_view line = text.substr(0, end);
        text.remove_prefix(std::min(end + 1, text.size()));
        ++lineNumber;
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        if (line.empty() || line.front() == '#') continue;
        // The message names the line, never its text: it may be a key with a typo.
        if (line.size() < kMinApiKeyBytes || line.size() > kMaxApiKeyBytes)
            return fail(ErrorCode::InvalidInput,
                        "--api-keys {} line {}: a key has {} to {} characters, this one {}", path,
                        lineNumber, kMinApiKeyBytes, kMaxApiKeyBytes, line.size());
        if (!std::ranges::all_of(line, [](char c) { return c > ' ' && c < 127; }))
            return fail(ErrorCode::InvalidInput,
                        "--api-keys {} line {}: a key is printable ASCII without spaces", path,
                        lineNumber);
        Key key{"", tokenDigest(line)};
        key.id = "key-" + key.digest.substr(0, 12);
        if (std::ranges::none_of(keys.mKeys, [&](const Key& k) { return k.digest == key.digest; }))
            keys.mKeys.push_back(std::move(key));
    }
    if (keys.mKeys.empty())
        return fail(ErrorCode::InvalidInput, "--api-keys {}: the file holds no key", path);
    return keys;
}

std::vector<std::string> ApiKeys::ids() const {
    std::vector<std::string> ids;
    for (const Key& key : mKeys) ids.push_back(key.id);
    return ids;
}

std::optional<std::string> ApiKeys::find(std::string_view key) const {
    const std::string digest = tokenDigest(key);
    std::optional<std::string> id;
    // Every key is compared, so the time does not say which one matched.
    for (const Key& k : mKeys)
        if (sameDigest(digest, k.digest)) id = k.id;
    return id;
}

std::optional<std::string_view> bearerKey(std::string_view authorization) {
    constexpr std::string_view kScheme = "bearer ";
    if (authorization.size() <= kScheme.size()) return std::nullopt;
    for (size_t i = 0; i < kScheme.size(); ++i)
        if (std::tolower(static_cast<unsigned char>(authorization[i])) != kScheme[i]) return std::nullopt;
    return authorization.substr(kScheme.size());
}

bool isLoopbackListen(std::string_view listen) {
    const size_t colon = listen.rfind(':');
    std::string_view host = colon == std::string_view::npos ? listen : listen.substr(0, colon);
    if (host.size() >= 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
    if (host == "localhost" || host == "::1") return true;
    // 127.0.0.0/8 as a dotted quad.
    if (!host.starts_with("127.")) return false;
    int dots = 0;
    for (char c : host) {
        if (c == '.') ++dots;
        else if (!std::isdigit(static_cast<unsigned char>(c))) return false;
    }
    return dots == 3;
}

Result<void> checkOpenListen(std::string_view listen, bool hasKeys, bool allowUnauthenticated) {
    if (hasKeys || allowUnauthenticated || isLoopbackListen(listen)) return {};
    return fail(ErrorCode::InvalidInput,
                "--listen {} is reachable from other machines and the server has no --api-keys: "
                "anyone who reaches it could create sessions and download the scenes. Give "
                "--api-keys FILE, or --allow-unauthenticated to serve it open",
                listen);
}

}  // namespace pic
