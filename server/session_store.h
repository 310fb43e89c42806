#pragma once
/// The server's database (`picserver --db`): its sessions, so that a restarted server, or
/// another replica, carries them on. Two backends behind one interface:
/// - SQLite (`--db FILE`), the embedded default: one server per file, enforced by a lock
///   held for the server's life; the sessions are restored when the server starts.
/// - PostgreSQL (`--db postgresql://…` or `postgres://…`, libpq's connection URI): shared by
///   the replicas of a deployment; a replica takes a session over from the database on its
///   first request for it.
///
/// One row per session: its id, its tokens' digests (server/token_digest.h, never the
/// tokens), its bake, its newest accepted version with that version's light set, and its
/// presets (named light sets, one JSON object name → light set). Every write is one
/// committed transaction before the call returns: a SetLights reply, or a preset's, means
/// the change survives a crash of the server.
///
/// Versions order the replicas. A row's version only grows (save() refuses a version not
/// newer than the stored one), so a replica whose copy of a session is behind the database
/// (another replica took the session over and moved on) learns it at its next save.
///
/// The schema carries a version (SQLite: PRAGMA user_version; PostgreSQL: table
/// pic_schema) migrated forward at open; a database of a newer schema is refused. A FILE
/// that holds the JSON database of earlier releases (format 1 or 2) is converted in place:
/// its sessions move into a new SQLite file and the JSON stays beside it as FILE.json.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/light_set.h"

namespace pic {

/// What the database keeps of one session.
struct StoredSession {
    std::string id;
    std::string editorDigest;  ///< tokenDigest of the editor token
    std::string viewerDigest;  ///< tokenDigest of the viewer token
    std::string bakeId;
    uint64_t version = 0;  ///< the newest version it had accepted
    LightSet lights;       ///< the light set of that version
    LightPresets presets;  ///< its named light sets
};

/// The schema version this build writes: 1, the sessions table; 2, its presets column.
inline constexpr int kSessionSchema = 2;

class SessionStore {
public:
    virtual ~SessionStore() = default;

    /// Opens the database `spec` names (a PostgreSQL URI, else an SQLite file), creating or
    /// migrating its schema. InvalidInput naming the spec for a path that cannot hold the
    /// database or a file another server holds; Io when PostgreSQL cannot be reached;
    /// Corrupt for a file that is neither SQLite nor a JSON database, or of a newer schema.
    static Result<std::unique_ptr<SessionStore>> open(const std::string& spec);
    /// Whether `spec` names a PostgreSQL database rather than an SQLite file.
    static bool isPostgres(const std::string& spec);
    /// InvalidInput naming the path unless it can hold an SQLite database: not a directory,
    /// in a directory that exists and that this process may write in.
    static Result<void> checkPath(const std::string& path);

    /// For logs: "sqlite FILE" or "postgresql HOST:PORT/DB" (never a password).
    virtual std::string describe() const = 0;
    /// Whether other servers may use the database at the same time (PostgreSQL).
    virtual bool shared() const = 0;

    /// Every session, oldest first.
    virtual Result<std::vector<StoredSession>> loadAll() = 0;
    /// The session `id`, or none.
    virtual Result<std::optional<StoredSession>> find(const std::string& id) = 0;
    /// Adds a new session; false (nothing written) when the id is taken.
    virtual Result<bool> create(const StoredSession& session) = 0;
    /// Writes the session's version and light set when its version is newer than the stored
    /// one (inserting the row, presets too, should it be gone); false, writing nothing, when
    /// the stored version is the same or newer.
    virtual Result<bool> save(const StoredSession& session) = 0;
    /// Writes the session's presets when the stored version is not newer than its version
    /// (inserting the row should it be gone); false, writing nothing, when a newer version is
    /// stored (another server took the session over).
    virtual Result<bool> savePresets(const StoredSession& session) = 0;
    /// Deletes the session unless the stored version is newer than `version` (another
    /// replica has taken it over since).
    virtual Result<void> remove(const std::string& id, uint64_t version) = 0;
    /// Whether the database answers (a trivial query).
    virtual Result<void> ping() = 0;
};

/// The JSON database of earlier releases (format 1: plain tokens, digested here; format 2:
/// digests) parsed from `text`; Corrupt naming `path` and the problem.
Result<std::vector<StoredSession>> parseJsonSessions(const std::string& text,
                                                     const std::string& path);

/// A row's columns as a session; Corrupt naming `where` and the row for a digest that is not
/// 64 lowercase hex digits, a light set parseLightSet refuses, or presets parseLightPresets
/// refuses.
Result<StoredSession> sessionFromRow(std::string id, std::string editorDigest,
                                     std::string viewerDigest, std::string bakeId, int64_t version,
                                     const std::string& lightsJson, const std::string& presetsJson,
                                     const std::string& where);

/// The backends (server/sqlite_store.cpp, server/postgres_store.cpp).
Result<std::unique_ptr<SessionStore>> openSqliteStore(const std::string& path);
Result<std::unique_ptr<SessionStore>> openPostgresStore(const std::string& uri);

}  // namespace pic
