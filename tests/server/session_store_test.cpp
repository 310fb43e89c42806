// The session store (server/session_store.h): the same tests on SQLite and on a real
// PostgreSQL started for them, then what only one backend does (SQLite's one server per
// file and conversion of the JSON database; PostgreSQL's errors for an unreachable server).

#include "server/session_store.h"

#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include <gtest/gtest.h>
#include <libpq-fe.h>
#include <nlohmann/json.hpp>
#include <sqlite3.h>
#include <sys/stat.h>

#include "server/token_digest.h"
#include "tests/support/command.h"
#include "tests/support/postgres.h"

namespace pic {
namespace {

namespace fs = std::filesystem;

LightSet lampAt(float x) {
    LightSet lights;
    Light light;
    light.id = "lamp";
    light.type = LightType::Point;
    light.position = glm::vec3(x, 0.5f, 0.0f);
    light.intensity = 4.0f;
    lights.lights.push_back(light);
    return lights;
}

StoredSession sessionNamed(const std::string& id, uint64_t version = 1, float x = 0.0f) {
    return {id, tokenDigest(id + "-editor"), tokenDigest(id + "-viewer"), "bake-1", version,
            lampAt(x)};
}

/// "true", "false" or the error, for messages that say what went wrong.
std::string outcome(const Result<bool>& result) {
    return result ? (*result ? "true" : "false") : "error: " + result.error().message;
}

/// One PostgreSQL for the whole suite: starting a cluster takes seconds.
test::PostgresServer* sharedPostgres(std::string& why) {
    static std::string startFailure;
    static std::unique_ptr<test::PostgresServer> server = test::PostgresServer::start(startFailure);
    why = startFailure;
    return server.get();
}

/// Runs `sql` on the PostgreSQL at `uri`; whether it succeeded.
bool postgresExec(const std::string& uri, const std::string& sql) {
    PGconn* conn = PQconnectdb(uri.c_str());
    PQsetNoticeProcessor(conn, [](void*, const char*) {}, nullptr);
    PGresult* result = PQexec(conn, sql.c_str());
    const ExecStatusType status = PQresultStatus(result);
    PQclear(result);
    PQfinish(conn);
    return status == PGRES_COMMAND_OK || status == PGRES_TUPLES_OK;
}

/// The backend under test: a fresh, empty database of its kind.
class SessionStoreTest : public testing::TestWithParam<std::string> {
protected:
    void SetUp() override {
        if (GetParam() == "postgresql") {
            std::string why;
            test::PostgresServer* server = sharedPostgres(why);
            ASSERT_NE(server, nullptr) << why;
            ASSERT_TRUE(postgresExec(server->uri(), "DROP TABLE IF EXISTS sessions, pic_schema"));
            mSpec = server->uri();
        } else {
            mSpec = (mDir / "sessions.db").string();
        }
    }

    std::unique_ptr<SessionStore> open() {
        auto store = SessionStore::open(mSpec);
        EXPECT_TRUE(store) << (store ? "" : store.error().message);
        return store ? std::move(*store) : nullptr;
    }

    /// Sets the stored schema version, as a newer picserver would have left it.
    void setSchema(int version) {
        if (GetParam() == "postgresql") {
            ASSERT_TRUE(postgresExec(mSpec, "UPDATE pic_schema SET version = " + std::to_string(version)));
        } else {
            sqlite3* db = nullptr;
            ASSERT_EQ(sqlite3_open(mSpec.c_str(), &db), SQLITE_OK);
            EXPECT_EQ(sqlite3_exec(db, ("PRAGMA user_version = " + std::to_string(version)).c_str(),
                                   nullptr, nullptr, nullptr),
                      SQLITE_OK);
            sqlite3_close(db);
        }
    }

