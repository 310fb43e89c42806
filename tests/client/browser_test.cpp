// The browser client (client/web/) in a real browser: headless chromium, software WebGL2
// (SwiftShader through ANGLE), driven by puppeteer-core from client/web/tests/. Each test
// starts a picserver with --web-listen on 127.0.0.1 and stops it; chromium runs as a child
// process of node and is closed by the driver script.
#include <gtest/gtest.h>

#include <csignal>
#include <cstdio>
#include <filesystem>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "core/image.h"
#include "core/light_set.h"
#include "server/served_bake.h"
#include "tests/client/stream_fixture.h"
#include "tests/support/baked_scene.h"
#include "tests/support/lights.h"

namespace pic {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using namespace test;

const std::string kWebDir = std::string(PIC_SOURCE_DIR) + "/client/web";

/// A server over a small bake of test scene `name`, with the browsers' listener.
Result<std::unique_ptr<PicServer>> serveScene(const std::string& name, const BakeOptions& bake) {
    const std::string& path = bakeFile(name, bake);
    if (path.empty()) return fail(ErrorCode::Io, "no bake of {}", name);
    ServeOptions serveOptions;
    serveOptions.backend = "cpu";
    serveOptions.bounces.bounces = 1;
    PIC_TRY_ASSIGN(auto served, ServedBake::load(path, testScenePath(name), serveOptions));
    std::vector<std::unique_ptr<ServedBake>> bakes;
    bakes.push_back(std::move(served));
    ServerOptions options;
    options.session.setLightsPerSecond = 1e6;
    options.webListen = "127.0.0.1:0";
    return PicServer::start(std::move(bakes), "127.0.0.1:0", options);
}

/// A server over a small bake of test scene `name` (serveScene), a connection to it and a
/// new session on it; fatal failures when any of them fails (ASSERT_NO_FATAL_FAILURE).
struct OpenSession {
    std::unique_ptr<PicServer> server;
    std::unique_ptr<PicConnection> connection;
    v1::CreateSessionResponse session;
};
void openSession(const std::string& name, uint32_t surfels, OpenSession& out) {
    auto server = serveScene(name, smallBakeOptions(surfels, 32));
    ASSERT_TRUE(server) << server.error().message;
    out.server = std::move(*server);
    auto connection = PicConnection::connect(out.server->address());
    ASSERT_TRUE(connection) << connection.error().message;
    out.connection = std::move(*connection);
    auto session = out.connection->createSession();
    ASSERT_TRUE(session) << session.error().message;
    out.session = std::move(*session);
}

/// What the browser tests need installed: chromium and the npm packages (scripts/build.sh).
void requireBrowser() {
    ASSERT_TRUE(fs::exists("/usr/bin/chromium") || std::getenv("PIC_CHROMIUM"))
        << "chromium is not installed (scripts/install_deps.sh installs it)";
    ASSERT_TRUE(fs::exists(kWebDir + "/node_modules/puppeteer-core"))
        << "client/web's npm packages are not installed (scripts/build.sh installs them)";
}

/// "ex,ey,ez,tx,ty,tz,ux,uy,uz,fovy" of a camera, as --camera and the page's URL take it.
std::string cameraText(const Camera& c) {
    return fmt::format("{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g}",
                       c.eye.x, c.eye.y, c.eye.z, c.target.x, c.target.y, c.target.z, c.up.x,
                       c.up.y, c.up.z, c.fovyDegrees);
}

struct ParityCase {
    std::string scene;
    uint32_t surfels;
    std::string size;
    bool pushLights;  ///< a point and a spot light pushed (else the scene's own lights)
};

class BrowserParity : public testing::TestWithParam<ParityCase> {};

// The page's image of one view against `picclient render`'s of the same view, size and
// exposure: the same shading, pass for pass, on another rasteriser. Relative RMSE over 4 × 4
// blocks within 0.02 (the bound); the per-pixel figure is reported too.
TEST_P(BrowserParity, TheBrowsersImageIsPicclientRenders) {
    requireBrowser();
    const ParityCase& c = GetParam();
    OpenSession open;
    ASSERT_NO_FATAL_FAILURE(openSession(c.scene, c.surfels, open));
    auto& [server, connection, session] = open;
    uint64_t version = session.version();
    const Scene scene = loadTestScene(c.scene);
    ASSERT_FALSE(scene.cameras.empty());
    if (c.pushLights) {
        LightSet lights;
        Light point;
        point.id = "point";
        point.type = LightType::Point;
        point.position = scene.bounds.center() + glm::vec3(0.15f, 0.25f, 0.1f) * scene.bounds.extent();
        point.intensity = 0.6f * glm::dot(scene.bounds.extent(), scene.bounds.extent());
        point.color = {1.0f, 0.8f, 0.6f};
        Light spot;
        spot.id = "spot";
        spot.type = LightType::Spot;
        spot.position = scene.bounds.center() + glm::vec3(-0.3f, 0.3f, 0.2f) * scene.bounds.extent();
        spot.direction = glm::normalize(glm::vec3(0.3f, -1.0f, -0.2f));
        spot.outerConeAngle = 0.6f;
        spot.innerConeAngle = 0.4f;
        spot.intensity = point.intensity;
        lights.lights = {point, spot};
        auto set = connection->setLights(session.session(), session.editor_token(), lights);
        ASSERT_TRUE(set) << set.error().message;
        version = *set;
    }
    auto live = server->session(session.session());
    ASSERT_TRUE(live->waitForVersion(version, 60s));

    const std::string camera = cameraText(scene.cameras.front());
    const fs::path dir = fs::path(testing::TempDir()) / ("browser_" + c.scene);
    fs::create_directories(dir);
    const std::string native = (dir / "picclient.png").string();
    const std::string browser = (dir / "browser.png").string();
    int exit = 0;
    const std::string rendered = run(
        fmt::format("{} render --server {} --session {} --token {} --camera {} --size {} --out {} "
                    "--cache-dir {} 2>&1",
                    PIC_PICCLIENT, server->address(), session.session(),
                    session.viewer_token(), camera, c.size, native, (dir / "cache").string()),
        exit);
    ASSERT_EQ(exit, 0) << rendered;
    const std::string url =
        fmt::format("http://{}/?session={}&token={}&camera={}&size={}&ui=0",
                    server->webAddress(), session.session(), session.viewer_token(), camera,
                    c.size);
    const std::string shot =
        run(fmt::format("node {}/tests/screenshot.mjs --url '{}' --out {} --version {} 2>&1",
                        kWebDir, url, browser, version),
            exit);
    ASSERT_EQ(exit, 0) << shot;

    auto a = readImage(browser);
    auto b = readImage(native);
    ASSERT_TRUE(a) << a.error().message;
    ASSERT_TRUE(b) << b.error().message;
    ASSERT_EQ(a->width, b->width);
    ASSERT_EQ(a->height, b->height);
    auto perPixel = compareImages(*a, *b);
    auto blocksA = blockAverage(*a, 4);
    auto blocksB = blockAverage(*b, 4);
    ASSERT_TRUE(perPixel && blocksA && blocksB);
    auto blocks = compareImages(*blocksA, *blocksB);
    ASSERT_TRUE(blocks);
    std::printf("%s %s: relative RMSE %.4f over 4x4 blocks, %.4f per pixel; mean ratio %.4f\n",
                c.scene.c_str(), c.size.c_str(), blocks->relativeRmse, perPixel->relativeRmse,
                perPixel->meanRatio);
    RecordProperty("block_relative_rmse", fmt::format("{:.4f}", blocks->relativeRmse));
    RecordProperty("pixel_relative_rmse", fmt::format("{:.4f}", perPixel->relativeRmse));
    EXPECT_LE(blocks->relativeRmse, 0.02) << "browser " << browser << " vs " << native;
    EXPECT_GT(perPixel->meanRatio, 0.0);
}

INSTANTIATE_TEST_SUITE_P(Scenes, BrowserParity,
                         testing::Values(ParityCase{"cornell", 4096, "320x240", true},
                                         ParityCase{"textured_quad", 2048, "320x240", true},
                                         ParityCase{"atrium", 8192, "384x216", false}),
                         [](const auto& info) { return info.param.scene; });

/// A white point light "lamp" at `position`, alone in its set.
LightSet pointAt(const glm::vec3& position, float intensity) {
    LightSet set;
    set.lights = {pointLight(position, intensity, glm::vec3(1.0f))};
    return set;
}

glm::vec3 vec3Of(const nlohmann::json& v) { return {v[0].get<float>(), v[1].get<float>(), v[2].get<float>()}; }

// Design review with two browsers and a native client on one session: the editor drags a
// light's gizmo, and the viewer's browser, `picclient watch` and a gRPC subscriber get the
// version that carries it, the light where the editor put it; the viewer cannot change
// lights; a viewer whose connection drops connects again and draws the next change.
TEST(BrowserSession, ALightDraggedInOneBrowserReachesTheOthers) {
    requireBrowser();
    OpenSession open;
    ASSERT_NO_FATAL_FAILURE(openSession("cornell", 4096, open));
    auto& [server, connection, session] = open;
    const Scene scene = loadTestScene("cornell");
    const glm::vec3 start = scene.bounds.center() + glm::vec3(0.0f, 0.2f, 0.0f) * scene.bounds.extent();
    auto first = connection->setLights(session.session(), session.editor_token(),
                                          pointAt(start, glm::dot(scene.bounds.extent(), scene.bounds.extent())));
    ASSERT_TRUE(first) << first.error().message;
    Reader native(*connection, session.session(), session.viewer_token());
    ASSERT_TRUE(native.waitFor(*first));
    Child watch({PIC_PICCLIENT, "watch", "--server", server->address(), "--session",
                 session.session(), "--token", session.viewer_token()});

    // Small shadow maps: every drag redraws a point light's six layers in both pages.
    const std::string page = fmt::format("http://{}/?session={}&size=480x320&samples=1&shadow_map_size=256&token=",
                                         server->webAddress(), session.session());
    int exit = 0;
    const std::string output = run(fmt::format("node {}/tests/session.mjs --editor '{}{}&viewer={}' --viewer '{}{}' 2>&1",
                                               kWebDir, page, session.editor_token(),
                                               session.viewer_token(), page, session.viewer_token()),
                                   exit);
    ASSERT_EQ(exit, 0) << output;
    // The driver's report is its last line.
    const size_t end = output.find_last_not_of('\n');
    const size_t begin = output.rfind('\n', end);
    const auto json = nlohmann::json::parse(
        output.substr(begin == std::string::npos ? 0 : begin + 1, end + 1), nullptr, false);
    ASSERT_FALSE(json.is_discarded()) << output;
    EXPECT_EQ(json["editorRole"], "editor");
    EXPECT_EQ(json["viewerRole"], "viewer");

    // Share links: the editor's view link grants viewing, its editing link editing; a viewer's
    // link is a viewer's; a page whose viewer token is the editor's does not start.
    const auto tokenOf = [](const std::string& url) {
        const size_t at = url.find("token=");
        return at == std::string::npos ? std::string() : url.substr(at + 6, url.find('&', at) - at - 6);
    };
    EXPECT_EQ(tokenOf(json["editorShare"]["view"]), session.viewer_token()) << json["editorShare"].dump();
    EXPECT_EQ(json["editorShare"]["view"].get<std::string>().find(session.editor_token()), std::string::npos);
    EXPECT_EQ(tokenOf(json["editorShare"]["edit"]), session.editor_token()) << json["editorShare"].dump();
    EXPECT_TRUE(json["editorShare"]["editButton"]);
    EXPECT_EQ(json["editorShare"]["label"], "Share this view");
    EXPECT_EQ(tokenOf(json["viewerShare"]["view"]), session.viewer_token());
    EXPECT_FALSE(json["viewerShare"]["editButton"]);
    EXPECT_NE(json["wrongViewerError"].get<std::string>().find("viewer token"), std::string::npos)
        << json["wrongViewerError"];

    // The viewer draws the editor's version with the light where the editor dropped it.
    const glm::vec3 before = vec3Of(json["before"]["position"]);
    const glm::vec3 dragged = vec3Of(json["editorLight"]["position"]);
    const glm::vec3 seen = vec3Of(json["viewerLight"]["position"]);
    EXPECT_GT(glm::length(dragged - before), 1e-3f) << "the drag did not move the light";
    EXPECT_LT(glm::length(seen - dragged), 1e-5f);
    const uint64_t version = json["version"].get<uint64_t>();
    EXPECT_GT(version, *first);

    // The viewer's drag sends nothing and its own set is refused, changing no version.
    EXPECT_EQ(json["viewerDragRequests"], 0);
    EXPECT_EQ(json["viewerRefusal"]["status"], 403) << json["viewerRefusal"].dump();
    EXPECT_EQ(json["viewerVersionAfterRefusal"], json["versionBeforeRefusal"]);

    // Connected again, the viewer draws the editor's next drag.
    EXPECT_GE(json["resumed"]["connections"].get<int>(), 2);
    const uint64_t last = json["resumed"]["version"].get<uint64_t>();
    EXPECT_GT(last, version);
    EXPECT_LT(glm::length(vec3Of(json["resumed"]["light"]["position"]) -
                          vec3Of(json["editorLightAfter"]["position"])),
              1e-5f);

    // The native clients: a gRPC subscriber holds the last version with the dragged light,
    // and picclient watch printed it.
    ASSERT_TRUE(native.waitFor(last));
    const auto lights = native.lights();
    ASSERT_TRUE(lights && lights->lights.size() == 1);
    EXPECT_LT(glm::length(lights->lights[0].position - vec3Of(json["editorLightAfter"]["position"])), 1e-5f);
    uint64_t watched = 0;
    while (watched < last) {
        const std::string line = readLine(watch.out());
        ASSERT_FALSE(line.empty()) << "picclient watch ended before version " << last;
        if (line.starts_with("version ")) watched = std::stoull(line.substr(8));
    }
    EXPECT_GE(watched, last);
}

// The browser transport without a browser (client/web/tests/sockets.mjs, the page's own
// stream and frame decoder in node, as MODE=sockets of bench/run_browser.sh runs it): eight
// WebSocket subscribers of one session each decode every version the editor pushes, and
// each holds the last one.
TEST(BrowserTransport, EverySocketDecodesEveryVersion) {
    requireBrowser();
    int exit = 0;
    std::string node = run("command -v node", exit);
    node.erase(node.find_last_not_of('\n') + 1);
    ASSERT_EQ(exit, 0) << "node is not on PATH";
    // node's WebSocket: built in from node 22, behind a flag in node 20.
    std::vector<std::string> args = {node};
    for (const std::string flag : {"", "--experimental-websocket"}) {
        run(fmt::format("{} {} -e 'process.exit(typeof WebSocket === \"function\" ? 0 : 1)' > /dev/null 2>&1",
                        node, flag),
            exit);
        if (exit != 0) continue;
        if (!flag.empty()) args.push_back(flag);
        break;
    }
    if (exit != 0) GTEST_SKIP() << "this node has no WebSocket (node >= 20.10 has one)";
    OpenSession open;
    ASSERT_NO_FATAL_FAILURE(openSession("cornell", 4096, open));
    auto& [server, connection, session] = open;
    Reader native(*connection, session.session(), session.viewer_token());

    constexpr int kSockets = 8, kChanges = 5;
    args.insert(args.end(), {kWebDir + "/tests/sockets.mjs", "--url",
                             fmt::format("http://{}/?session={}&token={}", server->webAddress(),
                                         session.session(), session.viewer_token()),
                             "--sockets", std::to_string(kSockets), "--duration-s", "120",
                             "--decode", "1", "--timeout-s", "300"});
    Child sockets(args);
    ASSERT_EQ(readLine(sockets.out()), "ready");

    const Scene scene = loadTestScene("cornell");
    const float intensity = glm::dot(scene.bounds.extent(), scene.bounds.extent());
    uint64_t last = 0;
    for (int i = 0; i < kChanges; ++i) {
        const glm::vec3 at = scene.bounds.center() + glm::vec3(0.1f * i, 0.2f, 0.0f) * scene.bounds.extent();
        auto version = connection->setLights(session.session(), session.editor_token(), pointAt(at, intensity));
        ASSERT_TRUE(version) << version.error().message;
        ASSERT_TRUE(native.waitFor(*version));  // one at a time: none is merged into the next
        last = *version;
    }
    sockets.signal(SIGUSR2);  // the changes are over: drain and report
    const auto report = nlohmann::json::parse(readLine(sockets.out()), nullptr, false);
    ASSERT_EQ(sockets.wait(), 0);
    ASSERT_FALSE(report.is_discarded());
    EXPECT_EQ(report["versions"]["newest"], last);
    EXPECT_EQ(report["versions"]["sockets_without_newest"], 0);
    EXPECT_EQ(report["versions"]["never_received_total"], 0);
    // Every version counted for every socket (a socket that fell behind skips to the newest,
    // latest wins, and a skipped version counts until the newer one arrived).
    EXPECT_EQ(report["received_latency_ms"]["samples"], kSockets * kChanges) << report.dump();
    const int frames = report["frame_bytes"]["key"]["frames"].get<int>() +
                       report["frame_bytes"]["delta"]["frames"].get<int>();
    EXPECT_GE(report["frame_bytes"]["key"]["frames"].get<int>(), kSockets) << report.dump();
    EXPECT_LE(frames, kSockets * (kChanges + 1)) << report.dump();
    EXPECT_EQ(report["reconnects"], 0);
}

}  // namespace
}  // namespace pic
