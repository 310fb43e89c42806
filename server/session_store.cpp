#include "server/session_store.h"

#include <filesystem>

#include <unistd.h>

#include <nlohmann/json.hpp>

#include "server/token_digest.h"

namespace pic {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

/// 64 lowercase hex digits, as tokenDigest writes.
bool isDigest(const std::string& text) {
    return text.size() == 64 && text.find_first_not_of("0123456789abcdef") == std::string::npos;
}

}  // namespace

bool SessionStore::isPostgres(const std::string& spec) {
    return spec.starts_with("postgresql://") || spec.starts_with("postgres://");
}

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

Result<std::unique_ptr<SessionStore>> SessionStore::open(const std::string& spec) {
    if (isPostgres(spec)) return openPostgresStore(spec);
    PIC_TRY(checkPath(spec));
    return openSqliteStore(spec);
}

Result<std::vector<StoredSession>> parseJsonSessions(const std::string& text,
                                                     const std::string& path) {
    const Json root = Json::parse(text, nullptr, /*allow_exceptions=*/false);
    // Any type where the format should be (found by fuzzing: an array here threw from value()).
    const auto stated = root.is_object() ? root.find("format") : root.end();
    const int format = stated != root.end() && stated->is_number_integer() ? stated->get<int>() : 0;
    if ((format != 1 && format != 2) || !root.contains("sessions") || !root["sessions"].is_array())
        return fail(ErrorCode::Corrupt,
                    "{} is not a pic session database (SQLite, or JSON of format 1 or 2); move "
                    "it away to start afresh",
                    path);
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
            return fail(ErrorCode::Corrupt, "{}: session entry {}: {}", path, sessions.size(),
                        error.what());
        }
        PIC_TRY_ASSIGN(StoredSession checked,
                       sessionFromRow(std::move(session.id), std::move(session.editorDigest),
                                      std::move(session.viewerDigest), std::move(session.bakeId),
                                      int64_t(session.version),
                                      entry.value("lights", Json::object()).dump(), "{}", path));
        sessions.push_back(std::move(checked));
    }
    return sessions;
}

Result<StoredSession> sessionFromRow(std::string id, std::string editorDigest,
                                     std::string viewerDigest, std::string bakeId, int64_t version,
                                     const std::string& lightsJson, const std::string& presetsJson,
                                     const std::string& where) {
    if (!isDigest(editorDigest) || !isDigest(viewerDigest))
        return fail(ErrorCode::Corrupt,
                    "{}: session {}: a token digest is not 64 lowercase hex digits", where, id);
    if (version < 1)
        return fail(ErrorCode::Corrupt, "{}: session {}: version {} is not positive", where, id,
                    version);
    auto lights = parseLightSet(lightsJson);
    if (!lights)
        return fail(ErrorCode::Corrupt, "{}: session {}: {}", where, id, lights.error().message);
    auto presets = parseLightPresets(presetsJson);
    if (!presets)
        return fail(ErrorCode::Corrupt, "{}: session {}: {}", where, id, presets.error().message);
    return StoredSession{std::move(id),      std::move(editorDigest), std::move(viewerDigest),
                         std::move(bakeId),  uint64_t(version),       std::move(*lights),
                         std::move(*presets)};
}

}  // namespace pic
