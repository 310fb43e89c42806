// The server, the stream and the thin client on loopback (127.0.0.1, port 0): sessions and
// tokens, light-set validation, coalescing, latest-wins delivery to fast and stalled
// subscribers, key frames for late joiners, exact decoding, the scene download, and the
// picserver / picclient command lines (the session database: session_database_test.cpp).
// Every server a test starts is stopped by it.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <future>

#include <grpcpp/generic/generic_stub.h>
#include <limits>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "client/connection.h"
#include "core/bake_file.h"
#include "core/camera.h"
#include "core/color.h"
#include "core/gltf_loader.h"
#include "core/image.h"
#include "proto/wire.h"
#include "render/cpu/cache_shading.h"
#include "render/cpu_runtime.h"
#include "render/renderer.h"
#include "server/service.h"
#include "tests/support/baked_scene.h"
#include "tests/client/stream_fixture.h"
#include "tests/support/command.h"

namespace pic {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using namespace test;

/// The CPU twin on the test bake, set up as serve() runs it (one bounce, unless told): it is
/// deterministic, so it gives the served caches for the same lights.
struct Twin {
    Scene scene;
    BakeData bake;
    std::unique_ptr<EmbreeScene> rays;
    std::unique_ptr<Runtime> runtime;
};

std::unique_ptr<Twin> cpuTwin(int bounces = 1) {
    auto twin = std::make_unique<Twin>();
    auto scene = loadScene(kScene);
    auto bake = readBakeFile(bakePath());
    EXPECT_TRUE(scene && bake);
    if (!scene || !bake) return nullptr;
    twin->scene = std::move(*scene);
    twin->bake = std::move(*bake);
    auto rays = EmbreeScene::create(twin->scene);
    EXPECT_TRUE(rays);
    if (!rays) return nullptr;
    twin->rays = std::move(*rays);
    auto runtime = createCpuRuntime(twin->scene, *twin->rays, twin->bake, BounceParams{bounces});
    EXPECT_TRUE(runtime);
    if (!runtime) return nullptr;
    twin->runtime = std::move(*runtime);
    return twin;
}


TEST(Stream, TwoSubscribersReceiveEveryVersionTheyCanAndAlwaysTheLastDecodedExactly) {
    Served served = serve();
    ASSERT_TRUE(served.connection);
    auto session = served.connection->createSession();
    ASSERT_TRUE(session) << session.error().message;
    EXPECT_EQ(session->version(), 1u);
    Reader editorView(*served.connection, session->session(), session->editor_token());
    Reader viewer(*served.connection, session->session(), session->viewer_token());
    ASSERT_TRUE(editorView.waitFor(1));
    ASSERT_TRUE(viewer.waitFor(1));

    auto live = served.server->session(session->session());
    ASSERT_TRUE(live);
    uint64_t last = 0;
    for (int i = 0; i < 6; ++i) {
        auto version = served.connection->setLights(session->session(), session->editor_token(),
                                                    pointLight(-0.3f + 0.1f * float(i)));
        ASSERT_TRUE(version) << version.error().message;
        EXPECT_EQ(*version, uint64_t(i) + 2);
        last = *version;
        // Paced: each version is computed before the next set arrives.
        ASSERT_TRUE(live->waitForVersion(last, 30s));
    }
    ASSERT_TRUE(editorView.waitFor(last));
    ASSERT_TRUE(viewer.waitFor(last));

    const auto update = live->latestUpdate();
    ASSERT_TRUE(update);
    ASSERT_EQ(update->version, last);

    auto stats = served.connection->stats(session->session(), session->viewer_token());
    ASSERT_TRUE(stats) << stats.error().message;
    EXPECT_EQ(stats->versions_set(), last);
    EXPECT_EQ(stats->versions_computed(), last);
    EXPECT_EQ(stats->key_frames() + stats->delta_frames(), last);
    EXPECT_EQ(stats->subscribers(), 2u);
    EXPECT_GE(stats->frames_sent(), 2 * last - 1);  // the last frame may still be in flight
    EXPECT_GT(stats->broadcast_bytes(), 0u);
    EXPECT_GT(stats->mean_update_ms(), 0.0);
    for (Reader* reader : {&editorView, &viewer}) {
        const auto versions = reader->received();
        const auto keys = reader->keys();
        EXPECT_TRUE(reader->errors().empty()) << reader->errors().front();
        ASSERT_FALSE(versions.empty());
        EXPECT_TRUE(keys.front()) << "the first frame of a subscriber is a key frame";
        EXPECT_EQ(versions.back(), last);
        for (size_t i = 1; i < versions.size(); ++i) EXPECT_LT(versions[i - 1], versions[i]);
        // Paced updates and fast readers: nothing is skipped.
        EXPECT_EQ(versions.size(), last) << "versions received";
        // Lossless: the decoded textures are the server's half floats, bit for bit.
        EXPECT_TRUE(reader->frame() == *update->frame);
    }
}

TEST(Stream, LateJoinerFirstFrameIsAKeyFrameOfTheLatestVersion) {
    Served served = serve();
    ASSERT_TRUE(served.connection);
    auto session = served.connection->createSession();
    ASSERT_TRUE(session);
    auto live = served.server->session(session->session());
    for (int i = 0; i < 3; ++i) {
        auto version = served.connection->setLights(session->session(), session->editor_token(),
                                                    pointLight(0.1f * float(i)));
        ASSERT_TRUE(version);
        ASSERT_TRUE(live->waitForVersion(*version, 30s));
    }
    const auto latest = live->latestUpdate();
    ASSERT_TRUE(latest);
    EXPECT_NE(latest->base.version, 0u) << "the broadcast frame of version 4 is a delta";
    Reader late(*served.connection, session->session(), session->viewer_token());
    ASSERT_TRUE(late.waitFor(latest->version));
    ASSERT_FALSE(late.keys().empty());
    EXPECT_TRUE(late.keys().front());
    EXPECT_EQ(late.received().front(), latest->version);
    EXPECT_TRUE(late.frame() == *latest->frame);
    EXPECT_TRUE(latest->keyEncoded());
}

TEST(Stream, KeyFrameOnDemandIsEncodedOncePerVersionForAnyNumberOfSubscribers) {
    Served served = serve();
    ASSERT_TRUE(served.connection);
    auto session = served.connection->createSession();
    ASSERT_TRUE(session);
    auto live = served.server->session(session->session());
    ASSERT_TRUE(live->waitForVersion(1, 30s));
    auto version = served.connection->setLights(session->session(), session->editor_token(),
                                                pointLight(0.2f));
    ASSERT_TRUE(version);
    ASSERT_TRUE(live->waitForVersion(*version, 30s));
    const auto update = live->latestUpdate();
    ASSERT_NE(update->base.version, 0u);
    EXPECT_EQ(update->frameFor(update->base), update->broadcast);
    const auto key = update->frameFor({});
    ASSERT_TRUE(key);
    EXPECT_EQ(key->base_version(), 0u);
    for (uint64_t held : {0u, 1u, 7u})
        EXPECT_EQ(update->frameFor({held, 0}).get(),
                  held == update->base.version ? update->broadcast.get() : key.get());
}

TEST(Stream, StalledSubscriberDoesNotDelayTheOthersAndSkipsToTheLast) {
    Served served = serve();
    ASSERT_TRUE(served.connection);
    auto session = served.connection->createSession();
    ASSERT_TRUE(session);
    auto live = served.server->session(session->session());
    ASSERT_TRUE(live->waitForVersion(1, 30s));

    // A subscriber that never reads until the end.
    auto stalled = served.connection->subscribe(session->session(), session->viewer_token());
    Reader fast(*served.connection, session->session(), session->viewer_token());
    ASSERT_TRUE(fast.waitFor(1));

    constexpr int kUpdates = 200;
    uint64_t last = 0;
    const auto start = std::chrono::steady_clock::now();
    for (int i = 0; i < kUpdates; ++i) {
        auto version = served.connection->setLights(session->session(), session->editor_token(),
                                                    pointLight(0.01f * float(i % 20)));
        ASSERT_TRUE(version);
        last = *version;
        ASSERT_TRUE(fast.waitFor(last, 30s)) << "the fast subscriber waited on the stalled one";
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_EQ(fast.received().back(), last);
    size_t bytes = 0;
    for (const v1::Plane& plane : live->latestUpdate()->broadcast->planes()) bytes += plane.data().size();
    std::printf("%d updates (%zu bytes each) to the fast subscriber in %.2f s beside a stalled one\n",
                kUpdates, bytes, seconds);

    // The stalled subscriber now reads: it gets what gRPC had buffered, then the last version,
    // never all of them.
    v1::Frame frame;
    FrameDecoder decoder(sceneHeaderOf(*served.connection));
    int frames = 0;
    while (decoder.version() < last && stalled->next(frame)) {
        ASSERT_TRUE(decoder.apply(frame)) << "version " << frame.version();
        ++frames;
    }
    EXPECT_EQ(decoder.version(), last);
    EXPECT_TRUE(decoder.frame() == *live->latestUpdate()->frame);
    std::printf("the stalled subscriber received %d frames for %llu versions\n", frames,
                (unsigned long long)last);
    EXPECT_LT(frames, int(last));
}

TEST(Stream, DisconnectedSubscriberIsRemovedAtOnce) {
    Served served = serve();
    ASSERT_TRUE(served.connection);
    auto session = served.connection->createSession();
    ASSERT_TRUE(session);
    auto live = served.server->session(session->session());
    {
        Reader a(*served.connection, session->session(), session->viewer_token());
        Reader b(*served.connection, session->session(), session->viewer_token());
        ASSERT_TRUE(a.waitFor(1));
        ASSERT_TRUE(b.waitFor(1));
        EXPECT_EQ(live->subscribers(), 2u);
    }
    const auto start = std::chrono::steady_clock::now();
    while (live->subscribers() > 0 && std::chrono::steady_clock::now() - start < 5s)
        std::this_thread::sleep_for(1ms);
    EXPECT_EQ(live->subscribers(), 0u);
    std::printf("subscribers removed %.1f ms after they disconnected\n",
                std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
}

TEST(Stream, IdleSessionsWithoutSubscribersAreRemoved) {
    Served served = serve("cpu", 32, 300ms);
    ASSERT_TRUE(served.connection);
    auto idle = served.connection->createSession();
    auto watched = served.connection->createSession();
    ASSERT_TRUE(idle && watched);
    Reader reader(*served.connection, watched->session(), watched->viewer_token());
    ASSERT_TRUE(reader.waitFor(1));
    std::this_thread::sleep_for(1200ms);
    auto gone = served.connection->joinSession(idle->session(), idle->editor_token());
    ASSERT_FALSE(gone);
    EXPECT_EQ(gone.error().code, ErrorCode::NotFound);
    auto kept = served.connection->joinSession(watched->session(), watched->editor_token());
    EXPECT_TRUE(kept) << "a session with a subscriber stays";
}

// The load runs one update with the scene's own lights (ServedBake::warmUp), and a session
// that then asks for the same lights gets the same caches as a runtime that never ran one.
TEST(Stream, ALoadRunsAFirstUpdateThatChangesNoResult) {
    ServeOptions options;
    options.backend = "cpu";
    options.bounces.bounces = 1;
    auto served = ServedBake::load(bakePath(), kScene, options);
    ASSERT_TRUE(served) << served.error().message;
    EXPECT_GT((*served)->warmUpMs(), 0.0);
    UpdateStats stats;
    HalfFrame frame;
    const LightSet lights = pointLight(0.25f);
    ASSERT_TRUE((*served)->relight(lights, stats, frame));

    auto twin = cpuTwin();
    ASSERT_TRUE(twin);
    auto values = twin->runtime->setLights(lights);
    ASSERT_TRUE(values);
    EXPECT_TRUE(frame == halfFrameOf(**values));
}

TEST(Stream, HealthCheckSaysServing) {
    Served served = serve();
    ASSERT_TRUE(served.connection);
    EXPECT_EQ(healthStatus(served.server->address()), "SERVING");
}

// GET /metrics: Prometheus text with the updates computed per session, the update and pass
// histograms, frames sent, sessions, subscribers and the database's calls; other paths 404.
TEST(Stream, MetricsCountWhatTheServerDid) {
    const test::ScratchDir dir("pic_metrics");
    ServerOptions options;
    options.metricsListen = "127.0.0.1:0";
    options.dbPath = (dir / "sessions.db").string();
    Served served = serveWith(options);
    ASSERT_TRUE(served.connection);
    const std::string address = served.server->metricsAddress();
    ASSERT_TRUE(address.starts_with("127.0.0.1:")) << address;
    EXPECT_NE(address, "127.0.0.1:0");
    auto session = served.connection->createSession();
    ASSERT_TRUE(session);
    // Version 1 first: a light set pushed while it computes would supersede it.
    Reader reader(*served.connection, session->session(), session->viewer_token());
    ASSERT_TRUE(reader.waitFor(1));
    ASSERT_TRUE(served.connection->setLights(session->session(), session->editor_token(), pointLight(0.1f)));
    ASSERT_TRUE(reader.waitFor(2));

    // A version reaches the metrics just after its subscribers (Session::publish logs it once
    // the slots hold it): read them until they count it.
    const std::string computed = "pic_session_versions_computed_total{session=\"" + session->session() + "\"}";
    HttpReply reply = httpGet(address, "/metrics");
    for (int attempt = 0; attempt < 500 && metricValue(reply.body, computed) < 2.0; ++attempt) {
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
        reply = httpGet(address, "/metrics");
    }
    ASSERT_EQ(reply.status, "HTTP/1.1 200 OK") << reply.body;
    const std::string& text = reply.body;
    EXPECT_EQ(metricValue(text, "pic_sessions"), 1.0) << text;
    EXPECT_EQ(metricValue(text, "pic_subscribers"), 1.0);
    EXPECT_EQ(metricValue(text, "pic_session_versions_computed_total{session=\"" +
                                    session->session() + "\"}"),
              2.0)
        << text;
    EXPECT_GE(metricValue(text, "pic_updates_total"), 2.0);
    EXPECT_GE(metricValue(text, "pic_frames_sent_total"), 1.0);
    EXPECT_EQ(metricValue(text, "pic_update_ms_count"), metricValue(text, "pic_updates_total"));
    EXPECT_EQ(metricValue(text, "pic_update_ms_bucket{le=\"+Inf\"}"), metricValue(text, "pic_update_ms_count"));
    EXPECT_NE(text.find("pic_pass_ms_bucket{pass=\""), std::string::npos) << text;
    EXPECT_EQ(metricValue(text, "pic_store_ms_count{op=\"create\"}"), 1.0);
    EXPECT_EQ(metricValue(text, "pic_store_ms_count{op=\"save\"}"), 1.0);
    EXPECT_EQ(metricValue(text, "pic_store_up"), 1.0);
    EXPECT_NE(text.find("# TYPE pic_update_ms histogram"), std::string::npos);
    EXPECT_TRUE(httpGet(address, "/other").status.starts_with("HTTP/1.1 404")) << httpGet(address, "/other").status;
}

/// One ServerReflectionInfo exchange: sends `request`, collects the first reply's bytes.
class ReflectionCall final : public grpc::ClientBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer> {
public:
    ReflectionCall(grpc::GenericStub& stub, const std::string& request) {
        grpc::Slice slice(request);
        mRequest = grpc::ByteBuffer(&slice, 1);
        stub.PrepareBidiStreamingCall(&mContext, "/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo",
                                      grpc::StubOptions(), this);
        StartWriteLast(&mRequest, grpc::WriteOptions());
        StartRead(&mResponse);
        StartCall();
    }
    void OnReadDone(bool ok) override {
        if (ok) {
            std::vector<grpc::Slice> slices;
            if (mResponse.Dump(&slices).ok())
                for (const auto& slice : slices)
                    mReply.append(reinterpret_cast<const char*>(slice.begin()), slice.size());
        }
    }
    void OnDone(const grpc::Status& status) override { mDone.set_value(status); }
    std::string reply() {
        mDone.get_future().get();
        return mReply;
    }

private:
    grpc::ClientContext mContext;
    grpc::ByteBuffer mRequest, mResponse;
    std::string mReply;
    std::promise<grpc::Status> mDone;
};

TEST(Stream, ReflectionListsThePicService) {
    Served served = serve();
    ASSERT_TRUE(served.connection);
    auto channel = grpc::CreateChannel(served.server->address(), grpc::InsecureChannelCredentials());
    grpc::GenericStub stub(channel);
    // ServerReflectionRequest{list_services: ""}: field 7, length-delimited, empty.
    ReflectionCall call(stub, std::string("\x3a\x00", 2));
    const std::string reply = call.reply();
    EXPECT_NE(reply.find("pic.v1.Pic"), std::string::npos) << "reflection lists the service";
}

TEST(Stream, TokensAndRoles) {
    Served served = serve();
    ASSERT_TRUE(served.connection);
    auto session = served.connection->createSession();
    ASSERT_TRUE(session);
    const LightSet lights = pointLight(0.0f);

    grpc::ClientContext context;
    v1::SetLightsRequest request;
    request.set_session(session->session());
    request.set_token(session->viewer_token());
    *request.mutable_lights() = wire::toProto(lights);
    v1::SetLightsResponse response;
    EXPECT_EQ(served.connection->stub().SetLights(&context, request, &response).error_code(),
              grpc::StatusCode::PERMISSION_DENIED);

    grpc::ClientContext context2;
    request.set_token("not-a-token");
    EXPECT_EQ(served.connection->stub().SetLights(&context2, request, &response).error_code(),
              grpc::StatusCode::UNAUTHENTICATED);

    grpc::ClientContext context3;
    request.set_session("no-such-session");
    EXPECT_EQ(served.connection->stub().SetLights(&context3, request, &response).error_code(),
              grpc::StatusCode::NOT_FOUND);

    auto joined = served.connection->joinSession(session->session(), session->viewer_token());
    ASSERT_TRUE(joined);
    EXPECT_EQ(joined->role(), v1::VIEWER);
    joined = served.connection->joinSession(session->session(), session->editor_token());
    ASSERT_TRUE(joined);
    EXPECT_EQ(joined->role(), v1::EDITOR);

    // A viewer cannot subscribe with a wrong token either.
    auto stream = served.connection->subscribe(session->session(), "wrong");
    v1::Frame frame;
    EXPECT_FALSE(stream->next(frame));
    EXPECT_EQ(stream->status().error_code(), grpc::StatusCode::UNAUTHENTICATED);
}

// A client behind a load balancer draws the session id it routes by: the server takes it,
// once; an id of another form is refused. Every session call carries it as metadata.
TEST(Stream, CreateSessionTakesTheIdTheClientDrewOnce) {
    Served served = serve();
    ASSERT_TRUE(served.connection);
    const auto create = [&](const std::string& id) {
        grpc::ClientContext context;
        v1::CreateSessionRequest request;
        request.set_session(id);
        v1::CreateSessionResponse response;
        const grpc::Status status = served.connection->stub().CreateSession(&context, request, &response);
        return status.ok() ? response.session() : "status " + std::to_string(int(status.error_code()));
    };
    EXPECT_EQ(create("0123456789abcdef"), "0123456789abcdef");
    EXPECT_EQ(create("0123456789abcdef"), "status " + std::to_string(int(grpc::StatusCode::ALREADY_EXISTS)));
    for (const char* bad : {"0123456789ABCDEF", "0123", "0123456789abcdef0", "../../etc/passwd0"})
        EXPECT_EQ(create(bad), "status " + std::to_string(int(grpc::StatusCode::INVALID_ARGUMENT))) << bad;
    auto drawn = served.connection->createSession();
    ASSERT_TRUE(drawn);
    EXPECT_TRUE(wire::isSessionId(drawn->session())) << drawn->session();
}

TEST(Stream, MalformedLightSetsAreInvalidArgumentNamingTheField) {
    Served served = serve();
    ASSERT_TRUE(served.connection);
    auto session = served.connection->createSession();
    ASSERT_TRUE(session);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();

    struct Case {
        const char* field;
        std::function<void(v1::LightSet&)> spoil;
    };
    const std::vector<Case> cases = {
        {"lights[0].intensity", [&](v1::LightSet& s) { s.mutable_lights(0)->set_intensity(nan); }},
        {"lights[0].intensity", [&](v1::LightSet& s) { s.mutable_lights(0)->set_intensity(-1.0f); }},
        {"lights[0].position[1]", [&](v1::LightSet& s) { s.mutable_lights(0)->mutable_position()->set_y(inf); }},
        {"lights[0].color", [&](v1::LightSet& s) { s.mutable_lights(0)->mutable_color()->set_x(-0.5f); }},
        {"lights[0].type", [&](v1::LightSet& s) { s.mutable_lights(0)->set_type(v1::Light::TYPE_UNSPECIFIED); }},
        {"lights[1].direction", [&](v1::LightSet& s) {
             v1::Light& sun = *s.add_lights();
             sun.set_type(v1::Light::DIRECTIONAL);
             sun.mutable_direction()->set_x(0.0f);
         }},
        {"lights[1].outerConeAngle", [&](v1::LightSet& s) {
             v1::Light& spot = *s.add_lights();
             spot.set_type(v1::Light::SPOT);
             spot.set_outer_cone_angle(2.0f);
         }},
        {"lights[1].innerConeAngle", [&](v1::LightSet& s) {
             v1::Light& spot = *s.add_lights();
             spot.set_type(v1::Light::SPOT);
             spot.set_inner_cone_angle(0.9f);
             spot.set_outer_cone_angle(0.5f);
         }},
        {"lights holds 257", [&](v1::LightSet& s) {
             for (int i = 1; i < 257; ++i) {
                 *s.add_lights() = s.lights(0);
                 s.mutable_lights(i)->set_id(fmt::format("l{}", i));
             }
         }},
        {"emissiveScale", [&](v1::LightSet& s) { (*s.mutable_emissive_scale())["no such material"] = 1.0f; }},
        // An id is a name, not a payload: a 64 KiB one would go into the database. (A 1 MiB
        // request is refused before it is read: access_test.cpp.)
        {"lights[0].id", [&](v1::LightSet& s) { s.mutable_lights(0)->set_id(std::string(1 << 16, 'x')); }},
        {"lights[0].id", [&](v1::LightSet& s) { s.mutable_lights(0)->set_id("bell\a"); }},
        {"lights[0].intensity × color", [&](v1::LightSet& s) { s.mutable_lights(0)->set_intensity(3e38f); }},
    };
    for (const Case& c : cases) {
        v1::SetLightsRequest request;
        request.set_session(session->session());
        request.set_token(session->editor_token());
        *request.mutable_lights() = wire::toProto(pointLight(0.0f));
        c.spoil(*request.mutable_lights());
        grpc::ClientContext context;
        v1::SetLightsResponse response;
        grpc::Status status = served.connection->stub().SetLights(&context, request, &response);
        EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << c.field;
        EXPECT_NE(status.error_message().find(c.field), std::string::npos)
            << "message \"" << status.error_message() << "\" names " << c.field;
    }
    // Nothing was queued: the version is still the first.
    auto joined = served.connection->joinSession(session->session(), session->editor_token());
    ASSERT_TRUE(joined);
    EXPECT_EQ(joined->version(), 1u);
}

TEST(Stream, LightSetsCoalesceWhileAnUpdateComputes) {
    Served served = serve();
    ASSERT_TRUE(served.connection);
    auto session = served.connection->createSession();
    ASSERT_TRUE(session);
    Reader reader(*served.connection, session->session(), session->viewer_token());
    uint64_t last = 0;
    for (int i = 0; i < 20; ++i) {
        auto version = served.connection->setLights(session->session(), session->editor_token(),
                                                    pointLight(0.01f * float(i)));
        ASSERT_TRUE(version);
        EXPECT_EQ(*version, uint64_t(i) + 2);
        last = *version;
    }
    ASSERT_TRUE(reader.waitFor(last));
    const auto versions = reader.received();
    EXPECT_EQ(versions.back(), last);
    EXPECT_LT(versions.size(), size_t(last)) << "20 sets sent back to back were coalesced";
    EXPECT_TRUE(reader.errors().empty());
}

TEST(Stream, SceneDownloadLoadsTheSameSceneAndLayout) {
    Served served = serve();
    ASSERT_TRUE(served.connection);
    const test::ScratchDir dir("pic_stream_cache");
    const fs::path cache = dir / "cache";
    bool downloaded = false;
    auto client = served.connection->fetchScene("", cache.string(), &downloaded);
    ASSERT_TRUE(client) << client.error().message;
    EXPECT_TRUE(downloaded);
    // Kept: the next fetch reuses the folder; a damaged copy is downloaded again.
    auto again = served.connection->fetchScene("", cache.string(), &downloaded);
    ASSERT_TRUE(again) << again.error().message;
    EXPECT_FALSE(downloaded);
    EXPECT_EQ(again->scene.hash, client->scene.hash);
    fs::remove(fs::path(client->folder) / "layout" / "grid_caches");
    again = served.connection->fetchScene("", cache.string(), &downloaded);
    ASSERT_TRUE(again) << again.error().message;
    EXPECT_TRUE(downloaded);
    EXPECT_EQ(again->gridCaches, client->gridCaches);
    {
        // An index map that names a cache the bake does not have is refused, so the kept
        // copy is downloaded again.
        std::fstream map(fs::path(client->folder) / "layout" / "lightmap_caches",
                         std::ios::in | std::ios::out | std::ios::binary);
        const uint32_t beyond = client->header.caches();
        map.write(reinterpret_cast<const char*>(&beyond), sizeof(beyond));
    }
    again = served.connection->fetchScene("", cache.string(), &downloaded);
    ASSERT_TRUE(again) << again.error().message;
    EXPECT_TRUE(downloaded);
    EXPECT_EQ(again->lightmapCaches, client->lightmapCaches);
    auto twin = cpuTwin();
    ASSERT_TRUE(twin);
    const BakeData& bake = twin->bake;
    EXPECT_EQ(client->scene.hash, bake.sceneHash);
    EXPECT_EQ(client->triangleUvs, bake.lightmap.triangleUvs);
    EXPECT_EQ(client->gridCaches, bake.grid.cacheIndex);
    EXPECT_EQ(client->lightmapCaches, bake.lightmap.cacheIndex);
    EXPECT_EQ(client->header.caches(), bake.caches.size());
    EXPECT_EQ(client->header.bands_y(), 3u);
    EXPECT_EQ(client->header.bands_c(), 2u);

    // The textures the client makes from a streamed frame are the server's runtime's own,
    // through halves: the scene's lights on the same bake, one bounce.
    auto session = served.connection->createSession();
    ASSERT_TRUE(session);
    Reader reader(*served.connection, session->session(), session->viewer_token());
    ASSERT_TRUE(reader.waitFor(1));
    auto textures = cacheTexturesOf(*client, reader.frame());
    ASSERT_TRUE(textures) << textures.error().message;
    ASSERT_TRUE(twin->runtime->setLights(defaultLightSet(twin->scene)));
    auto expected = twin->runtime->textures();
    ASSERT_TRUE(expected);
    const auto halved = [](const std::vector<float>& values) {
        std::vector<float> out(values.size());
        for (size_t i = 0; i < values.size(); ++i)
            out[i] = halfToFloat(floatToHalfClamped(values[i]));
        return out;
    };
    for (int ch = 0; ch < 3; ++ch) {
        EXPECT_EQ(textures->grid[ch], halved((*expected)->grid[ch])) << ch;
        EXPECT_EQ(textures->lightmap[ch], halved((*expected)->lightmap[ch])) << ch;
    }
    EXPECT_EQ(textures->gridCoverage, (*expected)->gridCoverage);
    EXPECT_EQ(textures->lightmapCoverage, (*expected)->lightmapCoverage);

    // A decoder told the scene's layout takes its frames, and refuses, before decoding, the
    // frames of a bake with other caches.
    auto header = served.connection->sceneHeader(client->header.bake_id());
    ASSERT_TRUE(header) << header.error().message;
    EXPECT_EQ(header->caches(), client->header.caches());
    auto stream = served.connection->subscribe(session->session(), session->viewer_token());
    v1::Frame wireFrame;
    ASSERT_TRUE(stream->next(wireFrame));
    v1::Frame copy = wireFrame;
    FrameDecoder decoder(*header);
    ASSERT_TRUE(decoder.apply(copy));
    v1::SceneHeader other = *header;
    other.set_caches(header->caches() + 1);
    FrameDecoder refusing(other);
    auto refusedFrame = refusing.apply(wireFrame);
    ASSERT_FALSE(refusedFrame);
    EXPECT_EQ(refusedFrame.error().code, ErrorCode::Corrupt);
    EXPECT_NE(refusedFrame.error().message.find("cache_y"), std::string::npos)
        << refusedFrame.error().message;
    EXPECT_EQ(refusing.version(), 0u);
    stream->cancel();

    // A frame of another layout is refused, naming the plane.
    HalfFrame shortFrame = reader.frame();
    shortFrame.planes[1].pop_back();
    auto refused = cacheTexturesOf(*client, shortFrame);
    ASSERT_FALSE(refused);
    EXPECT_NE(refused.error().message.find("cache_co"), std::string::npos)
        << refused.error().message;

    auto missing = served.connection->fetchScene("0123456789abcdef", cache.string());
    ASSERT_FALSE(missing);
    EXPECT_EQ(missing.error().code, ErrorCode::NotFound);
}

TEST(Stream, GpuBackendServesTheSameProtocol) {
    Served served = serve("gpu");
    ASSERT_TRUE(served.connection);
    auto session = served.connection->createSession();
    ASSERT_TRUE(session);
    Reader reader(*served.connection, session->session(), session->viewer_token());
    auto version = served.connection->setLights(session->session(), session->editor_token(),
                                                pointLight(0.1f));
    ASSERT_TRUE(version);
    ASSERT_TRUE(reader.waitFor(*version));
    EXPECT_TRUE(reader.frame() == *served.server->session(session->session())->latestUpdate()->frame);
}

// Every frame names the light set its caches were computed for, so that every client shades
// with the same direct light and indirect scales. A set that changes only the indirect scales
// (applied where clients shade, core/light_set.h IndirectScale) reuses the caches: no pass
// runs and the frame's planes are the previous version's.
TEST(Stream, FramesCarryTheirLightSetAndScaleOnlyChangesReuseTheCaches) {
    Served served = serve();
    ASSERT_TRUE(served.connection);
    auto session = served.connection->createSession();
    ASSERT_TRUE(session);
    Reader reader(*served.connection, session->session(), session->viewer_token());
    LightSet lights = pointLight(0.1f);
    auto first = served.connection->setLights(session->session(), session->editor_token(), lights);
    ASSERT_TRUE(first);
    ASSERT_TRUE(reader.waitFor(*first));
    const auto relit = served.server->session(session->session())->latestUpdate();
    ASSERT_EQ(relit->version, *first);
    EXPECT_GT(relit->broadcast->bounces(), 0u);
    ASSERT_TRUE(reader.lights());
    EXPECT_EQ(reader.lights()->lights, lights.lights);
    EXPECT_EQ(reader.lights()->indirectScale, IndirectScale{});

    lights.indirectScale = {0.5f, 2.0f};
    auto scaled = served.connection->setLights(session->session(), session->editor_token(), lights);
    ASSERT_TRUE(scaled);
    ASSERT_TRUE(reader.waitFor(*scaled));
    const auto reused = served.server->session(session->session())->latestUpdate();
    ASSERT_EQ(reused->version, *scaled);
    EXPECT_EQ(reused->broadcast->bounces(), 0u);
    EXPECT_TRUE(*reused->frame == *relit->frame);
    EXPECT_EQ(reader.lights()->indirectScale, (IndirectScale{0.5f, 2.0f}));
    EXPECT_TRUE(reader.frame() == *relit->frame);

    // A light that moves is relit again.
    lights.lights[0].position.x += 0.1f;
    auto moved = served.connection->setLights(session->session(), session->editor_token(), lights);
    ASSERT_TRUE(moved);
    ASSERT_TRUE(reader.waitFor(*moved));
    EXPECT_GT(served.server->session(session->session())->latestUpdate()->broadcast->bounces(), 0u);
    EXPECT_TRUE(reader.errors().empty());
}

// picserver --update-budget-ms: an update over the budget streams earlier parts (estimates)
// before its final state, which is bit for bit the unbudgeted update's; every part is a delta
// against the state before it, and a subscriber that decodes them in order ends there.
TEST(Stream, ABudgetedUpdateStreamsItsPartsThenExactlyTheFullUpdate) {
    constexpr int kBounces = 3;
    ServerOptions options;
    options.session.setLightsPerSecond = 1e6;
    // Every update is over a budget this small, so each one after the first (which has no
    // previous version to estimate from) streams its caches in parts as its bounces end (the
    // first bounce, or the first two: the share due grows with the time spent), then its
    // final state. How parts pace themselves: progressive_test.cpp.
    options.session.updateBudgetMs = 1e-3;
    Served served = serveWith(options, "cpu", kBounces);
    ASSERT_TRUE(served.connection);
    auto session = served.connection->createSession();
    ASSERT_TRUE(session);
    auto live = served.server->session(session->session());
    ASSERT_TRUE(live->waitForVersion(1, 30s));
    // A subscriber that takes every update as it is published, and one on the wire.
    std::vector<std::shared_ptr<const Update>> published;
    std::mutex mutex;
    std::shared_ptr<SubscriberSlot> slot;
    slot = live->subscribe([&] {
        std::lock_guard lock(mutex);
        if (auto update = slot->take()) published.push_back(std::move(update));
    });
    {
        std::lock_guard lock(mutex);
        if (auto first = slot->take()) published.push_back(std::move(first));
    }
    Reader reader(*served.connection, session->session(), session->viewer_token());
    ASSERT_TRUE(reader.waitFor(1));

    auto twin = cpuTwin(kBounces);
    ASSERT_TRUE(twin);
    std::vector<HalfFrame> expected;
    for (int i = 0; i < 3; ++i) {
        const LightSet lights = pointLight(-0.2f + 0.2f * float(i));
        auto version = served.connection->setLights(session->session(), session->editor_token(), lights);
        ASSERT_TRUE(version);
        ASSERT_TRUE(live->waitForVersion(*version, 30s));
        auto values = twin->runtime->setLights(lights);
        ASSERT_TRUE(values);
        expected.push_back(halfFrameOf(**values));
        const auto start = std::chrono::steady_clock::now();
        while (!reader.holds(*version) && std::chrono::steady_clock::now() - start < 30s)
            std::this_thread::sleep_for(2ms);
        EXPECT_TRUE(reader.frame() == expected.back()) << "version " << *version;
    }
    live->unsubscribe(slot.get());
    EXPECT_TRUE(reader.errors().empty()) << reader.errors().front();
    const uint64_t parts = live->stats().partial_frames();
    EXPECT_GE(parts, 3u) << "one part at least for each of versions 2 to 4";
    EXPECT_LE(parts, 6u) << "one part at most for each of their first two bounces";
    EXPECT_EQ(live->stats().versions_computed(), 4u);

    // Version 1 alone, then each version's parts and its final state, each a delta against
    // the state before it (or a key frame), decoded in order to the twin's caches.
    std::lock_guard lock(mutex);
    ASSERT_EQ(published.size(), 4u + parts);
    EXPECT_EQ(published[0]->id(), (StateId{1, 0}));
    FrameDecoder decoder(sceneHeaderOf(*served.connection));
    size_t finals = 0;
    for (size_t i = 0; i < published.size(); ++i) {
        const Update& update = *published[i];
        if (i > 0) {
            const StateId before = published[i - 1]->id();
            EXPECT_TRUE(update.base == before || update.base.version == 0) << "update " << i;
            // Parts 1, 2, … of the version after the last final state, then its final state.
            EXPECT_EQ(update.version, before.part == 0 ? before.version + 1 : before.version);
            if (update.part != 0) {
                EXPECT_EQ(update.part, before.part + 1);
            }
        }
        v1::Frame frame = *update.broadcast;
        ASSERT_TRUE(decoder.apply(frame)) << "update " << i;
        EXPECT_EQ(decoder.part(), update.part);
        EXPECT_TRUE(decoder.frame() == *update.frame);
        if (i > 0 && update.part == 0) {
            EXPECT_TRUE(decoder.frame() == expected[finals]) << "the final state is exact";
            ++finals;
            // The part before it held estimates: not yet this version's caches.
            EXPECT_NE(published[i - 1]->part, 0u);
            EXPECT_FALSE(*published[i - 1]->frame == decoder.frame());
        }
    }
    EXPECT_EQ(finals, 3u);
    // A delta against another part than the one held is refused.
    v1::Frame wrongBase = *published.back()->broadcast;
    wrongBase.set_base_part(2);
    EXPECT_FALSE(decoder.apply(wrongBase));
}

TEST(Stream, ASkyIsRelitStreamedAndCarriedBackAndABadOneRefused) {
    // The Cornell box opens at the front: a sky over the wire relights it, the frame carries
    // the sky back, and turning the sky relights it again; an environment that is not there is
    // refused by the session before any version is taken.
    Served served = serve();
    ASSERT_TRUE(served.connection);
    auto session = served.connection->createSession();
    ASSERT_TRUE(session);
    Reader reader(*served.connection, session->session(), session->viewer_token());
    LightSet lights = pointLight(0.1f);
    auto lamp = served.connection->setLights(session->session(), session->editor_token(), lights);
    ASSERT_TRUE(lamp);
    ASSERT_TRUE(reader.waitFor(*lamp));
    const auto lampOnly = served.server->session(session->session())->latestUpdate();

    lights.sky = SkyLight{.id = "daylight", .color = {0.6f, 0.75f, 1.0f}, .intensity = 2.0f};
    auto sky = served.connection->setLights(session->session(), session->editor_token(), lights);
    ASSERT_TRUE(sky) << sky.error().message;
    ASSERT_TRUE(reader.waitFor(*sky));
    const auto skyLit = served.server->session(session->session())->latestUpdate();
    EXPECT_GT(skyLit->broadcast->bounces(), 0u);
    EXPECT_TRUE(skyLit->broadcast->pass_ms().contains("sky_caches"));
    EXPECT_FALSE(*skyLit->frame == *lampOnly->frame);
    ASSERT_TRUE(reader.lights());
    EXPECT_EQ(reader.lights()->sky, lights.sky);
    EXPECT_TRUE(reader.frame() == *skyLit->frame);

    const uint64_t before = served.server->session(session->session())->latestVersion();
    LightSet missing = lights;
    missing.sky->environment = "absent.hdr";
    auto refused = served.connection->setLights(session->session(), session->editor_token(), missing);
    ASSERT_FALSE(refused);
    EXPECT_NE(refused.error().message.find("absent.hdr"), std::string::npos)
        << refused.error().message;
    EXPECT_EQ(served.server->session(session->session())->latestVersion(), before);
    EXPECT_TRUE(reader.errors().empty());
}

TEST(Stream, ClientIndirectRenderFromTheStreamMatchesTheCpuShading) {
    Served served = serve();
    ASSERT_TRUE(served.connection);
    const test::ScratchDir dir("pic_stream_render");
    const fs::path cache = dir / "cache";
    auto client = served.connection->fetchScene("", cache.string());
    ASSERT_TRUE(client) << client.error().message;
    auto session = served.connection->createSession();
    ASSERT_TRUE(session);
    Reader reader(*served.connection, session->session(), session->viewer_token());
    const LightSet lights = pointLight(0.15f);
    auto version = served.connection->setLights(session->session(), session->editor_token(), lights);
    ASSERT_TRUE(version);
    ASSERT_TRUE(reader.waitFor(*version));
    auto textures = cacheTexturesOf(*client, reader.frame());
    ASSERT_TRUE(textures) << textures.error().message;

    auto context = gpu::Context::create();
    ASSERT_TRUE(context) << context.error().message;
    auto renderer = Renderer::create(**context, client->scene, clientLayoutOf(*client));
    ASSERT_TRUE(renderer) << renderer.error().message;
    ASSERT_TRUE((*renderer)->setCaches(*textures));
    auto camera = sceneCamera(client->scene, 0);
    ASSERT_TRUE(camera);
    ShadeParams params;
    params.width = 127;  // odd: no wall corner through a pixel centre (client/renderer_test.cpp)
    params.height = 112;
    params.component = ShadeComponent::Indirect;
    auto image = (*renderer)->render(lights, *camera, params);
    ASSERT_TRUE(image) << image.error().message;

    // The CPU shading of the same caches.
    auto twin = cpuTwin();
    ASSERT_TRUE(twin);
    auto values = twin->runtime->setLights(lights);
    ASSERT_TRUE(values);
    auto reference =
        shadeFromCaches(twin->scene, *twin->rays, twin->bake, **values, lights, *camera, params);
    ASSERT_TRUE(reference);
    auto error = compareImages(*image, *reference);
    ASSERT_TRUE(error);
    std::printf("client indirect vs CPU shading: relative RMSE %.5f, mean ratio %.5f\n",
                error->relativeRmse, error->meanRatio);
    EXPECT_LE(error->relativeRmse, 0.01);
    EXPECT_NEAR(error->meanRatio, 1.0, 0.01);
}


/// picserver as a child on a free loopback port serving the fixture's bake on the CPU backend
/// (one bounce), with `extra` flags after those: its address, or "" with a test failure.
std::string startCliServer(Child& server, const std::vector<std::string>& extra = {}) {
    std::vector<std::string> args{PIC_PICSERVER, "--bake", bakePath(), "--scene", kScene,
                                  "--listen", "127.0.0.1:0", "--backend", "cpu", "--bounces",
                                  "1", "--quiet"};
    args.insert(args.end(), extra.begin(), extra.end());
    server = Child(args);
    EXPECT_GT(server.pid(), 0);
    if (server.pid() <= 0) return "";
    const std::string first = readLine(server.out());
    EXPECT_TRUE(first.starts_with("listening on 127.0.0.1:")) << first;
    if (!first.starts_with("listening on ")) return "";
    return first.substr(std::string("listening on ").size());
}

TEST(StreamCli, PicserverAndPicclientEndToEnd) {
    Child server;
    const std::string address = startCliServer(server);
    ASSERT_FALSE(address.empty());
    EXPECT_NE(address, "127.0.0.1:0");

    int exit = 0;
    const std::string client = PIC_PICCLIENT;
    std::string created = run(client + " session --server " + address, exit);
    ASSERT_EQ(exit, 0) << created;
    auto json = nlohmann::json::parse(created);
    const std::string session = json["session"], editor = json["editor_token"],
                      viewer = json["viewer_token"];

    const test::ScratchDir dir("pic_cli");
    const fs::path lightsFile = dir / "lights.json";
    {
        std::FILE* f = std::fopen(lightsFile.c_str(), "w");
        std::fputs(R"({"lights":[{"id":"lamp","type":"point","position":[0,0.6,0],"intensity":3}]})", f);
        std::fclose(f);
    }
    std::string version = run(client + " lights --server " + address + " --session " + session +
                                  " --token " + editor + " --set " + lightsFile.string(),
                              exit);
    EXPECT_EQ(exit, 0);
    EXPECT_EQ(version, "2\n");
    std::string denied = run(client + " lights --server " + address + " --session " + session +
                                 " --token " + viewer + " --set " + lightsFile.string() + " 2>&1",
                             exit);
    EXPECT_EQ(exit, 2);
    EXPECT_NE(denied.find("PERMISSION_DENIED"), std::string::npos) << denied;

    std::string watched = run(client + " watch --server " + address + " --session " + session +
                                  " --token " + viewer + " --count 1",
                              exit);
    EXPECT_EQ(exit, 0) << watched;
    EXPECT_NE(watched.find("version 2: key"), std::string::npos) << watched;

    const fs::path report = dir / "load.json";
    std::string loaded = run(client + " load --server " + address + " --clients 3 --duration 1 "
                                  "--update-rate 4 --report " + report.string(),
                             exit);
    EXPECT_EQ(exit, 0) << loaded;
    std::ifstream reportFile(report);
    auto loadReport = nlohmann::json::parse(reportFile);
    for (const char* key : {"p50", "p95", "p99", "max"})
        EXPECT_GT(loadReport["latency_ms"][key].get<double>(), 0.0) << key;
    EXPECT_EQ(loadReport["updates"].get<int>(), 4);
    EXPECT_GE(loadReport["frames_received"].get<int>(), 3);
    EXPECT_EQ(loadReport["errors"].get<int>(), 0);

    const fs::path image = dir / "render.exr";
    const fs::path cacheDir = dir / "cache";
    std::string rendered = run(client + " render --server " + address + " --session " + session +
                                   " --token " + editor + " --lights " + lightsFile.string() +
                                   " --scene-camera 0 --size 63x56 --component indirect --cache-dir " +
                                   cacheDir.string() + " --out " + image.string() + " 2>&1",
                               exit);
    EXPECT_EQ(exit, 0) << rendered;
    EXPECT_NE(rendered.find("light change to decoded frame"), std::string::npos) << rendered;
    EXPECT_NE(rendered.find("4 samples per pixel"), std::string::npos) << rendered;
    auto read = readImage(image.string());
    ASSERT_TRUE(read) << rendered;
    EXPECT_EQ(read->width, 63);
    // `picref shade` is the client's CPU counterpart: the same relight (one bounce, CPU), the
    // same 4 subsamples per pixel by default, shaded from the caches without the stream's
    // compression in between.
    const fs::path shaded = dir / "shaded.exr";
    std::string shade = run(std::string(PIC_PICREF) + " shade --quiet " + kScene + " --bake " +
                                bakePath() + " --backend cpu --bounces 1 --lights " +
                                lightsFile.string() +
                                " --scene-camera 0 --size 63x56 --component indirect --out " +
                                shaded.string() + " 2>&1",
                            exit);
    EXPECT_EQ(exit, 0) << shade;
    auto cpu = readImage(shaded.string());
    ASSERT_TRUE(cpu) << shade;
    auto error = compareImages(*read, *cpu);
    ASSERT_TRUE(error) << error.error().message;
    std::printf("picclient render against picref shade, 4 subsamples: relative RMSE %.5f, "
                "mean ratio %.5f\n",
                error->relativeRmse, error->meanRatio);
    EXPECT_LE(error->relativeRmse, 0.01);
    EXPECT_NEAR(error->meanRatio, 1.0, 0.01);
    // A dynamic object joins the view; an --object without its --transform is bad usage.
    const fs::path withBox = dir / "box.exr";
    const std::string box = std::string(PIC_TEST_SCENE_DIR) + "/object_box.gltf";
    std::string placed = run(client + " render --server " + address + " --session " + session +
                                 " --token " + editor + " --scene-camera 0 --size 63x56 " +
                                 "--component indirect --object " + box +
                                 " --transform 0.05,0.55,0.05,20,35,0,0.22 --cache-dir " +
                                 cacheDir.string() + " --out " + withBox.string() + " 2>&1",
                             exit);
    EXPECT_EQ(exit, 0) << placed;
    auto boxImage = readImage(withBox.string());
    ASSERT_TRUE(boxImage) << placed;
    EXPECT_NE(boxImage->pixels, read->pixels);
    std::string unpaired = run(client + " render --server " + address + " --session " + session +
                                   " --token " + editor + " --scene-camera 0 --size 8x8 --object " +
                                   box + " --cache-dir " + cacheDir.string() + " --out " +
                                   withBox.string() + " 2>&1",
                               exit);
    EXPECT_EQ(exit, 2) << unpaired;
    EXPECT_NE(unpaired.find("1 objects, 0 transforms"), std::string::npos) << unpaired;
    std::string viewerPush = run(client + " render --server " + address + " --session " + session +
                                     " --token " + viewer + " --lights " + lightsFile.string() +
                                     " --scene-camera 0 --size 8x8 --cache-dir " + cacheDir.string() +
                                     " --out " + image.string() + " 2>&1",
                                 exit);
    EXPECT_EQ(exit, 2) << viewerPush;
    // Without --lights a viewer renders the session's current frame: nothing changed, so no
    // light change's latency is claimed.
    std::string viewerRender =
        run(client + " render --server " + address + " --session " + session + " --token " +
                viewer + " --scene-camera 0 --size 8x8 --cache-dir " + cacheDir.string() +
                " --out " + image.string() + " 2>&1",
            exit);
    EXPECT_EQ(exit, 0) << viewerRender;
    EXPECT_NE(viewerRender.find("current frame received and decoded in"), std::string::npos)
        << viewerRender;
    EXPECT_EQ(viewerRender.find("light change"), std::string::npos) << viewerRender;

    std::string stats = run(client + " stats --server " + address + " --session " + session +
                                " --token " + viewer,
                            exit);
    EXPECT_EQ(exit, 0) << stats;
    auto statsJson = nlohmann::json::parse(stats);
    // Protobuf JSON prints 64-bit integers as strings.
    EXPECT_GE(std::stoull(statsJson["versions_computed"].get<std::string>()), 2u) << stats;
    EXPECT_TRUE(statsJson.contains("broadcast_bytes")) << stats;

    // The update log: one line per update after the first line.
    const std::string updateLine = readLine(server.out());
    EXPECT_TRUE(updateLine.starts_with("update session=")) << updateLine;
    EXPECT_NE(updateLine.find("encode_ms="), std::string::npos);
    EXPECT_NE(updateLine.find("bytes="), std::string::npos);
    EXPECT_NE(updateLine.find("subscribers="), std::string::npos);

    server.signal(SIGTERM);
    EXPECT_EQ(server.wait(), 0);
}

// `picclient record` draws the stream at a fixed rate from caches blended over time: after a
// light change every pixel moves monotonically from the old version's value to the new one's,
// some frames show the light part of the way, and the last frames show the new version.
TEST(StreamCli, RecordBlendsFromOneVersionToTheNext) {
    Child server;
    const std::string address = startCliServer(server);
    ASSERT_FALSE(address.empty());
    int exit = 0;
    const std::string client = PIC_PICCLIENT;
    const std::string created = run(client + " session --server " + address, exit);
    ASSERT_EQ(exit, 0) << created;
    const auto json = nlohmann::json::parse(created);
    const std::string session = json["session"], editor = json["editor_token"];

    const test::ScratchDir dir("pic_record");
    const fs::path frames = dir / "frames";
    Child recorder({client, "record", "--server", address, "--session", session, "--token", editor,
                    "--scene-camera", "0", "--size", "16x16", "--component", "indirect", "--fps",
                    "20", "--duration", "6", "--blend", "1.5", "--format", "exr", "--cache-dir",
                    (dir / "cache").string(), "--out-dir", frames.string()});
    ASSERT_GT(recorder.pid(), 0);
    // The first frame shows the session's first version; then the light brightens 4×.
    for (int i = 0; i < 3000 && !fs::exists(frames / "frame_00000.exr"); ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    ASSERT_TRUE(fs::exists(frames / "frame_00000.exr"));
    LightSet brighter = pointLight(0.0f);
    for (Light& light : brighter.lights) light.intensity *= 4.0f;
    const fs::path lightsFile = dir / "brighter.json";
    {
        std::ofstream out(lightsFile);
        out << toJson(brighter);
    }
    const std::string set = run(client + " lights --server " + address + " --session " + session +
                                    " --token " + editor + " --set " + lightsFile.string(),
                                exit);
    ASSERT_EQ(exit, 0) << set;
    ASSERT_EQ(recorder.wait(), 0);

    std::vector<Image> images;
    for (int k = 0;; ++k) {
        const fs::path path = frames / fmt::format("frame_{:05}.exr", k);
        if (!fs::exists(path)) break;
        auto image = readImage(path.string());
        ASSERT_TRUE(image) << image.error().message;
        images.push_back(std::move(*image));
    }
    ASSERT_GE(images.size(), 20u);
    const auto mean = [](const Image& image) {
        double sum = 0.0;
        for (const glm::vec3& p : image.pixels) sum += p.r + p.g + p.b;
        return sum / double(image.pixels.size());
    };
    const Image& before = images.front();
    const Image& after = images.back();
    ASSERT_GT(mean(after), 2.0 * mean(before));
    EXPECT_EQ(after.pixels, images[images.size() - 2].pixels);  // settled
    int between = 0;
    for (size_t k = 1; k < images.size(); ++k) {
        for (size_t i = 0; i < after.pixels.size(); ++i)
            for (int c = 0; c < 3; ++c) {
                const float lo = std::min(before.pixels[i][c], after.pixels[i][c]);
                const float hi = std::max(before.pixels[i][c], after.pixels[i][c]);
                const float slack = 1e-4f * (1.0f + hi);
                ASSERT_GE(images[k].pixels[i][c], lo - slack) << "frame " << k << " pixel " << i;
                ASSERT_LE(images[k].pixels[i][c], hi + slack) << "frame " << k << " pixel " << i;
                // Never back towards the old value.
                const float step = images[k].pixels[i][c] - images[k - 1].pixels[i][c];
                ASSERT_GE(step * (after.pixels[i][c] - before.pixels[i][c]), -slack * slack)
                    << "frame " << k << " pixel " << i;
            }
        const double m = mean(images[k]);
        between += m > 1.1 * mean(before) && m < 0.9 * mean(after);
    }
    EXPECT_GE(between, 3) << "frames part of the way from the old light to the new";
    server.signal(SIGTERM);
    EXPECT_EQ(server.wait(), 0);
}

TEST(StreamCli, TlsServerAndClient) {
    const std::string tls = PIC_TEST_TLS_DIR;
    Child server;
    const std::string address =
        startCliServer(server, {"--tls-cert", tls + "/server.crt", "--tls-key", tls + "/server.key"});
    ASSERT_FALSE(address.empty());
    int exit = 0;
    const std::string client = PIC_PICCLIENT;
    std::string created = run(client + " session --server " + address + " --tls-ca " + tls +
                                  "/server.crt 2>&1",
                              exit);
    EXPECT_EQ(exit, 0) << created;
    EXPECT_NE(created.find("\"editor_token\""), std::string::npos) << created;
    std::string plain = run(client + " session --server " + address + " --connect-timeout 1 2>&1", exit);
    EXPECT_EQ(exit, 1) << plain;
    EXPECT_NE(plain.find("--tls-ca"), std::string::npos) << plain;
    server.signal(SIGTERM);
    EXPECT_EQ(server.wait(), 0);

    std::string half = run(std::string(PIC_PICSERVER) + " --bake " + bakePath() + " --scene " +
                               kScene + " --tls-cert " + tls + "/server.crt 2>&1",
                           exit);
    EXPECT_EQ(exit, 2) << half;
}

TEST(StreamCli, BadInputsExitWithTwoAndAMessage) {
    int exit = 0;
    std::string output = run(std::string(PIC_PICSERVER) + " --bake /no/such.pic --scene " + kScene +
                                 " --listen 127.0.0.1:0 --backend cpu 2>&1",
                             exit);
    EXPECT_EQ(exit, 2);
    EXPECT_NE(output.find("/no/such.pic"), std::string::npos) << output;
    output = run(std::string(PIC_PICCLIENT) + " session --server 127.0.0.1:1 --connect-timeout 0.5 2>&1", exit);
    EXPECT_EQ(exit, 1);
    EXPECT_NE(output.find("cannot reach"), std::string::npos) << output;
}

}  // namespace
}  // namespace pic
