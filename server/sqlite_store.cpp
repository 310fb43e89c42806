/// The SQLite session store (server/session_store.h): one connection, in WAL mode with full
/// synchronisation so that a committed write survives a crash of the process or the machine;
/// one server per file, by an exclusive lock on FILE.lock held while the store is open.

#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <mutex>

#include <fcntl.h>
#include <sqlite3.h>
#include <sys/file.h>
#include <unistd.h>

#include "server/session_store.h"

namespace pic {

namespace {

namespace fs = std::filesystem;

/// The statements that take a schema from version i to i + 1 (index i); shared in spirit
/// with the PostgreSQL store, whose dialect differs only in types.
constexpr const char* kMigrations[] = {
    // 0 → 1: one row per session.
    "CREATE TABLE sessions ("
    "  id TEXT PRIMARY KEY,"
    "  editor_token_sha256 TEXT NOT NULL,"
    "  viewer_token_sha256 TEXT NOT NULL,"
    "  bake_id TEXT NOT NULL,"
    "  version INTEGER NOT NULL,"
    "  lights TEXT NOT NULL,"
    "  created_unix_ms INTEGER NOT NULL,"
    "  updated_unix_ms INTEGER NOT NULL)",
    // 1 → 2: each session's presets, a JSON object name → light set.
    "ALTER TABLE sessions ADD COLUMN presets TEXT NOT NULL DEFAULT '{}'",
};
static_assert(std::size(kMigrations) == kSessionSchema);

int64_t unixMs() {
    return std::chrono::duration_cast<std::chrono::milliseconds>(
               std::chrono::system_clock::now().time_since_epoch())
        .count();
}

/// A prepared statement, finalised on scope exit.
class Statement {
public:
    Statement(sqlite3* db, const char* sql) { mRc = sqlite3_prepare_v2(db, sql, -1, &mStmt, nullptr); }
    ~Statement() { sqlite3_finalize(mStmt); }
    Statement(const Statement&) = delete;
    Statement& operator=(const Statement&) = delete;

    bool prepared() const { return mRc == SQLITE_OK; }
    void bind(int index, const std::string& text) {
        sqlite3_bind_text(mStmt, index, text.data(), int(text.size()), SQLITE_TRANSIENT);
    }
    void bind(int index, int64_t value) { sqlite3_bind_int64(mStmt, index, value); }
    /// SQLITE_ROW, SQLITE_DONE or an error code.
    int step() { return sqlite3_step(mStmt); }
    std::string text(int column) const {
        const auto* bytes = sqlite3_column_text(mStmt, column);
        return bytes ? std::string(reinterpret_cast<const char*>(bytes),
                                   size_t(sqlite3_column_bytes(mStmt, column)))
                     : std::string();
    }
    int64_t integer(int column) const { return sqlite3_column_int64(mStmt, column); }

private:
    sqlite3_stmt* mStmt = nullptr;
    int mRc = SQLITE_ERROR;
};

constexpr const char* kColumns =
    "id, editor_token_sha256, viewer_token_sha256, bake_id, version, lights, presets";

class SqliteStore final : public SessionStore {
public:
    SqliteStore(std::string path, int lockFd) : mPath(std::move(path)), mLockFd(lockFd) {}

    ~SqliteStore() override {
        sqlite3_close(mDb);
        ::close(mLockFd);  // after SQLite has closed the file: releases the server's lock
    }

    /// Opens the file (creating it owner-only), sets WAL with full synchronisation and
    /// migrates the schema.
    Result<void> openDatabase() {
        // SQLite gives its -wal and -shm files the database file's permissions.
        if (const int fd = ::open(mPath.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0600); fd >= 0)
            ::close(fd);
        if (sqlite3_open_v2(mPath.c_str(), &mDb, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE,
                            nullptr) != SQLITE_OK)
            return error("cannot open");
        sqlite3_busy_timeout(mDb, 5000);
        PIC_TRY(exec("PRAGMA journal_mode=WAL"));
        PIC_TRY(exec("PRAGMA synchronous=FULL"));
        return migrate();
    }

    std::string describe() const override { return "sqlite " + mPath; }
    bool shared() const override { return false; }

