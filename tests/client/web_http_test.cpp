// The browsers' HTTP routes (server/web_server.h) with a plain socket on 127.0.0.1: the scene
// blob of server/web_scene.h decoded as a browser decodes it and compared with the G-buffer's
// arrays and the bake, light sets posted as JSON reaching the gRPC stream, the session's state
// and its presets (saved, listed, replaced, deleted, at most 32), the refusals' statuses and
// JSON, the embedded pic.proto, and pages from a web root, none from outside it.
// Every server a test starts is stopped by it.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include <zstd.h>
#include <nlohmann/json.hpp>

#include "core/bake_file.h"
#include "core/gltf_loader.h"
#include "core/sh.h"
#include "render/gbuffer_geometry.h"
#include "render/renderer.h"
#include "server/web_scene.h"
#include "tests/client/stream_fixture.h"
#include "tests/support/baked_scene.h"
#include "tests/support/command.h"

namespace pic {
namespace {

using namespace std::chrono_literals;
using namespace test;
using Json = nlohmann::json;

/// The calls of `call` that ended with gRPC code `code`, as the server's metrics text counts them.
double callsCounted(const std::string& metrics, const std::string& call, const std::string& code) {
    return metricValue(metrics, "pic_calls_total{call=\"" + call + "\",code=\"" + code + "\"}");
}

/// A decompressed scene blob: its JSON and its binary area (from B on).
struct WebBlob {
    Json json;
    std::string binary;
};

/// Decodes the blob as server/web_scene.h says, failing the test where it does not hold.
WebBlob decodeWebScene(const std::string& compressed) {
    WebBlob blob;
    const unsigned long long size = ZSTD_getFrameContentSize(compressed.data(), compressed.size());
    EXPECT_NE(size, ZSTD_CONTENTSIZE_UNKNOWN) << "the frame carries its content size";
    EXPECT_NE(size, ZSTD_CONTENTSIZE_ERROR) << "one zstd frame";
    if (size == ZSTD_CONTENTSIZE_UNKNOWN || size == ZSTD_CONTENTSIZE_ERROR) return blob;
    std::string raw(size, '\0');
    const size_t n = ZSTD_decompress(raw.data(), raw.size(), compressed.data(), compressed.size());
    EXPECT_FALSE(ZSTD_isError(n)) << ZSTD_getErrorName(n);
    EXPECT_EQ(n, size);
    EXPECT_GE(raw.size(), 12u);
    if (ZSTD_isError(n) || raw.size() < 12) return blob;
    EXPECT_EQ(raw.substr(0, 8), std::string("PICWEB1\0", 8));
    uint32_t length = 0;
    std::memcpy(&length, raw.data() + 8, 4);
    EXPECT_LE(12 + size_t(length), raw.size());
    if (12 + size_t(length) > raw.size()) return blob;
    blob.json = Json::parse(raw.substr(12, length), nullptr, false);
    EXPECT_FALSE(blob.json.is_discarded()) << "the JSON parses";
    const size_t binaryStart = (12 + size_t(length) + 15) / 16 * 16;
    EXPECT_LE(binaryStart, raw.size());
    if (binaryStart > raw.size()) return blob;
    EXPECT_EQ(raw.substr(12 + length, binaryStart - 12 - length),
              std::string(binaryStart - 12 - length, '\0'))
        << "zero padding up to B";
    blob.binary = raw.substr(binaryStart);
    return blob;
}

/// Section `name` of the blob: its entry and bytes, checked to be aligned, in the binary area
/// and count × stride long.
std::string sectionOf(const WebBlob& blob, const std::string& name, size_t stride,
                      Json* entry = nullptr) {
    for (const Json& section : blob.json.at("sections")) {
        if (section.at("name") != name) continue;
        if (entry) *entry = section;
        const size_t offset = section.at("offset"), bytes = section.at("bytes");
        EXPECT_EQ(offset % 16, 0u) << name;
        EXPECT_EQ(section.at("stride").get<size_t>(), stride) << name;
        EXPECT_EQ(bytes, section.at("count").get<size_t>() * stride) << name;
        EXPECT_LE(offset + bytes, blob.binary.size()) << name;
        if (offset + bytes > blob.binary.size()) return {};
        return blob.binary.substr(offset, bytes);
    }
    ADD_FAILURE() << "no section " << name;
    return {};
}

template <class T>
std::string bytesOf(const std::vector<T>& values) {
    return std::string(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
}

/// The blob's sections hold exactly the G-buffer's arrays of `scene` and the bake's cache
/// maps, in the documented order, and the JSON describes both.
void expectBlobOf(const WebBlob& blob, const Scene& scene, const BakeData& bake) {
    const Json& json = blob.json;
    ASSERT_TRUE(json.is_object());
    EXPECT_EQ(json.at("format"), 1);
    EXPECT_EQ(json.at("scene_name"), std::filesystem::path(scene.sourcePath).filename().string());
    EXPECT_EQ(json.at("scene_hash"), fmt::format("{:016x}", scene.hash));
    EXPECT_EQ(json.at("bands_y"), bake.params.bandsY);
    EXPECT_EQ(json.at("bands_c"), bake.params.bandsC);
    EXPECT_EQ(json.at("caches"), bake.caches.size());
    EXPECT_EQ(json.at("triangles"), scene.triangles.size());
    EXPECT_EQ(json.at("grid").at("dims"),
              Json({bake.grid.dims.x, bake.grid.dims.y, bake.grid.dims.z}));
    EXPECT_EQ(json.at("grid").at("cell_size").get<float>(), bake.grid.cellSize);
    EXPECT_EQ(json.at("grid").at("origin").at(1).get<float>(), bake.grid.origin.y);
    EXPECT_EQ(json.at("lightmap").at("width"), bake.lightmap.width);
    EXPECT_EQ(json.at("lightmap").at("height"), bake.lightmap.height);
    EXPECT_EQ(json.at("bounds").at("max").at(0).get<float>(), scene.bounds.max.x);
    EXPECT_EQ(json.at("epsilon").get<float>(), rendererEpsilonOf(scene));
    EXPECT_EQ(json.at("near").get<float>(), rendererEpsilonOf(scene));
    EXPECT_EQ(json.at("no_cache"), kNoCache);
    // K_0 = π and K_1 = 2π/3 of the clamped cosine; odd bands above 1 vanish.
    const auto& clampedCosine = json.at("sh").at("clamped_cosine");
    ASSERT_EQ(clampedCosine.size(), size_t(kMaxShBands));
    EXPECT_NEAR(clampedCosine[0].get<float>(), 3.14159265f, 1e-6f);
    EXPECT_NEAR(clampedCosine[1].get<float>(), 2.0943951f, 1e-6f);
    EXPECT_NEAR(clampedCosine[3].get<float>(), 0.0f, 1e-6f);
    ASSERT_EQ(json.at("materials").size(), scene.materials.size());
    for (size_t m = 0; m < scene.materials.size(); ++m)
        EXPECT_EQ(json.at("materials").at(m).at("name"), scene.materials[m].name);
    ASSERT_EQ(json.at("cameras").size(), scene.cameras.size());
    for (size_t c = 0; c < scene.cameras.size(); ++c) {
        const Json& camera = json.at("cameras").at(c);
        EXPECT_EQ(camera.at("name"), scene.cameras[c].name);
        EXPECT_EQ(camera.at("eye").at(2).get<float>(), scene.cameras[c].eye.z);
        EXPECT_EQ(camera.at("fovy_degrees").get<float>(), scene.cameras[c].fovyDegrees);
    }
    std::vector<std::string> names;
    for (const Json& section : json.at("sections")) names.push_back(section.at("name"));
    EXPECT_EQ(names,
              (std::vector<std::string>{"vertices", "triangles", "materials", "textures", "levels",
                                        "texels", "grid_caches", "lightmap_caches"}));

    auto geometry = gbufferGeometryOf(scene, bake.lightmap.triangleUvs);
    ASSERT_TRUE(geometry) << geometry.error().message;
    Json vertices;
    EXPECT_TRUE(sectionOf(blob, "vertices", 64, &vertices) == bytesOf(geometry->vertices));
    EXPECT_EQ(vertices.at("count"), 3 * scene.triangles.size());
    EXPECT_TRUE(sectionOf(blob, "triangles", 48) == bytesOf(geometry->triangles));
    EXPECT_TRUE(sectionOf(blob, "materials", 48) == bytesOf(geometry->materials));
    EXPECT_TRUE(sectionOf(blob, "textures", 16) == bytesOf(geometry->textures));
    EXPECT_TRUE(sectionOf(blob, "levels", 16) == bytesOf(geometry->levels));
    const std::string texels = sectionOf(blob, "texels", 16);
    EXPECT_TRUE(texels == bytesOf(geometry->texels));
    if (!scene.textures.empty()) {
        // Texture 0's level 0 comes first.
        const std::string level0 = bytesOf(scene.textures[0].texels);
        EXPECT_TRUE(texels.substr(0, level0.size()) == level0);
    }
    Json grid, lightmap;
    EXPECT_TRUE(sectionOf(blob, "grid_caches", 4, &grid) == bytesOf(bake.grid.cacheIndex));
    EXPECT_EQ(grid.at("count"), size_t(bake.grid.dims.x) * bake.grid.dims.y * bake.grid.dims.z);
    EXPECT_TRUE(sectionOf(blob, "lightmap_caches", 4, &lightmap) ==
                bytesOf(bake.lightmap.cacheIndex));
    EXPECT_EQ(lightmap.at("count"), size_t(bake.lightmap.width) * bake.lightmap.height);
    // Nothing after the last section.
    const Json& last = json.at("sections").back();
    EXPECT_EQ(blob.binary.size(), last.at("offset").get<size_t>() + last.at("bytes").get<size_t>());
}

TEST(WebScene, HoldsTheGbufferArraysWithTexturesAndTheCacheMaps) {
    const BakedScene& baked = bakedScene("textured_quad", smallBakeOptions(256, 16));
    ASSERT_TRUE(baked.ok);
    ASSERT_FALSE(baked.scene.textures.empty());
    auto compressed = webSceneOf(baked.scene, baked.bake, "0123456789abcdef");
    ASSERT_TRUE(compressed) << compressed.error().message;
    const WebBlob blob = decodeWebScene(*compressed);
    EXPECT_EQ(blob.json.value("bake_id", ""), "0123456789abcdef");
    expectBlobOf(blob, baked.scene, baked.bake);
}

TEST(WebScene, RefusesLightMapUvsThatAreNotThreePerTriangle) {
    const BakedScene& baked = bakedScene("textured_quad", smallBakeOptions(256, 16));
    ASSERT_TRUE(baked.ok);
    BakeData bake = baked.bake;
    bake.lightmap.triangleUvs.pop_back();
    auto compressed = webSceneOf(baked.scene, bake, "0123456789abcdef");
    ASSERT_FALSE(compressed);
    EXPECT_EQ(compressed.error().code, ErrorCode::InvalidInput);
    EXPECT_NE(compressed.error().message.find(std::to_string(3 * baked.scene.triangles.size() - 1)),
              std::string::npos)
        << compressed.error().message;
}

ServerOptions withWeb() {
    ServerOptions options;
    options.session.setLightsPerSecond = 1e6;
    options.webListen = "127.0.0.1:0";
    options.metricsListen = "127.0.0.1:0";
    return options;
}

std::string sessionQuery(const std::string& session, const std::string& token) {
    return "?session=" + session + "&token=" + token;
}

/// The JSON body of a refusal: its "code", and its "error" containing `says`.
void expectRefusal(const HttpReply& reply, int status, const std::string& code,
                   const std::string& says) {
    EXPECT_EQ(reply.code(), status) << reply.status << " " << reply.body;
    EXPECT_EQ(reply.header("Content-Type"), "application/json");
    const Json body = Json::parse(reply.body, nullptr, false);
    ASSERT_TRUE(body.is_object()) << reply.body;
    EXPECT_EQ(body.value("code", ""), code) << reply.body;
    EXPECT_NE(body.value("error", "").find(says), std::string::npos) << reply.body;
}

TEST(WebHttp, TheSceneIsTheSessionsBakeForAnyOfItsTokens) {
    Served served = serveWith(withWeb());
    ASSERT_TRUE(served.connection);
    auto session = served.connection->createSession();
    ASSERT_TRUE(session);
    const std::string address = served.server->webAddress();

    const HttpReply reply =
        httpGet(address, "/v1/scene" + sessionQuery(session->session(), session->viewer_token()));
    ASSERT_EQ(reply.code(), 200) << reply.status << " " << reply.body;
    EXPECT_EQ(reply.header("Content-Type"), "application/octet-stream");
    EXPECT_EQ(reply.header("Cache-Control"), "private, max-age=3600");
    EXPECT_EQ(reply.header("ETag"), "\"" + session->bake_id() + "\"");
    std::printf("the Cornell box's scene blob takes %zu bytes\n", reply.body.size());
    const WebBlob blob = decodeWebScene(reply.body);
    EXPECT_EQ(blob.json.value("bake_id", ""), session->bake_id());
    auto scene = loadScene(kScene);
    ASSERT_TRUE(scene) << scene.error().message;
    auto bake = readBakeFile(bakePath());
    ASSERT_TRUE(bake) << bake.error().message;
    expectBlobOf(blob, *scene, *bake);

    // The editor's token gets the same bytes; a browser holding them is told so (304).
    const std::string editorPath =
        "/v1/scene" + sessionQuery(session->session(), session->editor_token());
    EXPECT_TRUE(httpGet(address, editorPath).body == reply.body);
    const HttpReply held =
        httpRequest(address, "GET", editorPath, "", {"If-None-Match: " + reply.header("ETag")});
    EXPECT_EQ(held.code(), 304) << held.status;
    EXPECT_TRUE(held.body.empty());

    const HttpReply metrics = httpGet(served.server->metricsAddress(), "/metrics");
    EXPECT_EQ(callsCounted(metrics.body, "WebScene", "OK"), 3.0) << metrics.body;
}

TEST(WebHttp, SessionRoutesRefuseWithTheStatusAndJson) {
    Served served = serveWith(withWeb());
    ASSERT_TRUE(served.connection);
    auto session = served.connection->createSession();
    ASSERT_TRUE(session);
    const std::string address = served.server->webAddress();

    expectRefusal(httpGet(address, "/v1/scene" + sessionQuery(session->session(), "not-a-token")),
                  401, "UNAUTHENTICATED", "not one of session");
    expectRefusal(
        httpGet(address, "/v1/scene" + sessionQuery("0123456789abcdef", session->viewer_token())),
        404, "NOT_FOUND", "0123456789abcdef");
    expectRefusal(httpGet(address, "/v1/scene?token=" + session->viewer_token()), 400,
                  "INVALID_ARGUMENT", "session=");
    expectRefusal(httpGet(address, "/v1/scene?session=" + session->session()), 400,
                  "INVALID_ARGUMENT", "token=");
    expectRefusal(httpRequest(address, "POST", "/v1/lights?session=" + session->session(), "{}"),
                  400, "INVALID_ARGUMENT", "token=");
    const HttpReply wrong = httpRequest(
        address, "POST", "/v1/scene" + sessionQuery(session->session(), session->viewer_token()));
    EXPECT_EQ(wrong.code(), 405) << wrong.status;
    EXPECT_EQ(wrong.header("Allow"), "GET");

    const HttpReply metrics = httpGet(served.server->metricsAddress(), "/metrics");
    EXPECT_EQ(callsCounted(metrics.body, "WebScene", "UNAUTHENTICATED"), 1.0) << metrics.body;
    EXPECT_EQ(callsCounted(metrics.body, "WebScene", "NOT_FOUND"), 1.0) << metrics.body;
}

TEST(WebHttp, AnEditorsLightSetReachesTheStreamAsItsVersion) {
    Served served = serveWith(withWeb());
    ASSERT_TRUE(served.connection);
    auto session = served.connection->createSession();
    ASSERT_TRUE(session);
    const std::string address = served.server->webAddress();
    Reader reader(*served.connection, session->session(), session->viewer_token());
    ASSERT_TRUE(reader.waitFor(1));

    const LightSet lights = pointLight(0.15f);
    const HttpReply reply = httpRequest(
        address, "POST", "/v1/lights" + sessionQuery(session->session(), session->editor_token()),
        toJson(lights), {"Content-Type: application/json"});
    ASSERT_EQ(reply.code(), 200) << reply.status << " " << reply.body;
    EXPECT_EQ(reply.header("Content-Type"), "application/json");
    const Json body = Json::parse(reply.body, nullptr, false);
    ASSERT_TRUE(body.is_object() && body.contains("version")) << reply.body;
    const uint64_t version = body.at("version");
    EXPECT_GT(version, 1u);
    ASSERT_TRUE(reader.waitFor(version));
    ASSERT_TRUE(reader.lights());
    EXPECT_EQ(reader.lights()->lights, lights.lights);
    EXPECT_EQ(served.server->session(session->session())->latestVersion(), version);

    // A viewer may not; a set that does not parse or does not fit the scene says why.
    const std::string editorPath =
        "/v1/lights" + sessionQuery(session->session(), session->editor_token());
    expectRefusal(
        httpRequest(address, "POST",
                    "/v1/lights" + sessionQuery(session->session(), session->viewer_token()),
                    toJson(lights)),
        403, "PERMISSION_DENIED", "editor");
    expectRefusal(
        httpRequest(address, "POST", editorPath, R"({"lights":[{"id":"a","type":"laser"}]})"), 400,
        "INVALID_ARGUMENT", "laser");
    expectRefusal(httpRequest(address, "POST", editorPath, R"({"lights": [)"), 400,
                  "INVALID_ARGUMENT", "");
    expectRefusal(httpRequest(address, "POST", editorPath,
                              R"({"lights":[],"emissiveScale":{"no such material":2}})"),
                  400, "INVALID_ARGUMENT", "no such material");
    // A body larger than a gRPC request may be.
    expectRefusal(httpRequest(address, "POST", editorPath, std::string((1 << 20) + 1, ' ')), 413,
                  "RESOURCE_EXHAUSTED", "at most");
    EXPECT_EQ(served.server->session(session->session())->latestVersion(), version)
        << "no refused set was applied";

    const HttpReply metrics = httpGet(served.server->metricsAddress(), "/metrics");
    EXPECT_EQ(callsCounted(metrics.body, "WebSetLights", "OK"), 1.0) << metrics.body;
    EXPECT_EQ(callsCounted(metrics.body, "WebSetLights", "PERMISSION_DENIED"), 1.0) << metrics.body;
}

TEST(WebHttp, TheRateLimitAnswers429WithRetryAfter) {
    ServerOptions options = withWeb();
    options.session.setLightsPerSecond = 1.0;
    Served served = serveWith(options);
    ASSERT_TRUE(served.connection);
    auto session = served.connection->createSession();
    ASSERT_TRUE(session);
    const std::string path =
        "/v1/lights" + sessionQuery(session->session(), session->editor_token());
    const std::string address = served.server->webAddress();
    const HttpReply first = httpRequest(address, "POST", path, toJson(pointLight(0.1f)));
    EXPECT_EQ(first.code(), 200) << first.status << " " << first.body;
    const HttpReply second = httpRequest(address, "POST", path, toJson(pointLight(0.2f)));
    expectRefusal(second, 429, "RESOURCE_EXHAUSTED", "at most 1 light sets a second");
    EXPECT_EQ(second.header("Retry-After"), "1") << "≤ 1000 ms rounded up to whole seconds";

    // Preset changes are writes too: within the same second, saving and deleting one are
    // refused alike, and nothing is saved.
    const std::string presets =
        "/v1/presets" + sessionQuery(session->session(), session->editor_token());
    const HttpReply save =
        httpRequest(address, "PUT", presets + "&name=day", toJson(pointLight(0.3f)));
    expectRefusal(save, 429, "RESOURCE_EXHAUSTED", "preset changes count as light sets");
    EXPECT_EQ(save.header("Retry-After"), "1");
    const HttpReply remove = httpRequest(address, "DELETE", presets + "&name=day", "");
    expectRefusal(remove, 429, "RESOURCE_EXHAUSTED", "at most 1 light sets a second");
    EXPECT_TRUE(served.server->session(session->session())->presets().empty());
}

/// The JSON body of a 200 reply not to be cached, failing the test where it is not one.
Json jsonOf(const HttpReply& reply) {
    EXPECT_EQ(reply.code(), 200) << reply.status << " " << reply.body;
    EXPECT_EQ(reply.header("Content-Type"), "application/json");
    EXPECT_EQ(reply.header("Cache-Control"), "no-store");
    const Json body = Json::parse(reply.body, nullptr, false);
    EXPECT_TRUE(body.is_object()) << reply.body;
    return body.is_object() ? body : Json::object();
}

/// A light set as the routes give it (a JSON object) in its toJson form, or the error.
std::string lightsOf(const Json& json) {
    auto parsed = parseLightSet(json.dump());
    return parsed ? toJson(*parsed) : "error: " + parsed.error().message;
}

/// The names of a {"presets": [...]} answer: its strings, or its objects' "name"s.
std::vector<std::string> presetNames(const Json& body) {
    std::vector<std::string> names;
    for (const Json& entry : body.value("presets", Json::array()))
        names.push_back(entry.is_string() ? entry.get<std::string>() : entry.value("name", ""));
    return names;
}

TEST(WebHttp, TheSessionSaysTheRoleTheNewestSetAndThePresets) {
    Served served = serveWith(withWeb());
    ASSERT_TRUE(served.connection);
    auto session = served.connection->createSession();
    ASSERT_TRUE(session);
    const std::string id = session->session();
    const std::string address = served.server->webAddress();

    const Json first =
        jsonOf(httpGet(address, "/v1/session" + sessionQuery(id, session->editor_token())));
    EXPECT_EQ(first.value("session", ""), id);
    EXPECT_EQ(first.value("role", ""), "editor");
    EXPECT_EQ(first.value("bake_id", ""), session->bake_id());
    EXPECT_EQ(first.value("version", 0u), 1u);
    auto joined = served.connection->joinSession(id, session->viewer_token());
    ASSERT_TRUE(joined) << joined.error().message;
    auto sceneLights = wire::fromProto(joined->lights());
    ASSERT_TRUE(sceneLights) << sceneLights.error().message;
    EXPECT_EQ(lightsOf(first.value("lights", Json())), toJson(*sceneLights))
        << "the scene's own lights, as JoinSession gives them";
    EXPECT_EQ(first.value("presets", Json()), Json::array());

    // After a light set and a preset, a viewer sees both.
    const LightSet posted = pointLight(0.15f);
    const Json set = jsonOf(httpRequest(
        address, "POST", "/v1/lights" + sessionQuery(id, session->editor_token()), toJson(posted)));
    const uint64_t version = set.value("version", 0u);
    EXPECT_GT(version, 1u);
    const LightSet saved = pointLight(-0.2f);
    jsonOf(
        httpRequest(address, "PUT",
                    "/v1/presets" + sessionQuery(id, session->editor_token()) + "&name=Left%20lamp",
                    toJson(saved)));
    const Json seen =
        jsonOf(httpGet(address, "/v1/session" + sessionQuery(id, session->viewer_token())));
    EXPECT_EQ(seen.value("role", ""), "viewer");
    EXPECT_EQ(seen.value("version", 0u), version) << "a preset takes no version";
    EXPECT_EQ(lightsOf(seen.value("lights", Json())), toJson(posted));
    ASSERT_EQ(presetNames(seen), std::vector<std::string>{"Left lamp"}) << seen.dump();
    EXPECT_EQ(lightsOf(seen.at("presets").at(0).value("lights", Json())), toJson(saved));

    expectRefusal(httpGet(address, "/v1/session" + sessionQuery(id, "not-a-token")), 401,
                  "UNAUTHENTICATED", "not one of session");
    expectRefusal(
        httpGet(address, "/v1/session" + sessionQuery("0123456789abcdef", session->viewer_token())),
        404, "NOT_FOUND", "0123456789abcdef");
    expectRefusal(httpGet(address, "/v1/session?session=" + id), 400, "INVALID_ARGUMENT", "token=");
    expectRefusal(httpGet(address, "/v1/session?token=" + session->viewer_token()), 400,
                  "INVALID_ARGUMENT", "session=");

    const HttpReply metrics = httpGet(served.server->metricsAddress(), "/metrics");
    EXPECT_EQ(callsCounted(metrics.body, "WebSession", "OK"), 2.0) << metrics.body;
    EXPECT_EQ(callsCounted(metrics.body, "WebSession", "UNAUTHENTICATED"), 1.0) << metrics.body;
}

TEST(WebHttp, AnEditorSavesListsReplacesAndDeletesPresets) {
    Served served = serveWith(withWeb());
    ASSERT_TRUE(served.connection);
    auto session = served.connection->createSession();
    ASSERT_TRUE(session);
    const std::string id = session->session();
    const std::string address = served.server->webAddress();
    const std::string editor = "/v1/presets" + sessionQuery(id, session->editor_token());
    const std::string viewer = "/v1/presets" + sessionQuery(id, session->viewer_token());

    EXPECT_EQ(jsonOf(httpGet(address, viewer)), Json({{"presets", Json::array()}}));
    const Json saved =
        jsonOf(httpRequest(address, "PUT", editor + "&name=warm-1.b", toJson(pointLight(0.2f))));
    EXPECT_EQ(presetNames(saved), std::vector<std::string>{"warm-1.b"});
    const Json both = jsonOf(
        httpRequest(address, "PUT", editor + "&name=Cool%20corner_2", toJson(pointLight(-0.3f))));
    EXPECT_EQ(presetNames(both), (std::vector<std::string>{"Cool corner_2", "warm-1.b"}))
        << "in name order";

    // Either token lists them with their light sets.
    Json listed = jsonOf(httpGet(address, viewer));
    ASSERT_EQ(presetNames(listed), (std::vector<std::string>{"Cool corner_2", "warm-1.b"}));
    EXPECT_EQ(lightsOf(listed.at("presets").at(0).at("lights")), toJson(pointLight(-0.3f)));
    EXPECT_EQ(lightsOf(listed.at("presets").at(1).at("lights")), toJson(pointLight(0.2f)));

    // A PUT of a name that exists replaces its set.
    jsonOf(httpRequest(address, "PUT", editor + "&name=warm-1.b", toJson(pointLight(0.4f))));
    listed = jsonOf(httpGet(address, editor));
    ASSERT_EQ(presetNames(listed), (std::vector<std::string>{"Cool corner_2", "warm-1.b"}));
    EXPECT_EQ(lightsOf(listed.at("presets").at(1).at("lights")), toJson(pointLight(0.4f)));
    EXPECT_EQ(served.server->session(id)->latestVersion(), 1u) << "presets take no version";

    // Refusals, none of which changes the presets.
    expectRefusal(httpRequest(address, "PUT", viewer + "&name=mine", toJson(pointLight(0.1f))), 403,
                  "PERMISSION_DENIED", "editor");
    expectRefusal(httpRequest(address, "DELETE", viewer + "&name=warm-1.b"), 403,
                  "PERMISSION_DENIED", "editor");
    for (const auto& [query, shown] :
         {std::pair{std::string("%20lead"), std::string(" lead")},
          std::pair{std::string("trail%20"), std::string("trail ")},
          std::pair{std::string("a%2Fb"), std::string("a/b")},
          std::pair{std::string("caf%C3%A9"), std::string("caf\xC3\xA9")},
          std::pair{std::string(65, 'x'), std::string(64, 'x')}}) {
        SCOPED_TRACE(shown);
        expectRefusal(
            httpRequest(address, "PUT", editor + "&name=" + query, toJson(pointLight(0.1f))), 400,
            "INVALID_ARGUMENT", "preset name \"" + shown);
    }
    jsonOf(httpRequest(address, "PUT", editor + "&name=" + std::string(64, 'x'),
                       toJson(pointLight(0.1f))));
    jsonOf(httpRequest(address, "DELETE", editor + "&name=" + std::string(64, 'x')));
    expectRefusal(httpRequest(address, "PUT", editor, toJson(pointLight(0.1f))), 400,
                  "INVALID_ARGUMENT", "name=");
    expectRefusal(httpRequest(address, "DELETE", editor), 400, "INVALID_ARGUMENT", "name=");
    expectRefusal(httpRequest(address, "PUT", editor + "&name=odd",
                              R"({"lights":[],"emissiveScale":{"no such material":2}})"),
                  400, "INVALID_ARGUMENT", "no such material");
    expectRefusal(httpRequest(address, "PUT", editor + "&name=odd",
                              R"({"lights":[{"id":"a","type":"laser"}]})"),
                  400, "INVALID_ARGUMENT", "laser");
    expectRefusal(
        httpRequest(address, "PUT", editor + "&name=odd", std::string((1 << 20) + 1, ' ')), 413,
        "RESOURCE_EXHAUSTED", "at most");
    const HttpReply wrong = httpRequest(address, "POST", editor + "&name=odd", "{}");
    EXPECT_EQ(wrong.code(), 405) << wrong.status;
    EXPECT_EQ(wrong.header("Allow"), "GET, PUT, DELETE");
    EXPECT_EQ(presetNames(jsonOf(httpGet(address, viewer))),
              (std::vector<std::string>{"Cool corner_2", "warm-1.b"}));

    // A DELETE removes it; a second finds none.
    EXPECT_EQ(presetNames(jsonOf(httpRequest(address, "DELETE", editor + "&name=warm-1.b"))),
              std::vector<std::string>{"Cool corner_2"});
    EXPECT_EQ(presetNames(jsonOf(httpGet(address, viewer))),
              std::vector<std::string>{"Cool corner_2"});
    expectRefusal(httpRequest(address, "DELETE", editor + "&name=warm-1.b"), 404, "NOT_FOUND",
                  "no preset \"warm-1.b\"");

    const HttpReply metrics = httpGet(served.server->metricsAddress(), "/metrics");
    EXPECT_EQ(callsCounted(metrics.body, "WebPresets", "PERMISSION_DENIED"), 2.0) << metrics.body;
    EXPECT_EQ(callsCounted(metrics.body, "WebPresets", "NOT_FOUND"), 1.0) << metrics.body;
}

TEST(WebHttp, ASessionHoldsAtMost32Presets) {
    Served served = serveWith(withWeb());
    ASSERT_TRUE(served.connection);
    auto session = served.connection->createSession();
    ASSERT_TRUE(session);
    const std::string address = served.server->webAddress();
    const std::string editor =
        "/v1/presets" + sessionQuery(session->session(), session->editor_token());
    for (int i = 0; i < 32; ++i)
        ASSERT_EQ(httpRequest(address, "PUT", editor + fmt::format("&name=p{:02}", i),
                              toJson(pointLight(0.01f * float(i))))
                      .code(),
                  200)
            << i;
    expectRefusal(httpRequest(address, "PUT", editor + "&name=p32", toJson(pointLight(0.5f))), 429,
                  "RESOURCE_EXHAUSTED", "32 presets");
    // One of the 32 may still be replaced; once one is deleted, a new one fits.
    EXPECT_EQ(httpRequest(address, "PUT", editor + "&name=p07", toJson(pointLight(0.5f))).code(),
              200);
    EXPECT_EQ(httpRequest(address, "DELETE", editor + "&name=p00").code(), 200);
    const Json saved =
        jsonOf(httpRequest(address, "PUT", editor + "&name=p32", toJson(pointLight(0.5f))));
    EXPECT_EQ(presetNames(saved).size(), 32u);
    EXPECT_EQ(presetNames(saved).back(), "p32");
}

TEST(WebHttp, ServesTheProtoAndTheShBasisWithoutAToken) {
    Served served = serveWith(withWeb());
    ASSERT_TRUE(served.connection);
    const HttpReply reply = httpGet(served.server->webAddress(), "/v1/pic.proto");
    ASSERT_EQ(reply.code(), 200) << reply.status;
    EXPECT_EQ(reply.header("Content-Type"), "text/plain; charset=utf-8");
    EXPECT_NE(reply.body.find("message Frame"), std::string::npos);
    EXPECT_EQ(reply.body, readFile(PIC_SOURCE_DIR "/proto/pic.proto"));
    // The browser's shading includes the Vulkan shaders' generated basis.
    const HttpReply basis = httpGet(served.server->webAddress(), "/v1/sh_basis.glsl");
    ASSERT_EQ(basis.code(), 200) << basis.status;
    EXPECT_EQ(basis.body, readFile(PIC_BINARY_DIR "/shaders/glsl/sh_basis.glsl"));
}

void writeFile(const std::filesystem::path& path, const std::string& text) {
    std::filesystem::create_directories(path.parent_path());
    std::ofstream(path, std::ios::binary) << text;
}

TEST(WebHttp, ServesTheWebRootsFilesAndNothingOutsideIt) {
    ScratchDir scratch("web_root");
    const std::filesystem::path root = scratch / "web";
    writeFile(root / "index.html", "<!doctype html><title>pic</title>");
    writeFile(root / "js" / "app.js", "export const answer = 42;\n");
    writeFile(root / "node_modules" / "lib" / "lib.mjs", "export default 1;\n");
    writeFile(root / "style.css", "body {}\n");
    writeFile(scratch / "secret.txt", "the secret\n");
    std::filesystem::create_symlink(scratch / "secret.txt", root / "escape.js");
    std::filesystem::create_directory_symlink(scratch.path(), root / "up");
    std::filesystem::create_symlink(root / "js" / "app.js", root / "alias.js");

    ServerOptions options = withWeb();
    options.webRoot = root.string();
    Served served = serveWith(options);
    ASSERT_TRUE(served.connection);
    const std::string address = served.server->webAddress();

    const HttpReply index = httpGet(address, "/");
    ASSERT_EQ(index.code(), 200) << index.status;
    EXPECT_EQ(index.header("Content-Type"), "text/html; charset=utf-8");
    EXPECT_EQ(index.header("Cache-Control"), "no-cache");
    EXPECT_EQ(index.body, "<!doctype html><title>pic</title>");
    EXPECT_EQ(httpGet(address, "/index.html").body, index.body);
    const HttpReply script = httpGet(address, "/js/app.js");
    ASSERT_EQ(script.code(), 200) << script.status;
    EXPECT_EQ(script.header("Content-Type"), "text/javascript; charset=utf-8");
    EXPECT_EQ(script.body, "export const answer = 42;\n");
    const HttpReply library = httpGet(address, "/node_modules/lib/lib.mjs");
    EXPECT_EQ(library.code(), 200) << library.status;
    EXPECT_EQ(library.header("Content-Type"), "text/javascript; charset=utf-8");
    EXPECT_EQ(httpGet(address, "/style.css").header("Content-Type"), "text/css; charset=utf-8");
    EXPECT_EQ(httpGet(address, "/alias.js").body, script.body) << "a link inside the root";

    for (const std::string path :
         {"/missing.js", "/js/", "/js", "/../secret.txt", "/%2e%2e/secret.txt",
          "/js/%2e%2e/%2e%2e/secret.txt", "/js/..%2f..%2fsecret.txt", "/../../../../etc/passwd",
          "/%2e%2e/%2e%2e/%2e%2e/%2e%2e/etc/passwd", "/escape.js", "/up/secret.txt"}) {
        const HttpReply reply = httpGet(address, path);
        EXPECT_EQ(reply.code(), 404) << path << ": " << reply.status;
        EXPECT_EQ(reply.body.find("secret"), std::string::npos) << path;
        EXPECT_EQ(reply.body.find("root:"), std::string::npos) << path;
    }

    // The stream's WebSocket path is not a page.
    EXPECT_NE(httpGet(address, "/v1/stream").code(), 200);
}

TEST(WebHttp, WithoutItsWebRootTheServerStillServesTheApi) {
    ScratchDir scratch("web_root");
    ServerOptions options = withWeb();
    options.webRoot = (scratch / "none").string();
    Served served = serveWith(options);
    ASSERT_TRUE(served.connection);
    const std::string address = served.server->webAddress();
    EXPECT_EQ(httpGet(address, "/").code(), 404);
    EXPECT_EQ(httpGet(address, "/index.html").code(), 404);
    EXPECT_EQ(httpGet(address, "/v1/pic.proto").code(), 200);
    auto session = served.connection->createSession();
    ASSERT_TRUE(session);
    EXPECT_EQ(
        httpGet(address, "/v1/scene" + sessionQuery(session->session(), session->viewer_token()))
            .code(),
        200);
}

}  // namespace
}  // namespace pic
