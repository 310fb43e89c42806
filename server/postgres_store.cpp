/// The PostgreSQL session store (server/session_store.h), over libpq: one connection, used
/// by one statement at a time and re-established when it breaks. Each write is one
/// statement in its own transaction, committed (synchronous_commit as the server sets it)
/// before the call returns. Schema migrations run under an advisory lock, so that replicas
/// starting together migrate once.

#include <chrono>
#include <memory>
#include <mutex>

#include <libpq-fe.h>

#include "server/session_store.h"

namespace pic {

namespace {

/// As the SQLite store's (server/sqlite_store.cpp), in PostgreSQL's types.
constexpr const char* kMigrations[] = {
    // 0 → 1: one row per session.
    "CREATE TABLE sessions ("
    "  id TEXT PRIMARY KEY,"
    "  editor_token_sha256 TEXT NOT NULL,"
    "  viewer_token_sha256 TEXT NOT NULL,"
    "  bake_id TEXT NOT NULL,"
    "  version BIGINT NOT NULL,"
    "  lights TEXT NOT NULL,"
    "  created_unix_ms BIGINT NOT NULL,"
    "  updated_unix_ms BIGINT NOT NULL)",
    // 1 → 2: each session's presets, a JSON object name → light set.
    "ALTER TABLE sessions ADD COLUMN IF NOT EXISTS presets TEXT NOT NULL DEFAULT '{}'",
};
static_assert(std::size(kMigrations) == kSessionSchema);

/// Any constant: the key of the advisory lock that serialises migrations.
constexpr const char* kMigrationLock = "SELECT pg_advisory_xact_lock(7370320)";

constexpr const char* kColumns =
    "id, editor_token_sha256, viewer_token_sha256, bake_id, version, lights, presets";

int64_t unixMs() {
    return std::chrono::duration_cast<std::chrono::milliseconds>(
               std::chrono::system_clock::now().time_since_epoch())
        .count();
}

using ResultPtr = std::unique_ptr<PGresult, decltype(&PQclear)>;

/// libpq's multi-line messages as one line for the log: runs of white space become a space.
std::string oneLine(const std::string& text) {
    std::string line;
    for (char c : text) {
        const bool space = c == '\n' || c == '\t' || c == ' ';
        if (space && (line.empty() || line.back() == ' ')) continue;
        line += space ? ' ' : c;
    }
    while (!line.empty() && line.back() == ' ') line.pop_back();
    return line;
}

class PostgresStore final : public SessionStore {
public:
    explicit PostgresStore(std::string uri) : mUri(std::move(uri)) {}
    ~PostgresStore() override {
        if (mConn) PQfinish(mConn);
    }

    Result<void> connect() {
        std::lock_guard lock(mMutex);
        PIC_TRY(ensureConnected());
        return migrate();
    }

    std::string describe() const override { return mWhere; }
    bool shared() const override { return true; }

    Result<std::vector<StoredSession>> loadAll() override {
        std::lock_guard lock(mMutex);
        PIC_TRY_ASSIGN(ResultPtr rows,
                       query(fmt::format("SELECT {} FROM sessions ORDER BY created_unix_ms, id",
                                         kColumns),
                             {}, PGRES_TUPLES_OK, /*read=*/true));
        std::vector<StoredSession> sessions;
        for (int i = 0; i < PQntuples(rows.get()); ++i) {
            PIC_TRY_ASSIGN(StoredSession session, row(rows.get(), i));
            sessions.push_back(std::move(session));
        }
        return sessions;
    }

    Result<std::optional<StoredSession>> find(const std::string& id) override {
        std::lock_guard lock(mMutex);
        PIC_TRY_ASSIGN(ResultPtr rows,
                       query(fmt::format("SELECT {} FROM sessions WHERE id = $1", kColumns), {id},
                             PGRES_TUPLES_OK, /*read=*/true));
        if (PQntuples(rows.get()) == 0) return std::optional<StoredSession>();
        PIC_TRY_ASSIGN(StoredSession session, row(rows.get(), 0));
        return std::optional<StoredSession>(std::move(session));
    }