    Result<std::vector<StoredSession>> loadAll() override {
        std::lock_guard lock(mMutex);
        Statement select(mDb, fmt::format("SELECT {} FROM sessions ORDER BY created_unix_ms, id",
                                          kColumns)
                                  .c_str());
        if (!select.prepared()) return error("cannot read");
        std::vector<StoredSession> sessions;
        int rc;
        while ((rc = select.step()) == SQLITE_ROW) {
            PIC_TRY_ASSIGN(StoredSession session, row(select));
            sessions.push_back(std::move(session));
        }
        if (rc != SQLITE_DONE) return error("cannot read");
        return sessions;
    }

    Result<std::optional<StoredSession>> find(const std::string& id) override {
        std::lock_guard lock(mMutex);
        Statement select(mDb, fmt::format("SELECT {} FROM sessions WHERE id = ?1", kColumns).c_str());
        if (!select.prepared()) return error("cannot read");
        select.bind(1, id);
        const int rc = select.step();
        if (rc == SQLITE_DONE) return std::optional<StoredSession>();
        if (rc != SQLITE_ROW) return error("cannot read");
        PIC_TRY_ASSIGN(StoredSession session, row(select));
        return std::optional<StoredSession>(std::move(session));
    }

    Result<bool> create(const StoredSession& session) override {
        return write(session,
                     "INSERT INTO sessions (id, editor_token_sha256, viewer_token_sha256, bake_id, "
                     "version, lights, presets, created_unix_ms, updated_unix_ms) "
                     "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?8, ?7, ?7) ON CONFLICT (id) DO NOTHING");
    }

    Result<bool> save(const StoredSession& session) override {
        return write(session,
                     "INSERT INTO sessions (id, editor_token_sha256, viewer_token_sha256, bake_id, "
                     "version, lights, presets, created_unix_ms, updated_unix_ms) "
                     "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?8, ?7, ?7) ON CONFLICT (id) DO UPDATE SET "
                     "version = excluded.version, lights = excluded.lights, "
                     "updated_unix_ms = excluded.updated_unix_ms "
                     "WHERE excluded.version > sessions.version");
    }

    Result<bool> savePresets(const StoredSession& session) override {
        return write(session,
                     "INSERT INTO sessions (id, editor_token_sha256, viewer_token_sha256, bake_id, "
                     "version, lights, presets, created_unix_ms, updated_unix_ms) "
                     "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?8, ?7, ?7) ON CONFLICT (id) DO UPDATE SET "
                     "presets = excluded.presets, updated_unix_ms = excluded.updated_unix_ms "
                     "WHERE excluded.version >= sessions.version");
    }

    Result<void> remove(const std::string& id, uint64_t version) override {
        std::lock_guard lock(mMutex);
        Statement erase(mDb, "DELETE FROM sessions WHERE id = ?1 AND version <= ?2");
        if (!erase.prepared()) return error("cannot write");
        erase.bind(1, id);
        erase.bind(2, int64_t(version));
        if (erase.step() != SQLITE_DONE) return error("cannot write");
        return {};
    }

    Result<void> ping() override {
        std::lock_guard lock(mMutex);
        Statement select(mDb, "SELECT count(*) FROM sessions");
        if (!select.prepared() || select.step() != SQLITE_ROW) return error("cannot read");
        return {};
    }

private:
    /// Io naming the file, what failed and SQLite's message.
    std::unexpected<Error> error(const char* what) const {
        return fail(ErrorCode::Io, "session database {}: {}: {}", mPath, what,
                    mDb ? sqlite3_errmsg(mDb) : "out of memory");
    }

    Result<void> exec(const char* sql) {
        char* message = nullptr;
        if (sqlite3_exec(mDb, sql, nullptr, nullptr, &message) == SQLITE_OK) return {};
        Error failure{ErrorCode::Io, fmt::format("session database {}: {}: {}", mPath, sql,
                                                 message ? message : sqlite3_errmsg(mDb))};
        sqlite3_free(message);
        return std::unexpected(std::move(failure));
    }

    Result<void> migrate() {
        Statement read(mDb, "PRAGMA user_version");
        if (!read.prepared() || read.step() != SQLITE_ROW)
            return fail(ErrorCode::Corrupt, "{} is not an SQLite database: {}", mPath,
                        sqlite3_errmsg(mDb));
        const int64_t schema = read.integer(0);
        if (schema > kSessionSchema)
            return fail(ErrorCode::Corrupt,
                        "{} has session schema {}, made by a newer picserver; this one knows "
                        "schemas up to {}",
                        mPath, schema, kSessionSchema);
        for (int64_t step = schema; step < kSessionSchema; ++step) {
            PIC_TRY(exec("BEGIN IMMEDIATE"));
            auto applied = exec(kMigrations[step]);
            if (applied)
                applied = exec(fmt::format("PRAGMA user_version = {}", step + 1).c_str());
            if (!applied) {
                (void)exec("ROLLBACK");
                return applied;
            }
            PIC_TRY(exec("COMMIT"));
        }
        return {};
    }

