// deploy/local: PostgreSQL, three picserver replicas and nginx as the gRPC load balancer on
// 127.0.0.1, started by the scripts users run and stopped by the test. 30 sessions with 5
// subscribers each go through nginx: the metrics show each session computed on exactly one
// replica; then one replica is killed (SIGKILL) and every session goes on within 5 s on the
// others, every subscriber ends with its session's final version, and no acknowledged light
// set is lost.
#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <unistd.h>
#include <vector>

#include "core/light_set.h"
#include "proto/wire.h"
#include "tests/client/stream_fixture.h"
#include "tests/support/command.h"

namespace pic {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using namespace test;

/// deploy/local/up.sh into a state directory, and down.sh when it goes.
class LocalDeployment {
public:
    LocalDeployment(const fs::path& state, int replicas) : mState(state) {
        const CommandResult up = runCommand(
            "PICSERVER='" + std::string(PIC_PICSERVER) + "' bash " + std::string(PIC_SOURCE_DIR) +
                "/deploy/local/up.sh '" + state.string() +
                "' --bake '" + bakePath() + "' --scene '" + kScene + "' --replicas " +
                std::to_string(replicas),
            state.parent_path());
        mStarted = up.exitCode == 0;
        mLog = up.out + up.err;
    }
    /// Stops everything and removes the directory above the state.
    ~LocalDeployment() {
        runCommand("bash " + std::string(PIC_SOURCE_DIR) + "/deploy/local/down.sh '" +
                       mState.string() + "'",
                   mState.parent_path());
        std::error_code ignored;
        fs::remove_all(mState.parent_path(), ignored);
    }
    bool started() const { return mStarted; }
    const std::string& log() const { return mLog; }
    std::string file(const std::string& name) const {
        std::string text = readFile(mState / name);
        while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
        return text;
    }

private:
    fs::path mState;
    bool mStarted = false;
    std::string mLog;
};

struct TrackedSession {
    std::string id, editor, viewer;
    std::vector<std::unique_ptr<Reader>> readers;
    uint64_t acknowledged = 0;  ///< the last version a SetLights reply gave
    LightSet lights;            ///< its light set
};

TEST(DeployLocal, ThreeReplicasBehindNginxShareSessionsAndSurviveAKill) {
    // A short path: PostgreSQL's socket lives in the state directory, and socket paths are
    // short (up.sh refuses a longer one).
    std::string dir = (fs::temp_directory_path() / "pic_dl_XXXXXX").string();
    ASSERT_NE(::mkdtemp(dir.data()), nullptr);
    fs::permissions(dir, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                             fs::perms::others_read | fs::perms::others_exec);  // postgres enters it
    LocalDeployment deployment(fs::path(dir) / "state", 3);
    ASSERT_TRUE(deployment.started()) << deployment.log();
    const std::string address = deployment.file("address");
    auto connection = PicConnection::connect(address);
    ASSERT_TRUE(connection) << connection.error().message;
    (*connection)->setPatience(20s);

    constexpr int kSessions = 30, kSubscribers = 5;
    std::vector<TrackedSession> sessions(kSessions);
    for (int s = 0; s < kSessions; ++s) {
        auto created = (*connection)->createSession();
        ASSERT_TRUE(created) << created.error().message;
        sessions[s].id = created->session();
        sessions[s].editor = created->editor_token();
        sessions[s].viewer = created->viewer_token();
        for (int r = 0; r < kSubscribers; ++r)
            sessions[s].readers.push_back(std::make_unique<Reader>(
                **connection, sessions[s].id, sessions[s].viewer, 20s));
    }
    const auto setAll = [&](float x) {
        for (TrackedSession& session : sessions) {
            session.lights = pointLight(x);
            auto version = (*connection)->setLights(session.id, session.editor, session.lights);
            ASSERT_TRUE(version) << session.id << ": " << version.error().message;
            session.acknowledged = *version;
        }
    };
    const auto allReceived = [&] {
        for (const TrackedSession& session : sessions)
            for (const auto& reader : session.readers)
                EXPECT_TRUE(reader->waitFor(session.acknowledged, 30s))
                    << session.id << " version " << session.acknowledged;
    };
    setAll(0.1f);
    setAll(0.2f);
    allReceived();

    // Each session was computed on exactly one replica (all its versions on that one).
    std::vector<std::string> metrics;
    for (int i = 1; i <= 3; ++i) {
        const HttpReply reply = httpGet(deployment.file("replica-" + std::to_string(i) + ".metrics"), "/metrics");
        ASSERT_EQ(reply.status, "HTTP/1.1 200 OK") << i;
        metrics.push_back(reply.body);  // replica i at i - 1
    }
    std::map<int, int> sessionsPerReplica;
    for (const TrackedSession& session : sessions) {
        const std::string series = "pic_session_versions_computed_total{session=\"" + session.id + "\"}";
        int holders = 0;
        for (int i = 1; i <= 3; ++i)
            if (metricValue(metrics[i - 1], series) > 0) {  // versions may coalesce: 1 to 3
                ++holders;
                ++sessionsPerReplica[i];
            }
        EXPECT_EQ(holders, 1) << session.id;
    }
    for (const auto& [replica, count] : sessionsPerReplica)
        std::printf("replica %d held %d sessions\n", replica, count);

    // Kill the replica that holds the most sessions; the others take them over.
    int victim = sessionsPerReplica.begin()->first;
    for (const auto& [replica, count] : sessionsPerReplica)
        if (count > sessionsPerReplica[victim]) victim = replica;
    const pid_t pid = std::stoi(deployment.file("replica-" + std::to_string(victim) + ".pid"));
    ASSERT_EQ(::kill(pid, SIGKILL), 0);
    const auto killed = std::chrono::steady_clock::now();
    setAll(0.3f);
    const double continuing =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - killed).count();
    std::printf("every session acknowledged a light set %.2f s after the kill\n", continuing);
    EXPECT_LT(continuing, 5.0) << "sessions continue within 5 s";
    allReceived();
    for (const TrackedSession& session : sessions) {
        auto joined = (*connection)->joinSession(session.id, session.viewer);
        ASSERT_TRUE(joined) << joined.error().message;
        EXPECT_GE(joined->version(), session.acknowledged);
        auto lights = wire::fromProto(joined->lights());
        ASSERT_TRUE(lights);
        EXPECT_EQ(toJson(*lights), toJson(session.lights)) << "acknowledged set of " << session.id;
        for (const auto& reader : session.readers) EXPECT_TRUE(reader->errors().empty());
    }
}

}  // namespace
}  // namespace pic