    test::ScratchDir mDir{"pic_store"};
    std::string mSpec;
};

TEST_P(SessionStoreTest, RowsAreCreatedFoundSavedOnlyForwardAndRemoved) {
    auto store = open();
    ASSERT_TRUE(store);
    EXPECT_EQ(store->shared(), GetParam() == "postgresql");
    EXPECT_NE(store->describe().find(GetParam() == "postgresql" ? "postgresql" : "sqlite"),
              std::string::npos);
    ASSERT_TRUE(store->ping());

    auto none = store->find("a");
    ASSERT_TRUE(none);
    EXPECT_FALSE(*none);
    ASSERT_EQ(outcome(store->create(sessionNamed("a"))), "true");
    EXPECT_EQ(outcome(store->create(sessionNamed("a", 1, 0.3f))), "false") << "the id is taken";
    ASSERT_EQ(outcome(store->create(sessionNamed("b"))), "true");

    auto found = store->find("a");
    ASSERT_TRUE(found && *found);
    EXPECT_EQ((*found)->editorDigest, tokenDigest("a-editor"));
    EXPECT_EQ((*found)->viewerDigest, tokenDigest("a-viewer"));
    EXPECT_EQ((*found)->bakeId, "bake-1");
    EXPECT_EQ((*found)->version, 1u);
    EXPECT_EQ(toJson((*found)->lights), toJson(lampAt(0.0f)));

    // Versions only go forward: the same or an older one is refused and changes nothing.
    EXPECT_EQ(outcome(store->save(sessionNamed("a", 3, 0.25f))), "true");
    EXPECT_EQ(outcome(store->save(sessionNamed("a", 3, 0.75f))), "false");
    EXPECT_EQ(outcome(store->save(sessionNamed("a", 2, 0.75f))), "false");
    found = store->find("a");
    ASSERT_TRUE(found && *found);
    EXPECT_EQ((*found)->version, 3u);
    EXPECT_EQ(toJson((*found)->lights), toJson(lampAt(0.25f)));

    // A removal by a server that holds an older version leaves the row.
    ASSERT_TRUE(store->remove("a", 2));
    found = store->find("a");
    ASSERT_TRUE(found && *found);
    ASSERT_TRUE(store->remove("a", 3));
    found = store->find("a");
    ASSERT_TRUE(found);
    EXPECT_FALSE(*found);
    // A save after a removal puts the row back (a server still carrying the session), created
    // now: a millisecond after "b" at least, so that "b" is the older (rows created in the same
    // millisecond come in id order).
    std::this_thread::sleep_for(std::chrono::milliseconds(3));
    EXPECT_EQ(outcome(store->save(sessionNamed("a", 4, 0.5f))), "true");

    auto all = store->loadAll();
    ASSERT_TRUE(all);
    ASSERT_EQ(all->size(), 2u);
    EXPECT_EQ(all->front().id, "b") << "oldest first";
    EXPECT_EQ(all->back().version, 4u);
}

TEST_P(SessionStoreTest, WritesSurviveReopeningAndReachAnotherConnection) {
    {
        auto store = open();
        ASSERT_TRUE(store);
        ASSERT_EQ(outcome(store->create(sessionNamed("kept"))), "true");
        ASSERT_EQ(outcome(store->save(sessionNamed("kept", 7, 0.125f))), "true");
    }
    auto reopened = open();
    ASSERT_TRUE(reopened);
    auto found = reopened->find("kept");
    ASSERT_TRUE(found && *found);
    EXPECT_EQ((*found)->version, 7u);
    EXPECT_EQ(toJson((*found)->lights), toJson(lampAt(0.125f)));
    if (GetParam() != "postgresql") return;
    // Two replicas on one database: the newer version wins whoever writes it.
    auto other = open();
    ASSERT_TRUE(other);
    EXPECT_EQ(outcome(other->save(sessionNamed("kept", 8))), "true");
    EXPECT_EQ(outcome(reopened->save(sessionNamed("kept", 8))), "false");
    auto seen = reopened->find("kept");
    ASSERT_TRUE(seen && *seen);
    EXPECT_EQ((*seen)->version, 8u);
}

TEST_P(SessionStoreTest, ADatabaseOfANewerSchemaIsRefused) {
    ASSERT_TRUE(open());
    setSchema(kSessionSchema + 1);
    auto refused = SessionStore::open(mSpec);
    ASSERT_FALSE(refused);
    EXPECT_EQ(refused.error().code, ErrorCode::Corrupt);
    EXPECT_NE(refused.error().message.find("newer picserver"), std::string::npos)
        << refused.error().message;
}

/// The presets of row `id` as their JSON, or what went wrong.
std::string presetsOf(SessionStore& store, const std::string& id) {
    auto found = store.find(id);
    if (!found) return "error: " + found.error().message;
    if (!*found) return "no row";
    return toJson((*found)->presets);
}

TEST_P(SessionStoreTest, PresetsAreSavedUnlessANewerVersionIsStored) {
    auto store = open();
    ASSERT_TRUE(store);
    ASSERT_EQ(outcome(store->create(sessionNamed("a"))), "true");
    EXPECT_EQ(presetsOf(*store, "a"), "{}");

    StoredSession row = sessionNamed("a");
    row.presets = {{"Left", lampAt(-0.5f)}, {"right 2", lampAt(0.5f)}};
    ASSERT_EQ(outcome(store->savePresets(row)), "true");
    EXPECT_EQ(presetsOf(*store, "a"), toJson(row.presets));

    // A light set leaves them; the row's version and light set stay what save() wrote.
    ASSERT_EQ(outcome(store->save(sessionNamed("a", 3, 0.25f))), "true");
    EXPECT_EQ(presetsOf(*store, "a"), toJson(row.presets));
    // A server whose copy is behind (version 2) changes nothing; one at the stored version
    // (or past it: a restored session counts on from the stored version) does.
    row.version = 2;
    row.presets.erase("Left");
    EXPECT_EQ(outcome(store->savePresets(row)), "false");
    EXPECT_EQ(presetsOf(*store, "a"),
              toJson(LightPresets{{"Left", lampAt(-0.5f)}, {"right 2", lampAt(0.5f)}}));
    row.version = 3;
    ASSERT_EQ(outcome(store->savePresets(row)), "true");
    EXPECT_EQ(presetsOf(*store, "a"), toJson(row.presets));
    row.version = 4;
    row.presets.clear();
    ASSERT_EQ(outcome(store->savePresets(row)), "true");
    auto found = store->find("a");
    ASSERT_TRUE(found && *found);
    EXPECT_TRUE((*found)->presets.empty());
    EXPECT_EQ((*found)->version, 3u) << "presets do not move the version";
    EXPECT_EQ(toJson((*found)->lights), toJson(lampAt(0.25f)));

    // Gone (removed as idle), the row comes back with them, as save() brings it back.
    ASSERT_TRUE(store->remove("a", 3));
    row.presets = {{"back", lampAt(0.125f)}};
    ASSERT_EQ(outcome(store->savePresets(row)), "true");
    EXPECT_EQ(presetsOf(*store, "a"), toJson(row.presets));
    // And save() of a row that is gone writes its presets too.
    ASSERT_TRUE(store->remove("a", 4));
    StoredSession saved = sessionNamed("a", 5);
    saved.presets = {{"again", lampAt(0.0f)}};
    ASSERT_EQ(outcome(store->save(saved)), "true");
    EXPECT_EQ(presetsOf(*store, "a"), toJson(saved.presets));
}

// A database of schema 1 (before presets) keeps its sessions and gains the presets column at
// open, every session's presets empty.
TEST_P(SessionStoreTest, ADatabaseOfSchemaOneGainsPresets) {
    const std::string createV1 =
        "CREATE TABLE sessions (id TEXT PRIMARY KEY, editor_token_sha256 TEXT NOT NULL, "
        "viewer_token_sha256 TEXT NOT NULL, bake_id TEXT NOT NULL, version BIGINT NOT NULL, "
        "lights TEXT NOT NULL, created_unix_ms BIGINT NOT NULL, updated_unix_ms BIGINT NOT NULL)";
    const std::string insert =
        fmt::format("INSERT INTO sessions VALUES ('old', '{}', '{}', 'bake-1', 6, '{}', 1, 1)",
                    tokenDigest("old-editor"), tokenDigest("old-viewer"), toJson(lampAt(0.75f)));
    if (GetParam() == "postgresql") {
        ASSERT_TRUE(postgresExec(mSpec, "CREATE TABLE pic_schema (version INTEGER NOT NULL)"));
        ASSERT_TRUE(postgresExec(mSpec, "INSERT INTO pic_schema (version) VALUES (1)"));
        ASSERT_TRUE(postgresExec(mSpec, createV1));
        ASSERT_TRUE(postgresExec(mSpec, insert));
    } else {
        sqlite3* db = nullptr;
        ASSERT_EQ(sqlite3_open(mSpec.c_str(), &db), SQLITE_OK);
        for (const std::string& sql : {createV1, insert, std::string("PRAGMA user_version = 1")})
            EXPECT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK) << sql;
        sqlite3_close(db);
    }
    {
        auto store = open();
        ASSERT_TRUE(store);
        auto found = store->find("old");
        ASSERT_TRUE(found && *found) << (found ? "no row" : found.error().message);
        EXPECT_EQ((*found)->version, 6u);
        EXPECT_EQ(toJson((*found)->lights), toJson(lampAt(0.75f)));
        EXPECT_TRUE((*found)->presets.empty());
        StoredSession row = **found;
        row.presets = {{"kept", lampAt(0.5f)}};
        ASSERT_EQ(outcome(store->savePresets(row)), "true");
    }
    auto reopened = open();
    ASSERT_TRUE(reopened);
    EXPECT_EQ(presetsOf(*reopened, "old"), toJson(LightPresets{{"kept", lampAt(0.5f)}}));
}

TEST_P(SessionStoreTest, ConcurrentWritersEachGetTheirRowsIn) {
    auto store = open();
    ASSERT_TRUE(store);
    std::vector<std::thread> writers;
    for (int w = 0; w < 4; ++w)
        writers.emplace_back([&, w] {
            for (int i = 0; i < 10; ++i) {
                const std::string id = fmt::format("w{}-{}", w, i);
                EXPECT_EQ(outcome(store->create(sessionNamed(id))), "true") << id;
                EXPECT_EQ(outcome(store->save(sessionNamed(id, 2))), "true") << id;
            }
        });
    for (auto& writer : writers) writer.join();
    auto all = store->loadAll();
    ASSERT_TRUE(all);
    EXPECT_EQ(all->size(), 40u);
}

INSTANTIATE_TEST_SUITE_P(Backends, SessionStoreTest, testing::Values("sqlite", "postgresql"),
                         [](const auto& info) { return info.param; });

// Two servers given one SQLite file would overwrite each other's sessions: the second is
// refused, naming the file, until the first has closed it.
TEST(SqliteStore, OneServerPerFile) {
    const test::ScratchDir dir("pic_store_lock");
    const std::string path = (dir / "sessions.db").string();
    auto first = SessionStore::open(path);
    ASSERT_TRUE(first) << first.error().message;
    auto second = SessionStore::open(path);
    ASSERT_FALSE(second);
    EXPECT_EQ(second.error().code, ErrorCode::InvalidInput);
    EXPECT_NE(second.error().message.find("in use by another picserver"), std::string::npos)
        << second.error().message;
    EXPECT_NE(second.error().message.find(path), std::string::npos);
    first->reset();
    EXPECT_TRUE(SessionStore::open(path));
}

TEST(SqliteStore, TheFileIsPrivate) {
    const test::ScratchDir dir("pic_store_private");
    const fs::path path = dir / "sessions.db";
    auto store = SessionStore::open(path.string());
    ASSERT_TRUE(store);
    ASSERT_EQ(outcome((*store)->create(sessionNamed("a"))), "true");
    for (const fs::path& file : {path, fs::path(path.string() + "-wal")}) {
        SCOPED_TRACE(file.string());
        ASSERT_TRUE(fs::exists(file));
        EXPECT_EQ(fs::status(file).permissions() & (fs::perms::group_all | fs::perms::others_all),
                  fs::perms::none);
    }
}

// The JSON database of earlier releases (format 1 with plain tokens, format 2 with their
// digests) becomes an SQLite file at the same path, its sessions kept, the JSON beside it.
TEST(SqliteStore, TheJsonDatabaseIsConvertedInPlace) {
    for (int format : {1, 2}) {
        SCOPED_TRACE(format);
        const test::ScratchDir dir("pic_store_json" + std::to_string(format));
        const fs::path path = dir / "sessions.json";
        nlohmann::json entry = {{"id", "s1"}, {"bake_id", "bake-1"}, {"version", 5},
                                {"lights", nlohmann::json::parse(toJson(lampAt(0.5f)))}};
        if (format == 1) {
            entry["editor_token"] = "editor-token";
            entry["viewer_token"] = "viewer-token";
        } else {
            entry["editor_token_sha256"] = tokenDigest("editor-token");
            entry["viewer_token_sha256"] = tokenDigest("viewer-token");
        }
        const nlohmann::json root = {{"format", format}, {"sessions", {entry}}};
        std::ofstream(path) << root.dump(2);

        auto store = SessionStore::open(path.string());
        ASSERT_TRUE(store) << store.error().message;
        auto found = (*store)->find("s1");
        ASSERT_TRUE(found && *found);
        EXPECT_EQ((*found)->editorDigest, tokenDigest("editor-token"));
        EXPECT_EQ((*found)->viewerDigest, tokenDigest("viewer-token"));
        EXPECT_EQ((*found)->version, 5u);
        EXPECT_EQ(toJson((*found)->lights), toJson(lampAt(0.5f)));
        store->reset();
        EXPECT_TRUE(test::readFile(path).starts_with("SQLite format 3"));
        EXPECT_EQ(nlohmann::json::parse(test::readFile(path.string() + ".json")), root)
            << "the JSON is kept beside it";
        EXPECT_EQ(test::readFile(path).find("editor-token"), std::string::npos)
            << "no token in the database";
    }
}

TEST(SqliteStore, AFileThatIsNeitherSqliteNorJsonIsRefusedNamingIt) {
    const test::ScratchDir dir("pic_store_junk");
    const fs::path path = dir / "sessions.db";
    std::ofstream(path) << "not a database";
    auto refused = SessionStore::open(path.string());
    ASSERT_FALSE(refused);
    EXPECT_EQ(refused.error().code, ErrorCode::Corrupt);
    EXPECT_NE(refused.error().message.find(path.string()), std::string::npos);
    EXPECT_EQ(test::readFile(path), "not a database") << "left as it was";
}

TEST(PostgresStore, AnUnreachableServerIsAnIoErrorNamingItWithoutThePassword) {
    // A port nothing listens on: the one a fresh server was on, after it stopped.
    std::string why;
    int port = 0;
    {
        auto server = test::PostgresServer::start(why);
        ASSERT_TRUE(server) << why;
        port = server->port();
    }
    const std::string uri =
        "postgresql://pic:secret-password@127.0.0.1:" + std::to_string(port) + "/postgres";
    auto refused = SessionStore::open(uri);
    ASSERT_FALSE(refused);
    EXPECT_EQ(refused.error().code, ErrorCode::Io);
    EXPECT_NE(refused.error().message.find("127.0.0.1"), std::string::npos) << refused.error().message;
    EXPECT_EQ(refused.error().message.find("secret-password"), std::string::npos)
        << refused.error().message;
}

// While PostgreSQL is away every call fails with Io; once it is back the same store works
// again without being reopened.
TEST(PostgresStore, ACallAfterTheServerCameBackSucceeds) {
    std::string why;
    auto server = test::PostgresServer::start(why);
    ASSERT_TRUE(server) << why;
    auto store = SessionStore::open(server->uri());
    ASSERT_TRUE(store) << store.error().message;
    ASSERT_EQ(outcome((*store)->create(sessionNamed("a"))), "true");
    ASSERT_TRUE(server->stop());
    auto failed = (*store)->save(sessionNamed("a", 2));
    ASSERT_FALSE(failed);
    EXPECT_EQ(failed.error().code, ErrorCode::Io);
    EXPECT_FALSE((*store)->ping());
    ASSERT_TRUE(server->resume());
    EXPECT_TRUE((*store)->ping());
    EXPECT_EQ(outcome((*store)->save(sessionNamed("a", 2))), "true");
}

}  // namespace
}  // namespace pic