    Result<StoredSession> row(const Statement& select) const {
        return sessionFromRow(select.text(0), select.text(1), select.text(2), select.text(3),
                              select.integer(4), select.text(5), select.text(6), mPath);
    }

    /// Runs an INSERT of `session`'s columns; whether it changed a row.
    Result<bool> write(const StoredSession& session, const char* sql) {
        std::lock_guard lock(mMutex);
        Statement insert(mDb, sql);
        if (!insert.prepared()) return error("cannot write");
        insert.bind(1, session.id);
        insert.bind(2, session.editorDigest);
        insert.bind(3, session.viewerDigest);
        insert.bind(4, session.bakeId);
        insert.bind(5, int64_t(session.version));
        insert.bind(6, toJson(session.lights));
        insert.bind(7, unixMs());
        insert.bind(8, toJson(session.presets));
        if (insert.step() != SQLITE_DONE) return error("cannot write");
        return sqlite3_changes(mDb) > 0;
    }

    std::string mPath;
    int mLockFd = -1;
    sqlite3* mDb = nullptr;
    std::mutex mMutex;  ///< one statement at a time on the connection
};

bool startsWith(const std::string& path, const char* magic, size_t size) {
    std::ifstream file(path, std::ios::binary);
    std::string head(size, '\0');
    return file.read(head.data(), std::streamsize(size)) && head == std::string(magic, size);
}

/// Converts the JSON database at `path` into an SQLite file at the same path, keeping the
/// JSON as path.json. A crash part way leaves either the JSON at `path` (converted again at
/// the next start) or the finished SQLite file.
Result<void> convertJson(const std::string& path, int lockFd) {
    std::ifstream file(path, std::ios::binary);
    const std::string text{std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
    PIC_TRY_ASSIGN(std::vector<StoredSession> sessions, parseJsonSessions(text, path));
    const std::string fresh = path + ".sqlite-new";
    std::error_code ec;
    fs::remove(fresh, ec);
    fs::remove(fresh + "-wal", ec);
    fs::remove(fresh + "-shm", ec);
    {
        SqliteStore store(fresh, ::dup(lockFd));
        PIC_TRY(store.openDatabase());
        for (const StoredSession& session : sessions) PIC_TRY(store.create(session));
    }
    const std::string kept = path + ".json";
    fs::remove(kept, ec);
    fs::create_hard_link(path, kept, ec);
    if (ec || std::rename(fresh.c_str(), path.c_str()) != 0)
        return fail(ErrorCode::Io, "cannot replace the JSON session database {} by its SQLite form {}",
                    path, fresh);
    std::fprintf(stderr,
                 "picserver: %zu sessions moved from the JSON database %s into SQLite; the JSON "
                 "is kept as %s\n",
                 sessions.size(), path.c_str(), kept.c_str());
    return {};
}

}  // namespace

Result<std::unique_ptr<SessionStore>> openSqliteStore(const std::string& path) {
    const std::string lockPath = path + ".lock";
    const int lockFd = ::open(lockPath.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0600);
    if (lockFd < 0)
        return fail(ErrorCode::InvalidInput, "--db {}: cannot create its lock file {}: {}", path,
                    lockPath, std::strerror(errno));
    if (::flock(lockFd, LOCK_EX | LOCK_NB) != 0) {
        ::close(lockFd);
        return fail(ErrorCode::InvalidInput,
                    "--db {} is in use by another picserver (it holds {}); give each server its "
                    "own file, or share a PostgreSQL database between replicas",
                    path, lockPath);
    }
    std::error_code ec;
    const auto size = fs::file_size(path, ec);
    if (!ec && size > 0 && !startsWith(path, "SQLite format 3", 16)) {
        if (auto converted = convertJson(path, lockFd); !converted) {
            ::close(lockFd);
            return std::unexpected(converted.error());
        }
    }
    auto store = std::make_unique<SqliteStore>(path, lockFd);
    PIC_TRY(store->openDatabase());
    return std::unique_ptr<SessionStore>(std::move(store));
}

}  // namespace pic