    Result<bool> create(const StoredSession& session) override {
        return write(session,
                     "INSERT INTO sessions (id, editor_token_sha256, viewer_token_sha256, bake_id, "
                     "version, lights, presets, created_unix_ms, updated_unix_ms) "
                     "VALUES ($1, $2, $3, $4, $5, $6, $8, $7, $7) ON CONFLICT (id) DO NOTHING");
    }

    Result<bool> save(const StoredSession& session) override {
        return write(session,
                     "INSERT INTO sessions (id, editor_token_sha256, viewer_token_sha256, bake_id, "
                     "version, lights, presets, created_unix_ms, updated_unix_ms) "
                     "VALUES ($1, $2, $3, $4, $5, $6, $8, $7, $7) ON CONFLICT (id) DO UPDATE SET "
                     "version = excluded.version, lights = excluded.lights, "
                     "updated_unix_ms = excluded.updated_unix_ms "
                     "WHERE excluded.version > sessions.version");
    }

    Result<bool> savePresets(const StoredSession& session) override {
        return write(session,
                     "INSERT INTO sessions (id, editor_token_sha256, viewer_token_sha256, bake_id, "
                     "version, lights, presets, created_unix_ms, updated_unix_ms) "
                     "VALUES ($1, $2, $3, $4, $5, $6, $8, $7, $7) ON CONFLICT (id) DO UPDATE SET "
                     "presets = excluded.presets, updated_unix_ms = excluded.updated_unix_ms "
                     "WHERE excluded.version >= sessions.version");
    }

    Result<void> remove(const std::string& id, uint64_t version) override {
        std::lock_guard lock(mMutex);
        PIC_TRY(query("DELETE FROM sessions WHERE id = $1 AND version <= $2",
                      {id, std::to_string(version)}, PGRES_COMMAND_OK));
        return {};
    }

    Result<void> ping() override {
        std::lock_guard lock(mMutex);
        PIC_TRY(query("SELECT 1", {}, PGRES_TUPLES_OK, /*read=*/true));
        return {};
    }

private:
    /// Connects when there is no connection or it broke; Io naming where on failure.
    Result<void> ensureConnected() {
        if (mConn && PQstatus(mConn) == CONNECTION_OK) return {};
        if (mConn) {
            PQreset(mConn);
        } else {
            // Keywords before the URI, so that the URI's own settings win.
            const char* keys[] = {"connect_timeout", "application_name", "dbname", nullptr};
            const char* values[] = {"5", "picserver", mUri.c_str(), nullptr};
            mConn = PQconnectdbParams(keys, values, /*expand_dbname=*/1);
        }
        if (!mConn) return fail(ErrorCode::Io, "cannot connect to PostgreSQL: out of memory");
        if (PQstatus(mConn) != CONNECTION_OK)
            return fail(ErrorCode::Io, "cannot connect to the session database {}: {}",
                        redacted(), message());
        mWhere = fmt::format("postgresql {}:{}/{}", PQhost(mConn), PQport(mConn), PQdb(mConn));
        // Notices ("relation already exists, skipping") are not the log's business.
        PQsetNoticeProcessor(mConn, [](void*, const char*) {}, nullptr);
        // A database that stops answering fails the call instead of holding it forever.
        PGresult* set = PQexec(mConn, "SET statement_timeout = 10000");
        PQclear(set);
        return {};
    }

    /// The URI without its password, for messages.
    std::string redacted() const {
        const size_t scheme = mUri.find("://");
        const size_t at = mUri.find('@');
        if (scheme == std::string::npos || at == std::string::npos || at < scheme) return mUri;
        const size_t colon = mUri.find(':', scheme + 3);
        if (colon == std::string::npos || colon > at) return mUri;
        return mUri.substr(0, colon) + ":***" + mUri.substr(at);
    }

    std::string message() const { return oneLine(mConn ? PQerrorMessage(mConn) : "no connection"); }

