// Who may call what (issue: open to the network): operator API keys for CreateSession,
// ListBakes and GetScene, session tokens for a session's own calls, the refusal to serve a
// non-loopback address open, and the audit log of every call.

#include <gtest/gtest.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "proto/wire.h"
#include "server/api_keys.h"
#include "tests/client/stream_fixture.h"
#include "tests/support/command.h"

namespace pic {
namespace {

namespace fs = std::filesystem;
using namespace test;

constexpr const char* kKey = "k3y-0f-the-0perator-9f8e7d6c";
constexpr const char* kOtherKey = "k3y-0f-the-0ther-0perator-11";

/// The audit log's lines, each parsed.
std::vector<nlohmann::json> auditLines(const fs::path& path) {
    std::vector<nlohmann::json> lines;
    std::ifstream in(path);
    for (std::string line; std::getline(in, line);) lines.push_back(nlohmann::json::parse(line));
    return lines;
}

/// The first audit line of `call` with `outcome`, or null.
const nlohmann::json* findLine(const std::vector<nlohmann::json>& lines, const std::string& call,
                               const std::string& outcome) {
    for (const auto& line : lines)
        if (line.at("call") == call && line.at("outcome") == outcome) return &line;
    return nullptr;
}

TEST(ApiKeys, FileRulesAndIds) {
    auto keys = ApiKeys::parse(std::string("# operators\n\n") + kKey + "\r\n" + kOtherKey + "\n" + kKey + "\n", "keys");
    ASSERT_TRUE(keys) << keys.error().message;
    EXPECT_EQ(keys->size(), 2u) << "a key given twice counts once";
    const auto id = keys->find(kKey);
    ASSERT_TRUE(id);
    EXPECT_TRUE(id->starts_with("key-")) << *id;
    EXPECT_EQ(id->size(), 16u);
    EXPECT_EQ(keys->ids().front(), *id);
    EXPECT_NE(keys->find(kOtherKey), id);
    EXPECT_FALSE(keys->find("k3y-0f-the-0perator-9f8e7d6"));
    EXPECT_FALSE(keys->find(""));

    // Bad lines are named by number, never shown.
    for (const std::string& bad : std::vector<std::string>{"short-key", std::string(257, 'x'),
                                                           "a key with spaces in it",
                                                           "tab\tseparated-key-0123"}) {
        auto refused = ApiKeys::parse(std::string(kKey) + "\n" + bad + "\n", "keys");
        ASSERT_FALSE(refused) << bad;
        EXPECT_NE(refused.error().message.find("keys line 2"), std::string::npos) << refused.error().message;
        EXPECT_EQ(refused.error().message.find(bad), std::string::npos) << refused.error().message;
    }
    EXPECT_FALSE(ApiKeys::parse("# nothing but a comment\n", "keys"));
    EXPECT_EQ(ApiKeys::load("/nonexistent/keys").error().code, ErrorCode::NotFound);

    EXPECT_EQ(bearerKey("Bearer abc"), "abc");
    EXPECT_EQ(bearerKey("bearer abc"), "abc");
    EXPECT_FALSE(bearerKey("Basic abc"));
    EXPECT_FALSE(bearerKey("Bearer "));
    EXPECT_FALSE(bearerKey("abc"));
}

TEST(ApiKeys, LoopbackAddresses) {
    for (const char* listen : {"127.0.0.1:50051", "127.1.2.3:0", "localhost:80", "[::1]:50051"})
        EXPECT_TRUE(isLoopbackListen(listen)) << listen;
    for (const char* listen : {"0.0.0.0:50051", "[::]:50051", "10.0.0.7:50051", "example.com:1",
                               "127.0.0.1.example.com:1", "128.0.0.1:1", ":50051"})
        EXPECT_FALSE(isLoopbackListen(listen)) << listen;
    EXPECT_TRUE(checkOpenListen("127.0.0.1:0", false, false));
    EXPECT_TRUE(checkOpenListen("0.0.0.0:0", true, false));
    EXPECT_TRUE(checkOpenListen("0.0.0.0:0", false, true));
    const auto refused = checkOpenListen("0.0.0.0:0", false, false);
    ASSERT_FALSE(refused);
    EXPECT_NE(refused.error().message.find("--allow-unauthenticated"), std::string::npos);
}

// Before keys existed, any peer that reached the port could create sessions until the
// server was full and download every scene.
TEST(Access, OperatorCallsNeedAKeySessionCallsTheirTokenAndTheAuditLogSaysWho) {
    const ScratchDir dir("pic_access");
    ServerOptions options;
    options.apiKeys = *ApiKeys::parse(std::string(kKey) + "\n", "keys");
    options.auditLog = (dir / "audit.jsonl").string();
    Served served = serveWith(options);
    ASSERT_TRUE(served.connection);
    PicConnection& anonymous = *served.connection;
    const std::string address = served.server->address();

    // Without a key, or with one the server does not hold: UNAUTHENTICATED, nothing created.
    auto created = anonymous.createSession();
    ASSERT_FALSE(created);
    EXPECT_NE(created.error().message.find("UNAUTHENTICATED"), std::string::npos) << created.error().message;
    EXPECT_NE(created.error().message.find("API key"), std::string::npos) << created.error().message;
    EXPECT_FALSE(anonymous.listBakes());
    EXPECT_FALSE(anonymous.sceneHeader(""));
    auto wrong = PicConnection::connect(address, {.apiKey = kOtherKey});
    ASSERT_TRUE(wrong);
    created = (*wrong)->createSession();
    ASSERT_FALSE(created);
    EXPECT_NE(created.error().message.find("not one of this server's"), std::string::npos)
        << created.error().message;

    // With the key, every operator call; the session's own calls need only its tokens.
    auto keyed = PicConnection::connect(address, {.apiKey = kKey});
    ASSERT_TRUE(keyed);
    ASSERT_TRUE((*keyed)->listBakes());
    ASSERT_TRUE((*keyed)->sceneHeader(""));
    created = (*keyed)->createSession();
    ASSERT_TRUE(created) << created.error().message;
    const std::string session = created->session();
    EXPECT_TRUE(anonymous.joinSession(session, created->viewer_token()));
    EXPECT_TRUE(anonymous.setLights(session, created->editor_token(), pointLight(0.1f)));
    {
        Reader reader(*keyed.value(), session, created->viewer_token());
        EXPECT_TRUE(reader.waitFor(2));
    }
    EXPECT_FALSE(anonymous.setLights(session, "not-a-token", pointLight(0.2f)));
    // Health stays open: probes carry no key.
    EXPECT_EQ(healthStatus(address), "SERVING");

    const std::vector<nlohmann::json> lines = auditLines(dir / "audit.jsonl");
    ASSERT_GE(lines.size(), 9u);
    const std::string keyId = *options.apiKeys.find(kKey);
    for (const auto& line : lines) {
        for (const char* field : {"time", "peer", "call", "credential", "outcome"})
            EXPECT_TRUE(line.contains(field)) << field << " in " << line.dump();
        EXPECT_TRUE(line.at("peer").get<std::string>().starts_with("ipv4:127.0.0.1:")) << line.dump();
        const std::string text = line.dump();
        for (const std::string& secret : {std::string(kKey), std::string(kOtherKey),
                                          created->editor_token(), created->viewer_token()})
            EXPECT_EQ(text.find(secret), std::string::npos) << "a secret in the audit log: " << text;
    }
    const auto* refused = findLine(lines, "CreateSession", "UNAUTHENTICATED");
    ASSERT_TRUE(refused);
    EXPECT_EQ(refused->at("credential"), "none");
    EXPECT_TRUE(refused->contains("message"));
    const auto* accepted = findLine(lines, "CreateSession", "OK");
    ASSERT_TRUE(accepted);
    EXPECT_EQ(accepted->at("credential"), keyId);
    EXPECT_EQ(accepted->at("session"), session);
    ASSERT_TRUE(findLine(lines, "GetScene", "UNAUTHENTICATED"));
    ASSERT_TRUE(findLine(lines, "ListBakes", "OK"));
    const auto* set = findLine(lines, "SetLights", "OK");
    ASSERT_TRUE(set);
    EXPECT_EQ(set->at("credential"), "editor");
    EXPECT_EQ(set->at("session"), session);
    const auto* badToken = findLine(lines, "SetLights", "UNAUTHENTICATED");
    ASSERT_TRUE(badToken);
    EXPECT_EQ(badToken->at("credential"), "none");
    const auto* subscribed = findLine(lines, "Subscribe", "OK");
    ASSERT_TRUE(subscribed);
    EXPECT_EQ(subscribed->at("credential"), "viewer");
}

// Before: a server on 0.0.0.0 without any credential started without a word.
TEST(AccessCli, AnOpenServerOnAnAddressOthersReachIsRefused) {
    const ScratchDir dir("pic_access_cli");
    int exit = 0;
    const std::string server = std::string(PIC_PICSERVER) + " --bake " + bakePath() + " --scene " + kScene +
                               " --backend cpu --quiet";
    std::string out = run(server + " --listen 0.0.0.0:0 2>&1", exit);
    EXPECT_EQ(exit, 2) << out;
    EXPECT_NE(out.find("--api-keys"), std::string::npos) << out;
    EXPECT_NE(out.find("--allow-unauthenticated"), std::string::npos) << out;
    EXPECT_EQ(out.find("listening on"), std::string::npos) << out;

    // A bad key file is refused naming the line, not showing it.
    const fs::path keys = dir / "keys";
    std::ofstream(keys) << kKey << "\nshort\n";
    out = run(server + " --listen 127.0.0.1:0 --api-keys " + keys.string() + " 2>&1", exit);
    EXPECT_EQ(exit, 2) << out;
    EXPECT_NE(out.find("line 2"), std::string::npos) << out;
    EXPECT_EQ(out.find(kKey), std::string::npos) << out;
    out = run(server + " --listen 127.0.0.1:0 --api-keys " + (dir / "missing").string() + " 2>&1", exit);
    EXPECT_EQ(exit, 2) << out;
    EXPECT_NE(out.find("missing"), std::string::npos) << out;
    out = run(server + " --listen 127.0.0.1:0 --audit-log " + (dir / "no" / "such" / "dir.jsonl").string() +
                  " 2>&1",
              exit);
    EXPECT_EQ(exit, 2) << out;
    EXPECT_NE(out.find("--audit-log"), std::string::npos) << out;
}

TEST(AccessCli, PicclientSendsTheKeyOfItsFlagOrOfPicApiKey) {
    const ScratchDir dir("pic_access_client");
    const fs::path keys = dir / "keys";
    std::ofstream(keys) << "# the operators\n" << kKey << "\n";
    Child server({PIC_PICSERVER, "--bake", bakePath(), "--scene", kScene, "--listen", "127.0.0.1:0",
                  "--backend", "cpu", "--bounces", "1", "--quiet", "--api-keys", keys.string()});
    const std::string first = readLine(server.out());
    ASSERT_TRUE(first.starts_with("listening on ")) << first;
    const std::string address = first.substr(std::string("listening on ").size());
    const std::string client = std::string(PIC_PICCLIENT) + " session --patience 0 --server " + address;

    int exit = 0;
    std::string out = run("env -u PIC_API_KEY " + client + " 2>&1", exit);
    EXPECT_EQ(exit, 2) << out;
    EXPECT_NE(out.find("UNAUTHENTICATED"), std::string::npos) << out;
    out = run(client + " --api-key " + kOtherKey + " 2>&1", exit);
    EXPECT_EQ(exit, 2) << out;
    out = run(client + " --api-key " + kKey, exit);
    ASSERT_EQ(exit, 0) << out;
    EXPECT_TRUE(nlohmann::json::parse(out).contains("editor_token")) << out;
    out = run(std::string("PIC_API_KEY=") + kKey + " " + client, exit);
    ASSERT_EQ(exit, 0) << out;
    EXPECT_TRUE(nlohmann::json::parse(out).contains("editor_token")) << out;
    out = run(client + " --api-key 'two words' 2>&1", exit);
    EXPECT_EQ(exit, 2) << out;
    EXPECT_NE(out.find("API key"), std::string::npos) << out;
}

// Before: one anonymous peer filled the server with sessions in 0.01 s, and one editor's
// 1,000 light sets were all accepted in 0.21 s.
TEST(Access, QuotasPerKeyAndPeerAndARateOfLightSets) {
    ServerOptions options;
    options.apiKeys = *ApiKeys::parse(std::string(kKey) + "\n" + kOtherKey + "\n", "keys");
    options.maxSessionsPerClient = 2;
    options.maxStreamsPerPeer = 2;
    options.session.setLightsPerSecond = 2.0;
    Served served = serveWith(options);
    ASSERT_TRUE(served.connection);
    const std::string address = served.server->address();
    auto first = PicConnection::connect(address, {.apiKey = kKey});
    auto second = PicConnection::connect(address, {.apiKey = kOtherKey});
    ASSERT_TRUE(first && second);

    // Sessions: two per key.
    auto a = (*first)->createSession();
    auto b = (*first)->createSession();
    ASSERT_TRUE(a && b);
    auto refused = (*first)->createSession();
    ASSERT_FALSE(refused);
    EXPECT_NE(refused.error().message.find("RESOURCE_EXHAUSTED"), std::string::npos) << refused.error().message;
    EXPECT_NE(refused.error().message.find("holds 2 sessions"), std::string::npos) << refused.error().message;
    EXPECT_NE(refused.error().message.find(*options.apiKeys.find(kKey)), std::string::npos) << refused.error().message;
    EXPECT_TRUE((*second)->createSession()) << "another key has its own share";

    // Light sets: a burst of two, then the delay to wait, in the message and the trailers.
    const std::string session = a->session(), editor = a->editor_token();
    ASSERT_TRUE(served.connection->setLights(session, editor, pointLight(0.1f)));
    ASSERT_TRUE(served.connection->setLights(session, editor, pointLight(0.2f)));
    v1::SetLightsRequest request;
    request.set_session(session);
    request.set_token(editor);
    *request.mutable_lights() = wire::toProto(pointLight(0.3f));
    grpc::ClientContext context;
    v1::SetLightsResponse response;
    const grpc::Status status = served.connection->stub().SetLights(&context, request, &response);
    ASSERT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << status.error_message();
    EXPECT_NE(status.error_message().find("at most 2 light sets a second"), std::string::npos) << status.error_message();
    const auto trailer = context.GetServerTrailingMetadata().find(wire::kRetryAfterMetadata);
    ASSERT_NE(trailer, context.GetServerTrailingMetadata().end());
    EXPECT_GT(std::stoi(std::string(trailer->second.data(), trailer->second.size())), 0);
    // A client with patience waits as told and gets every set through.
    served.connection->setPatience(std::chrono::seconds(20));
    for (int i = 0; i < 3; ++i)
        EXPECT_TRUE(served.connection->setLights(session, editor, pointLight(0.05f * i)));
    served.connection->setPatience(std::chrono::milliseconds(0));

    // Streams: two per peer host (all of these come from 127.0.0.1).
    {
        Reader one(**first, session, a->viewer_token());
        Reader two(**first, b->session(), b->viewer_token());
        ASSERT_TRUE(one.waitFor(1));
        ASSERT_TRUE(two.waitFor(1));
        Reader three(**first, session, a->viewer_token());
        EXPECT_EQ(three.waitForEnd(), "RESOURCE_EXHAUSTED");
    }
    // Once they are gone, the peer may subscribe again.
    for (int attempt = 0; attempt < 100; ++attempt) {
        Reader again(**first, session, a->viewer_token());
        if (again.waitFor(1, std::chrono::seconds(5))) return;
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    ADD_FAILURE() << "no stream after the first two ended";
}

/// CreateSession on a raw stub, with `forwardedFor` as X-Forwarded-For: the status.
grpc::Status createForwarded(const std::string& address, const std::string& forwardedFor) {
    auto stub = v1::Pic::NewStub(grpc::CreateChannel(address, grpc::InsecureChannelCredentials()));
    grpc::ClientContext context;
    context.AddMetadata("x-forwarded-for", forwardedFor);
    v1::CreateSessionRequest request;
    v1::CreateSessionResponse response;
    return stub->CreateSession(&context, request, &response);
}

// Behind a load balancer every client came from the balancer's address, so one client's
// sessions used up the per-peer share of all. A trusted balancer names the client instead; any
// other peer's X-Forwarded-For is ignored, or a client could pick its own address.
TEST(Access, PerPeerQuotasCountTheClientATrustedBalancerNames) {
    for (const bool trusted : {true, false}) {
        SCOPED_TRACE(trusted ? "trusted" : "not trusted");
        ServerOptions options;
        options.maxSessionsPerClient = 1;
        if (trusted) {
            ASSERT_TRUE(options.trustedProxies.add("127.0.0.0/8"));
        }
        Served served = serveWith(options);
        ASSERT_TRUE(served.connection);
        const std::string address = served.server->address();
        EXPECT_TRUE(createForwarded(address, "198.51.100.1").ok());
        const grpc::Status again = createForwarded(address, "203.0.113.7, 198.51.100.1");
        EXPECT_EQ(again.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << again.error_message();
        EXPECT_NE(again.error_message().find(trusted ? "peer 198.51.100.1" : "peer 127.0.0.1"),
                  std::string::npos)
            << again.error_message();
        const grpc::Status other = createForwarded(address, "198.51.100.2");
        EXPECT_EQ(other.ok(), trusted) << other.error_message();
    }
}

/// Threads of this process now.
size_t threadCount() {
    size_t count = 0;
    for ([[maybe_unused]] const auto& entry : fs::directory_iterator("/proc/self/task")) ++count;
    return count;
}

// Before the relight pool, every session had a thread of its own: 40 sessions, 40 threads.
// Now a fixed pool computes them all, and the metrics count the pool and every refusal.
TEST(Access, SessionsShareAFixedPoolOfRelightThreadsAndRefusalsAreCounted) {
    ServerOptions options;
    options.apiKeys = *ApiKeys::parse(std::string(kKey) + "\n", "keys");
    options.relightThreads = 2;
    options.metricsListen = "127.0.0.1:0";
    Served served = serveWith(options);
    ASSERT_TRUE(served.connection);
    auto keyed = PicConnection::connect(served.server->address(), {.apiKey = kKey});
    ASSERT_TRUE(keyed);
    // The channel's and the server's own threads, with one session computed through them.
    auto first = (*keyed)->createSession();
    ASSERT_TRUE(first);
    ASSERT_TRUE(served.server->session(first->session())->waitForVersion(1, std::chrono::seconds(60)));
    const size_t before = threadCount();

    std::vector<std::string> ids;
    for (int i = 0; i < 40; ++i) {
        auto created = (*keyed)->createSession();
        ASSERT_TRUE(created) << created.error().message;
        ids.push_back(created->session());
    }
    for (const std::string& id : ids)
        ASSERT_TRUE(served.server->session(id)->waitForVersion(1, std::chrono::seconds(60))) << id;
    const size_t after = threadCount();
    EXPECT_LT(after, before + 8) << before << " threads before 40 more sessions, " << after << " after";

    // A call without a key, refused, and counted.
    EXPECT_FALSE(served.connection->createSession());
    const HttpReply reply = httpGet(served.server->metricsAddress(), "/metrics");
    EXPECT_EQ(metricValue(reply.body, "pic_relight_threads"), 2.0) << reply.body;
    EXPECT_EQ(metricValue(reply.body, "pic_calls_total{call=\"CreateSession\",code=\"UNAUTHENTICATED\"}"), 1.0)
        << reply.body;
    EXPECT_EQ(metricValue(reply.body, "pic_calls_total{call=\"CreateSession\",code=\"OK\"}"), 41.0)
        << reply.body;
    EXPECT_GE(metricValue(reply.body, "pic_relight_queued"), 0.0) << reply.body;
}

// Both sides cap what they accept: a peer cannot make the other buffer an arbitrary amount.
TEST(Access, RequestsOverAMebibyteAreRefused) {
    Served served = serve();
    ASSERT_TRUE(served.connection);
    auto session = served.connection->createSession();
    ASSERT_TRUE(session);
    const std::string huge(2 << 20, 'x');
    // A channel without picclient's own cap: the server refuses it.
    auto channel = grpc::CreateChannel(served.server->address(), grpc::InsecureChannelCredentials());
    auto stub = v1::Pic::NewStub(channel);
    grpc::ClientContext context;
    v1::JoinSessionRequest request;
    request.set_session(session->session());
    request.set_token(huge);
    v1::JoinSessionResponse response;
    const grpc::Status status = stub->JoinSession(&context, request, &response);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << status.error_message();
    // picclient's connection does not even send it.
    auto joined = served.connection->joinSession(session->session(), huge);
    ASSERT_FALSE(joined);
    EXPECT_NE(joined.error().message.find("RESOURCE_EXHAUSTED"), std::string::npos) << joined.error().message;
    // The session and the server are fine.
    EXPECT_TRUE(served.connection->joinSession(session->session(), session->viewer_token()));
}

// Before: `picclient watch` sat silent for 30 s against a stopped server and never noticed.
TEST(AccessCli, AWatcherNoticesAServerThatStoppedAnswering) {
    Child server({PIC_PICSERVER, "--bake", bakePath(), "--scene", kScene, "--listen", "127.0.0.1:0",
                  "--backend", "cpu", "--bounces", "1", "--quiet"});
    const std::string first = readLine(server.out());
    ASSERT_TRUE(first.starts_with("listening on ")) << first;
    const std::string address = first.substr(std::string("listening on ").size());
    auto connection = PicConnection::connect(address);
    ASSERT_TRUE(connection);
    auto session = (*connection)->createSession();
    ASSERT_TRUE(session);
    Child watch({PIC_PICCLIENT, "watch", "--server", address, "--session", session->session(), "--token",
                 session->viewer_token(), "--keepalive", "1", "--patience", "0"});
    ASSERT_TRUE(readLine(watch.out()).starts_with("version 1:"));
    server.signal(SIGSTOP);  // alive, connected, silent
    // A ping after 1 s unanswered for 1 s: the stream fails within seconds. The bound is
    // generous for a loaded machine; the point is that it ends at all.
    const std::optional<int> exit = watch.waitFor(std::chrono::seconds(30));
    server.signal(SIGCONT);
    ASSERT_TRUE(exit) << "picclient watch did not notice the stopped server within 30 s";
    EXPECT_NE(*exit, 0);
}

}  // namespace
}  // namespace pic
