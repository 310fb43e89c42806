// The server's session database (picserver --db) seen from clients: sessions and their
// presets survive a restart, light sets a SIGKILL right after a reply, one server per SQLite
// file, the JSON database of earlier releases carried on, the drain on SIGTERM, and on a real
// PostgreSQL: replicas that hand a session and its presets over through the database, and
// health NOT_SERVING while it is away. Every server a test starts is stopped by it.
#include <gtest/gtest.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "proto/wire.h"
#include "server/session_store.h"
#include "server/token_digest.h"
#include "tests/client/stream_fixture.h"
#include "tests/support/command.h"
#include "tests/support/postgres.h"

namespace pic {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using namespace test;

/// The version a SetLights call gave, or its error.
std::string outcome(const Result<uint64_t>& version) {
    return version ? std::to_string(*version) : "error: " + version.error().message;
}

/// A server with the browsers' endpoint on the session database `db` (no light-set rate limit).
ServerOptions webOn(const std::string& db) {
    ServerOptions options;
    options.session.setLightsPerSecond = 1e6;
    options.webListen = "127.0.0.1:0";
    options.dbPath = db;
    return options;
}

/// "/v1/presets?session=ID&token=T".
std::string presetsPath(const std::string& id, const std::string& token) {
    return "/v1/presets?session=" + id + "&token=" + token;
}

/// The presets GET /v1/presets lists, each as "name: light set JSON", or what went wrong.
std::vector<std::string> presetsOn(const std::string& address, const std::string& id,
                                   const std::string& token) {
    const HttpReply reply = httpGet(address, presetsPath(id, token));
    if (reply.code() != 200) return {reply.status + " " + reply.body};
    const nlohmann::json body = nlohmann::json::parse(reply.body, nullptr, false);
    if (!body.is_object() || !body.contains("presets")) return {"not presets: " + reply.body};
    std::vector<std::string> presets;
    for (const nlohmann::json& preset : body["presets"]) {
        auto lights = parseLightSet(preset.value("lights", nlohmann::json()).dump());
        presets.push_back(preset.value("name", "") + ": " +
                          (lights ? toJson(*lights) : "error: " + lights.error().message));
    }
    return presets;
}

/// "name: light set JSON", as presetsOn lists a preset.
std::string presetOf(const std::string& name, const LightSet& lights) {
    return name + ": " + toJson(lights);
}

/// The light set a session holds now, as its JSON.
std::string lightsOf(PicConnection& connection, const std::string& id, const std::string& token) {
    auto joined = connection.joinSession(id, token);
    if (!joined) return "error: " + joined.error().message;
    auto lights = wire::fromProto(joined->lights());
    return lights ? toJson(*lights) : "error: " + lights.error().message;
}

TEST(SessionDatabase, SessionsSurviveARestart) {
    const test::ScratchDir dir("pic_sessions");
    const fs::path db = dir / "sessions.db";
    std::string id, editor, viewer;
    const LightSet lights = pointLight(0.25f);
    {
        Served served = serve("cpu", 32, std::chrono::hours(1), db.string());
        ASSERT_TRUE(served.connection);
        auto session = served.connection->createSession();
        ASSERT_TRUE(session);
        id = session->session();
        editor = session->editor_token();
        viewer = session->viewer_token();
        auto version = served.connection->setLights(id, editor, lights);
        ASSERT_TRUE(version);
        EXPECT_EQ(*version, 2u);
    }
    EXPECT_EQ(fs::status(db).permissions() & fs::perms::others_read, fs::perms::none)
        << "the database is private";
    {
        // It holds the tokens' digests, not the tokens.
        const std::string bytes = readFile(db);
        EXPECT_EQ(bytes.find(editor), std::string::npos);
        EXPECT_EQ(bytes.find(viewer), std::string::npos);
        EXPECT_NE(bytes.find(tokenDigest(viewer)), std::string::npos);
    }
    {
        Served restarted = serve("cpu", 32, std::chrono::hours(1), db.string());
        ASSERT_TRUE(restarted.connection);
        auto joined = restarted.connection->joinSession(id, viewer);
        ASSERT_TRUE(joined) << joined.error().message;
        EXPECT_EQ(joined->version(), 3u) << "versions go on after the restart";
        EXPECT_EQ(lightsOf(*restarted.connection, id, viewer), toJson(lights));
        Reader reader(*restarted.connection, id, viewer);
        EXPECT_TRUE(reader.waitFor(3));
        auto denied = restarted.connection->setLights(id, viewer, lights);
        EXPECT_FALSE(denied) << "roles survive too";
    }

    // A file that is not a database is refused, naming it.
    std::ofstream(db) << "not a database";
    auto refused = startWithDatabase(db.string());
    ASSERT_FALSE(refused);
    EXPECT_EQ(refused.error().code, ErrorCode::Corrupt);
    EXPECT_NE(refused.error().message.find(db.string()), std::string::npos);
}

// Presets are committed with the session: a server on the same file after a restart has
// the ones saved and not those deleted, and the light set stays as it was.
TEST(SessionDatabase, PresetsSurviveARestart) {
    const test::ScratchDir dir("pic_sessions_presets");
    const std::string db = (dir / "sessions.db").string();
    std::string id, editor, viewer;
    {
        Served served = serveWith(webOn(db));
        ASSERT_TRUE(served.connection);
        auto session = served.connection->createSession();
        ASSERT_TRUE(session);
        id = session->session();
        editor = session->editor_token();
        viewer = session->viewer_token();
        ASSERT_EQ(outcome(served.connection->setLights(id, editor, pointLight(0.25f))), "2");
        const std::string address = served.server->webAddress();
        for (const auto& [name, x] : {std::pair{"kept", 0.1f}, std::pair{"gone", 0.2f}})
            ASSERT_EQ(httpRequest(address, "PUT", presetsPath(id, editor) + "&name=" + name,
                                  toJson(pointLight(x)))
                          .code(),
                      200)
                << name;
        ASSERT_EQ(httpRequest(address, "DELETE", presetsPath(id, editor) + "&name=gone").code(),
                  200);
    }
    Served restarted = serveWith(webOn(db));
    ASSERT_TRUE(restarted.connection);
    EXPECT_EQ(presetsOn(restarted.server->webAddress(), id, viewer),
              std::vector<std::string>{presetOf("kept", pointLight(0.1f))});
    EXPECT_EQ(lightsOf(*restarted.connection, id, viewer), toJson(pointLight(0.25f)));
}

// A --db that cannot hold the database (a directory, or a file in a missing directory) is
// refused at start, naming the path, instead of aborting or serving without durability.
TEST(SessionDatabase, APathThatCannotHoldTheDatabaseIsRefused) {
    const test::ScratchDir dir("pic_sessions_path");
    for (const auto& [path, says] :
         {std::pair{dir.path().string(), std::string("is a directory")},
          std::pair{(dir / "missing" / "sessions.db").string(), std::string("does not exist")}}) {
        SCOPED_TRACE(path);
        auto refused = startWithDatabase(path);
        ASSERT_FALSE(refused);
        EXPECT_EQ(refused.error().code, ErrorCode::InvalidInput);
        EXPECT_NE(refused.error().message.find(path), std::string::npos) << refused.error().message;
        EXPECT_NE(refused.error().message.find(says), std::string::npos) << refused.error().message;
    }
    EXPECT_TRUE(SessionStore::checkPath((dir / "sessions.db").string()));
}

// A client with patience carries on across a restart of its server: the stream that the
// drain ends UNAVAILABLE subscribes again once the server is back on its address (a key
// frame of the restored version), and a light set sent while it is away goes through.
TEST(SessionDatabase, AClientWithPatienceCarriesOnAcrossARestart) {
    const test::ScratchDir dir("pic_sessions_patience");
    const std::string db = (dir / "sessions.db").string();
    ServerOptions options;
    options.dbPath = db;
    Served first = serveWith(options);
    ASSERT_TRUE(first.connection);
    const std::string address = first.server->address();
    auto connection = PicConnection::connect(address);
    ASSERT_TRUE(connection);
    (*connection)->setPatience(30s);
    auto session = (*connection)->createSession();
    ASSERT_TRUE(session) << session.error().message;
    const std::string id = session->session(), editor = session->editor_token();
    const v1::SceneHeader header = sceneHeaderOf(**connection);
    auto stream = (*connection)->subscribe(id, session->viewer_token(), 30s);
    FrameDecoder decoder(header);
    v1::Frame frame;
    ASSERT_TRUE(stream->next(frame));
    ASSERT_TRUE(decoder.apply(frame));
    EXPECT_EQ(decoder.version(), 1u);

    first.connection.reset();
    first.server.reset();  // drained: the stream ends UNAVAILABLE and tries again
    std::thread restart([&] {
        std::this_thread::sleep_for(500ms);
        ServeOptions serveOptions;
        serveOptions.backend = "cpu";
        serveOptions.bounces.bounces = 1;
        auto bake = ServedBake::load(bakePath(), kScene, serveOptions);
        ASSERT_TRUE(bake);
        std::vector<std::unique_ptr<ServedBake>> bakes;
        bakes.push_back(std::move(*bake));
        auto server = PicServer::start(std::move(bakes), address, options);
        ASSERT_TRUE(server) << server.error().message;
        first.server = std::move(*server);
    });
    // Sent while the server is away: retried until it is back.
    auto version = (*connection)->setLights(id, editor, pointLight(0.3f));
    restart.join();
    ASSERT_TRUE(version) << version.error().message;
    EXPECT_EQ(*version, 3u) << "restored at 2, then this set";
    while (decoder.version() < *version) {
        ASSERT_TRUE(stream->next(frame)) << stream->status().error_message();
        ASSERT_TRUE(decoder.apply(frame));
    }
    EXPECT_GE(stream->resubscriptions(), 1u);
    EXPECT_EQ(lightsOf(**connection, id, editor), toJson(pointLight(0.3f)));
    stream->cancel();
}

// Two servers on one file would each overwrite the other's sessions: the second is refused
// at start, naming the file.
TEST(SessionDatabase, TwoServersOnOneFileAreRefused) {
    const test::ScratchDir dir("pic_sessions_two");
    const std::string db = (dir / "sessions.db").string();
    auto first = startWithDatabase(db);
    ASSERT_TRUE(first) << first.error().message;
    auto second = startWithDatabase(db);
    ASSERT_FALSE(second);
    EXPECT_EQ(second.error().code, ErrorCode::InvalidInput);
    EXPECT_NE(second.error().message.find("in use by another picserver"), std::string::npos)
        << second.error().message;
}

// The JSON database of earlier releases (here format 1, with plain tokens) is carried on:
// its sessions open with their tokens, and it becomes an SQLite file with only digests.
TEST(SessionDatabase, TheJsonDatabaseOfEarlierReleasesIsCarriedOn) {
    const test::ScratchDir dir("pic_sessions_json");
    const fs::path db = dir / "sessions.json";
    std::string bakeId;
    {
        Served served = serve();
        ASSERT_TRUE(served.connection);
        auto session = served.connection->createSession();
        ASSERT_TRUE(session);
        bakeId = session->bake_id();
    }
    const std::string editor = "0123456789abcdef0123456789abcdef";
    const std::string viewer = "fedcba9876543210fedcba9876543210";
    const LightSet lights = pointLight(-0.2f);
    const nlohmann::json root = {
        {"format", 1},
        {"sessions",
         {{{"id", "00c0ffee00c0ffee"}, {"editor_token", editor}, {"viewer_token", viewer},
           {"bake_id", bakeId}, {"version", 4}, {"lights", nlohmann::json::parse(toJson(lights))}}}}};
    std::ofstream(db) << root.dump(2);
    {
        Served served = serve("cpu", 32, std::chrono::hours(1), db.string());
        ASSERT_TRUE(served.connection);
        auto joined = served.connection->joinSession("00c0ffee00c0ffee", viewer);
        ASSERT_TRUE(joined) << joined.error().message;
        EXPECT_EQ(joined->version(), 5u);
        EXPECT_EQ(lightsOf(*served.connection, "00c0ffee00c0ffee", viewer), toJson(lights));
        auto version = served.connection->setLights("00c0ffee00c0ffee", editor, pointLight(0.1f));
        EXPECT_TRUE(version) << (version ? "" : version.error().message);
    }
    const std::string bytes = readFile(db);
    EXPECT_TRUE(bytes.starts_with("SQLite format 3"));
    EXPECT_EQ(bytes.find(editor), std::string::npos);
    EXPECT_NE(bytes.find(tokenDigest(editor)), std::string::npos);
    EXPECT_EQ(nlohmann::json::parse(readFile(db.string() + ".json")), root) << "the JSON is kept";
}

/// picserver on the test bake with `--db db`, and its address once it listens ("" when it
/// did not start).
std::string startPicserver(Child& child, const std::string& db,
                           const std::vector<std::string>& extra = {}) {
    std::vector<std::string> args = {PIC_PICSERVER, "--bake", bakePath(), "--scene", kScene,
                                     "--listen", "127.0.0.1:0", "--backend", "cpu",
                                     "--bounces", "1", "--db", db};
    args.insert(args.end(), extra.begin(), extra.end());
    child = Child(args);
    const std::string first = readLine(child.out());
    if (!first.starts_with("listening on ")) return {};
    return first.substr(std::string("listening on ").size());
}

// A SetLights reply means the light set is committed: a server killed (SIGKILL) right after
// the reply comes back with that set, every time.
TEST(SessionDatabaseCli, AnAcknowledgedLightSetSurvivesSigkill) {
    const test::ScratchDir dir("pic_sessions_kill");
    const std::string db = (dir / "sessions.db").string();
    std::string id, editor;
    for (int round = 0; round < 5; ++round) {
        SCOPED_TRACE(round);
        Child server;
        const std::string address = startPicserver(server, db, {"--quiet"});
        ASSERT_FALSE(address.empty());
        auto connection = PicConnection::connect(address);
        ASSERT_TRUE(connection) << connection.error().message;
        if (round == 0) {
            auto session = (*connection)->createSession();
            ASSERT_TRUE(session) << session.error().message;
            id = session->session();
            editor = session->editor_token();
        } else {
            EXPECT_EQ(lightsOf(**connection, id, editor), toJson(pointLight(0.1f * float(round - 1))))
                << "the set acknowledged before the kill";
        }
        auto version = (*connection)->setLights(id, editor, pointLight(0.1f * float(round)));
        ASSERT_TRUE(version) << version.error().message;
        server.signal(SIGKILL);
        EXPECT_EQ(server.wait(), 128 + SIGKILL);
    }
}

// SIGTERM drains: streams end UNAVAILABLE (clients go elsewhere), versions not yet computed
// are abandoned, and the server exits within the 10 s it promises however many sessions wait.
TEST(SessionDatabaseCli, SigtermEndsStreamsUnavailableAndAbandonsPendingVersions) {
    const test::ScratchDir dir("pic_sessions_drain");
    constexpr int kSessions = 300;
    Child server;
    const std::string address = startPicserver(server, (dir / "sessions.db").string(),
                                               {"--max-sessions", std::to_string(kSessions)});
    ASSERT_FALSE(address.empty());
    auto connection = PicConnection::connect(address);
    ASSERT_TRUE(connection) << connection.error().message;
    auto watched = (*connection)->createSession();
    ASSERT_TRUE(watched);
    auto reader = std::make_unique<Reader>(**connection, watched->session(), watched->viewer_token());
    ASSERT_TRUE(reader->waitFor(1));
    for (int i = 1; i < kSessions; ++i) ASSERT_TRUE((*connection)->createSession()) << i;

    const auto start = std::chrono::steady_clock::now();
    server.signal(SIGTERM);
    EXPECT_EQ(reader->waitForEnd(), "UNAVAILABLE");
    // The update log (stdout): one line per computed version, then EOF when it exits.
    int updates = 0;
    for (std::string line = readLine(server.out()); !line.empty(); line = readLine(server.out()))
        updates += line.starts_with("update ");
    EXPECT_EQ(server.wait(), 0);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("drain: exit %.2f s after SIGTERM, %d versions computed for %d sessions\n",
                seconds, updates, kSessions);
    EXPECT_LT(seconds, 10.0) << "the drain the server promises";
    EXPECT_LT(updates, kSessions) << "first versions still pending at SIGTERM are abandoned";
    reader.reset();
}

/// A PostgreSQL for the test, or a failure saying why there is none.
std::unique_ptr<PostgresServer> startPostgres() {
    std::string why;
    auto server = PostgresServer::start(why);
    EXPECT_TRUE(server) << why;
    return server;
}

// Replicas share a PostgreSQL database: a replica asked for a session it does not hold takes
// it over from the database at the stored light set, and the replica that held it learns at
// its next write that the session moved: the write is refused UNAVAILABLE and its streams end
// UNAVAILABLE, so its clients come back through the load balancer to the new owner.
TEST(SessionDatabasePostgres, ReplicasHandASessionOverThroughTheDatabase) {
    auto postgres = startPostgres();
    ASSERT_TRUE(postgres);
    Served a = serve("cpu", 32, std::chrono::hours(1), postgres->uri());
    Served b = serve("cpu", 32, std::chrono::hours(1), postgres->uri());
    ASSERT_TRUE(a.connection && b.connection);
    auto session = a.connection->createSession();
    ASSERT_TRUE(session) << session.error().message;
    const std::string id = session->session(), editor = session->editor_token(),
                      viewer = session->viewer_token();
    ASSERT_EQ(outcome(a.connection->setLights(id, editor, pointLight(0.2f))), "2");
    Reader onA(*a.connection, id, viewer);
    ASSERT_TRUE(onA.waitFor(2));

    // B takes it over (A is, say, unreachable): the stored set, at the next version.
    auto joined = b.connection->joinSession(id, viewer);
    ASSERT_TRUE(joined) << joined.error().message;
    EXPECT_EQ(joined->version(), 3u);
    EXPECT_EQ(lightsOf(*b.connection, id, viewer), toJson(pointLight(0.2f)));
    EXPECT_FALSE(b.connection->joinSession(id, "not-a-token")) << "tokens are checked first";
    ASSERT_EQ(outcome(b.connection->setLights(id, editor, pointLight(0.3f))), "4");
    Reader onB(*b.connection, id, viewer);
    EXPECT_TRUE(onB.waitFor(4));

    // A's copy is behind: its write is refused, its subscriber sent on.
    auto stale = a.connection->setLights(id, editor, pointLight(0.9f));
    ASSERT_FALSE(stale);
    EXPECT_NE(stale.error().message.find("UNAVAILABLE"), std::string::npos) << stale.error().message;
    EXPECT_NE(stale.error().message.find("moved"), std::string::npos) << stale.error().message;
    EXPECT_EQ(onA.waitForEnd(), "UNAVAILABLE");
    EXPECT_EQ(lightsOf(*b.connection, id, viewer), toJson(pointLight(0.3f)))
        << "the refused set went nowhere";
}

// A replica that takes a session over from PostgreSQL gets its presets; the replica that held
// it learns at its next preset change that the session moved (503, the session evicted
// there), and the change goes nowhere.
TEST(SessionDatabasePostgres, ReplicasHandPresetsOverThroughTheDatabase) {
    auto postgres = startPostgres();
    ASSERT_TRUE(postgres);
    Served a = serveWith(webOn(postgres->uri()));
    Served b = serveWith(webOn(postgres->uri()));
    ASSERT_TRUE(a.connection && b.connection);
    auto session = a.connection->createSession();
    ASSERT_TRUE(session) << session.error().message;
    const std::string id = session->session(), editor = session->editor_token(),
                      viewer = session->viewer_token();
    const std::string onA = a.server->webAddress(), onB = b.server->webAddress();
    ASSERT_EQ(
        httpRequest(onA, "PUT", presetsPath(id, editor) + "&name=Noon", toJson(pointLight(0.2f)))
            .code(),
        200);

    EXPECT_EQ(presetsOn(onB, id, viewer),
              std::vector<std::string>{presetOf("Noon", pointLight(0.2f))})
        << "taken over with its presets";
    ASSERT_EQ(
        httpRequest(onB, "PUT", presetsPath(id, editor) + "&name=Dusk", toJson(pointLight(-0.2f)))
            .code(),
        200);

    const HttpReply stale =
        httpRequest(onA, "PUT", presetsPath(id, editor) + "&name=Stale", toJson(pointLight(0.9f)));
    EXPECT_EQ(stale.code(), 503) << stale.status << " " << stale.body;
    EXPECT_NE(stale.body.find("moved"), std::string::npos) << stale.body;
    EXPECT_EQ(a.server->session(id), nullptr) << "evicted from the replica that held it";
    EXPECT_EQ(presetsOn(onB, id, viewer),
              (std::vector<std::string>{presetOf("Dusk", pointLight(-0.2f)),
                                        presetOf("Noon", pointLight(0.2f))}));
}

// While the database cannot be reached, light sets are refused UNAVAILABLE (never
// acknowledged without being durable) and health says NOT_SERVING; once it is back, health
// says SERVING again and the session goes on.
TEST(SessionDatabasePostgres, HealthIsNotServingWhileTheDatabaseIsAway) {
    auto postgres = startPostgres();
    ASSERT_TRUE(postgres);
    Served served = serve("cpu", 32, std::chrono::hours(1), postgres->uri());
    ASSERT_TRUE(served.connection);
    auto session = served.connection->createSession();
    ASSERT_TRUE(session) << session.error().message;
    const std::string id = session->session(), editor = session->editor_token();
    EXPECT_EQ(healthStatus(served.server->address()), "SERVING");

    ASSERT_TRUE(postgres->stop());
    auto refused = served.connection->setLights(id, editor, pointLight(0.2f));
    ASSERT_FALSE(refused);
    EXPECT_NE(refused.error().message.find("UNAVAILABLE"), std::string::npos)
        << refused.error().message;
    EXPECT_EQ(healthStatus(served.server->address()), "NOT_SERVING");

    ASSERT_TRUE(postgres->resume());
    std::string health;
    for (int i = 0; i < 300 && health != "SERVING"; ++i) {
        std::this_thread::sleep_for(50ms);
        health = healthStatus(served.server->address());
    }
    EXPECT_EQ(health, "SERVING");
    auto version = served.connection->setLights(id, editor, pointLight(0.2f));
    ASSERT_TRUE(version) << version.error().message;
    EXPECT_EQ(*version, 2u) << "the refused set took no version";
    EXPECT_EQ(lightsOf(*served.connection, id, editor), toJson(pointLight(0.2f)));
}

}  // namespace
}  // namespace pic
