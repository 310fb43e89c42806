#include "server/session_store.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "server/token_digest.h"

namespace pic {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

/// 2: token digests; 1: plain tokens (read, digested on load).
constexpr int kFormat = 2;

/// 64 lowercase hex digits, as tokenDigest writes.
bool isDigest(const std::string& text) {
    return text.size() == 64 && text.find_first_not_of("0123456789abcdef") == std::string::npos;
}

}  // namespace

Result<void> SessionStore::checkPath(const std::string& path) {
    std::error_code ec;
    if (fs::is_directory(path, ec))
        return fail(ErrorCode::InvalidInput, "--db {} is a directory; give the database file's path", path);
    const fs::path parent = fs::path(path).parent_path().empty() ? fs::path(".") : fs::path(path).parent_path();
    if (!fs::is_directory(parent, ec))
        return fail(ErrorCode::InvalidInput, "--db {}: the directory {} does not exist", path, parent.string());
    if (::access(parent.c_str(), W_OK | X_OK) != 0)
        return fail(ErrorCode::InvalidInput, "--db {}: cannot write in the directory {}", path, parent.string());
    return {};
}

Result<std::vector<StoredSession>> SessionStore::load() const {
    std::error_code ec;
    if (!fs::exists(mPath, ec)) return std::vector<StoredSession>{};
    std::ifstream file(mPath, std::ios::binary);
    if (!file) return fail(ErrorCode::Io, "cannot open the session database {}", mPath);
    const std::string text{std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
    const Json root = Json::parse(text, nullptr, /*allow_exceptions=*/false);
    const int format = root.is_object() ? root.value("format", 0) : 0;
    if ((format != 1 && format != kFormat) || !root.contains("sessions") ||
        !root["sessions"].is_array())
        return fail(ErrorCode::Corrupt,
                    "{} is not a pic session database of format 1 or {} (move it away to start "
                    "afresh)",
                    mPath, kFormat);
    std::vector<StoredSession> sessions;
    for (const Json& entry : root["sessions"]) {
        StoredSession session;
        try {
            session.id = entry.at("id").get<std::string>();
            if (format == 1) {
                session.editorDigest = tokenDigest(entry.at("editor_token").get<std::string>());
                session.viewerDigest = tokenDigest(entry.at("viewer_token").get<std::string>());
            } else {
                session.editorDigest = entry.at("editor_token_sha256").get<std::string>();
                session.viewerDigest = entry.at("viewer_token_sha256").get<std::string>();
            }
            session.bakeId = entry.at("bake_id").get<std::string>();
            session.version = entry.at("version").get<uint64_t>();
        } catch (const Json::exception& error) {
            return fail(ErrorCode::Corrupt, "{}: session entry {}: {}", mPath, sessions.size(),
                        error.what());
        }
        if (!isDigest(session.editorDigest) || !isDigest(session.viewerDigest))
            return fail(ErrorCode::Corrupt,
                        "{}: session {}: a token digest is not 64 lowercase hex digits", mPath,
                        session.id);
        auto lights = parseLightSet(entry.value("lights", Json::object()).dump());
        if (!lights)
            return fail(ErrorCode::Corrupt, "{}: session {}: {}", mPath, session.id,
                        lights.error().message);
        session.lights = std::move(*lights);
        sessions.push_back(std::move(session));
    }
    return sessions;
}

Result<void> SessionStore::save(const std::vector<StoredSession>& sessions) {
    Json root;
    root["format"] = kFormat;
    root["sessions"] = Json::array();
    for (const StoredSession& session : sessions) {
        Json entry;
        entry["id"] = session.id;
        entry["editor_token_sha256"] = session.editorDigest;
        entry["viewer_token_sha256"] = session.viewerDigest;
        entry["bake_id"] = session.bakeId;
        entry["version"] = session.version;
        entry["lights"] = Json::parse(toJson(session.lights));
        root["sessions"].push_back(std::move(entry));
    }
    const std::string text = root.dump(2) + "\n";

    std::lock_guard lock(mMutex);
    const std::string temp = mPath + ".tmp";
    // Owner-only: the digests cannot be presented as tokens, but the sessions are private.
    const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
    if (fd < 0) return fail(ErrorCode::Io, "cannot write the session database {}", temp);
    size_t written = 0;
    while (written < text.size()) {
        const ssize_t n = ::write(fd, text.data() + written, text.size() - written);
        if (n <= 0) break;
        written += size_t(n);
    }
    const bool synced = ::fsync(fd) == 0;
    ::close(fd);
    if (written != text.size() || !synced || std::rename(temp.c_str(), mPath.c_str()) != 0) {
        std::remove(temp.c_str());
        return fail(ErrorCode::Io, "cannot write the session database {}", mPath);
    }
    return {};
}

}  // namespace pic