    /// Runs `sql` with text parameters; Io naming the database and PostgreSQL's message
    /// unless the result has `expected`. A broken connection is re-established at the next
    /// call, and within this one for a `read` (a write is not sent twice: the first may have
    /// committed before the connection broke).
    Result<ResultPtr> query(const std::string& sql, const std::vector<std::string>& params,
                            ExecStatusType expected, bool read = false) {
        std::vector<const char*> values;
        for (const std::string& param : params) values.push_back(param.c_str());
        for (int attempt = 0;; ++attempt) {
            PIC_TRY(ensureConnected());
            ResultPtr result(PQexecParams(mConn, sql.c_str(), int(values.size()), nullptr,
                                          values.data(), nullptr, nullptr, 0),
                             &PQclear);
            if (result && PQresultStatus(result.get()) == expected) return result;
            if (read && attempt == 0 && PQstatus(mConn) != CONNECTION_OK) continue;
            return fail(ErrorCode::Io, "session database {}: {}", mWhere,
                        oneLine(result ? PQresultErrorMessage(result.get()) : message()));
        }
    }

    Result<void> migrate() {
        PIC_TRY(query("BEGIN", {}, PGRES_COMMAND_OK));
        auto migrated = [&]() -> Result<void> {
            PIC_TRY(query(kMigrationLock, {}, PGRES_TUPLES_OK));
            PIC_TRY(query("CREATE TABLE IF NOT EXISTS pic_schema (version INTEGER NOT NULL)", {},
                          PGRES_COMMAND_OK));
            PIC_TRY_ASSIGN(ResultPtr rows, query("SELECT version FROM pic_schema", {}, PGRES_TUPLES_OK));
            int schema = 0;
            if (PQntuples(rows.get()) > 0) {
                schema = std::atoi(PQgetvalue(rows.get(), 0, 0));
            } else {
                PIC_TRY(query("INSERT INTO pic_schema (version) VALUES (0)", {}, PGRES_COMMAND_OK));
            }
            if (schema > kSessionSchema)
                return fail(ErrorCode::Corrupt,
                            "{} has session schema {}, made by a newer picserver; this one knows "
                            "schemas up to {}",
                            mWhere, schema, kSessionSchema);
            for (int step = schema; step < kSessionSchema; ++step)
                PIC_TRY(query(kMigrations[step], {}, PGRES_COMMAND_OK));
            PIC_TRY(query(fmt::format("UPDATE pic_schema SET version = {}",
                                      std::max(schema, kSessionSchema)),
                          {}, PGRES_COMMAND_OK));
            return {};
        }();
        PIC_TRY(query(migrated ? "COMMIT" : "ROLLBACK", {}, PGRES_COMMAND_OK));
        return migrated;
    }

    Result<StoredSession> row(const PGresult* rows, int i) const {
        return sessionFromRow(PQgetvalue(rows, i, 0), PQgetvalue(rows, i, 1),
                              PQgetvalue(rows, i, 2), PQgetvalue(rows, i, 3),
                              std::atoll(PQgetvalue(rows, i, 4)), PQgetvalue(rows, i, 5),
                              PQgetvalue(rows, i, 6), mWhere);
    }

    Result<bool> write(const StoredSession& session, const char* sql) {
        std::lock_guard lock(mMutex);
        PIC_TRY_ASSIGN(
            ResultPtr result,
            query(sql,
                  {session.id, session.editorDigest, session.viewerDigest, session.bakeId,
                   std::to_string(session.version), toJson(session.lights),
                   std::to_string(unixMs()), toJson(session.presets)},
                  PGRES_COMMAND_OK));
        return std::string(PQcmdTuples(result.get())) != "0";
    }

    std::string mUri;
    std::string mWhere = "postgresql";
    PGconn* mConn = nullptr;
    std::mutex mMutex;  ///< one statement at a time on the connection
};

}  // namespace

Result<std::unique_ptr<SessionStore>> openPostgresStore(const std::string& uri) {
    auto store = std::make_unique<PostgresStore>(uri);
    PIC_TRY(store->connect());
    return std::unique_ptr<SessionStore>(std::move(store));
}

}  // namespace pic
