#include "client/picclient_cli.h"

#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>
#include <google/protobuf/util/json_util.h>
#include <nlohmann/json.hpp>

#include "client/connection.h"
#include "client/load_test.h"
#include "core/cache_blend.h"
#include "core/cli.h"
#include "proto/wire.h"
#include "render/renderer.h"

namespace pic {

namespace {

using Clock = std::chrono::steady_clock;

int reportError(const Error& error) { return pic::reportError("picclient", error); }

/// Assigns the value of a Result or returns the process exit code of its error.
#define PIC_TRY_ASSIGN_OR_EXIT(lhs, expr)                              \
    auto PIC_CONCAT_(picExit_, __LINE__) = (expr);                     \
    if (!PIC_CONCAT_(picExit_, __LINE__))                              \
        return reportError(PIC_CONCAT_(picExit_, __LINE__).error());   \
    lhs = std::move(*PIC_CONCAT_(picExit_, __LINE__))

struct Common {
    std::string server = "127.0.0.1:50051";
    std::string tlsCa;
    std::string session;
    std::string token;
    std::string apiKey;
    double connectSeconds = 10;
    double keepaliveSeconds = 20;
    double patienceSeconds = 30;
};

void addServer(CLI::App& app, Common& common) {
    app.add_option("--server", common.server, "picserver address HOST:PORT");
    app.add_option("--connect-timeout", common.connectSeconds, "seconds to wait for the server")
        ->check(CLI::PositiveNumber);
    app.add_option("--patience", common.patienceSeconds,
                   "seconds to go on trying (with backoff) while the server answers UNAVAILABLE: "
                   "it drains, or a replica behind the load balancer went away; streams "
                   "subscribe again; 0: give up at once")
        ->check(CLI::NonNegativeNumber);
    app.add_option("--tls-ca", common.tlsCa,
                   "connect with TLS, trusting the certificates in this PEM file")
        ->check(CLI::ExistingFile);
    app.add_option("--keepalive", common.keepaliveSeconds,
                   "seconds without traffic before a ping; a server that does not answer within "
                   "as long (at most 10 s) counts as gone (default 20)")
        ->check(CLI::Range(1.0, 86400.0));
    app.add_option("--api-key", common.apiKey,
                   "operator API key of a server with --api-keys (default: $PIC_API_KEY); sent "
                   "with every call")
        ->envname("PIC_API_KEY");
}

void addSession(CLI::App& app, Common& common) {
    app.add_option("--session", common.session, "session id (picclient session)")->required();
    app.add_option("--token", common.token, "the session's editor or viewer token")->required();
}

std::chrono::milliseconds patienceOf(const Common& common) {
    return std::chrono::milliseconds(int64_t(common.patienceSeconds * 1000.0));
}

Result<std::unique_ptr<PicConnection>> connectTo(const Common& common) {
    std::string rootCerts;
    if (!common.tlsCa.empty()) {
        std::ifstream file(common.tlsCa, std::ios::binary);
        rootCerts.assign(std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>());
        if (rootCerts.empty())
            return fail(ErrorCode::InvalidInput, "--tls-ca {} is empty or unreadable", common.tlsCa);
    }
    ConnectOptions options;
    options.timeout = std::chrono::milliseconds(int64_t(common.connectSeconds * 1000.0));
    options.rootCertsPem = std::move(rootCerts);
    options.apiKey = common.apiKey;
    options.keepalive = std::chrono::milliseconds(int64_t(common.keepaliveSeconds * 1000.0));
    PIC_TRY_ASSIGN(auto connection, PicConnection::connect(common.server, options));
    connection->setPatience(patienceOf(common));
    return connection;
}

int runSession(const Common& common, const std::string& bakeId) {
    PIC_TRY_ASSIGN_OR_EXIT(auto connection, connectTo(common));
    auto created = connection->createSession(bakeId);
    if (!created) return reportError(created.error());
    nlohmann::ordered_json json;
    json["session"] = created->session();
    json["editor_token"] = created->editor_token();
    json["viewer_token"] = created->viewer_token();
    json["bake_id"] = created->bake_id();
    json["version"] = created->version();
    std::printf("%s\n", json.dump().c_str());
    return 0;
}

int runLights(const Common& common, const std::string& path) {
    auto lights = readLightSet(path);
    if (!lights) return reportError(lights.error());
    PIC_TRY_ASSIGN_OR_EXIT(auto connection, connectTo(common));
    auto version = connection->setLights(common.session, common.token, *lights);
    if (!version) return reportError(version.error());
    std::printf("%llu\n", (unsigned long long)*version);
    return 0;
}

int runWatch(const Common& common, uint64_t count, double seconds) {
    PIC_TRY_ASSIGN_OR_EXIT(auto connection, connectTo(common));
    auto joined = connection->joinSession(common.session, common.token);
    if (!joined) return reportError(joined.error());
    auto header = connection->sceneHeader(joined->bake_id());
    if (!header) return reportError(header.error());
    auto stream = connection->subscribe(common.session, common.token, patienceOf(common));
    FrameDecoder decoder(*header);
    v1::Frame frame;
    uint64_t frames = 0;
    const auto start = Clock::now();
    // A timer thread ends the stream after `seconds`, since next() blocks.
    std::atomic<bool> done{false};
    std::thread timer;
    if (seconds > 0.0)
        timer = std::thread([&] {
            while (!done && Clock::now() - start < std::chrono::duration<double>(seconds))
                std::this_thread::sleep_for(std::chrono::milliseconds(10));
            stream->cancel();
        });
    int exit = 0;
    while ((count == 0 || frames < count) && stream->next(frame)) {
        const int64_t nowNs = std::chrono::duration_cast<std::chrono::nanoseconds>(
                                  std::chrono::system_clock::now().time_since_epoch())
                                  .count();
        size_t bytes = 0;
        for (const v1::Plane& plane : frame.planes()) bytes += plane.data().size();
        std::string kind = frame.base_version() == 0 ? std::string("key")
                           : frame.base_part() == 0
                               ? fmt::format("delta:{}", frame.base_version())
                               : fmt::format("delta:{}.{}", frame.base_version(), frame.base_part());
        if (frame.part() != 0) kind += fmt::format(", part {}", frame.part());
        const uint64_t version = frame.version();
        const double updateMs = frame.update_ms(), encodeMs = frame.encode_ms();
        const double latencyMs = double(nowNs - frame.lights_set_unix_ns()) / 1e6;
        const auto decodeStart = Clock::now();
        auto applied = decoder.apply(frame);
        const double decodeMs =
            std::chrono::duration<double, std::milli>(Clock::now() - decodeStart).count();
        if (!applied) {
            exit = reportError(applied.error());
            break;
        }
        std::printf("version %llu: %s, %zu bytes, latency %.1f ms (server update %.1f ms, encode "
                    "%.1f ms; decode %.1f ms)\n",
                    (unsigned long long)version, kind.c_str(), bytes, latencyMs, updateMs,
                    encodeMs, decodeMs);
        std::fflush(stdout);
        ++frames;
    }
    done = true;
    if (timer.joinable()) timer.join();
    stream->cancel();
    if (exit != 0) return exit;
    grpc::Status status = stream->status();
    if (!status.ok() && status.error_code() != grpc::StatusCode::CANCELLED)
        return reportError(wire::fromStatus(status, "Subscribe"));
    return 0;
}

int runStats(const Common& common) {
    PIC_TRY_ASSIGN_OR_EXIT(auto connection, connectTo(common));
    auto stats = connection->stats(common.session, common.token);
    if (!stats) return reportError(stats.error());
    std::string json;
    google::protobuf::util::JsonPrintOptions options;
    options.always_print_primitive_fields = true;
    options.preserve_proto_field_names = true;
    if (!google::protobuf::util::MessageToJsonString(*stats, &json, options).ok())
        return reportError(Error{ErrorCode::Internal, "cannot print the stats as JSON"});
    std::printf("%s\n", json.c_str());
    return 0;
}

int runLoad(const Common& common, const LoadOptions& options, const std::string& reportPath) {
    PIC_TRY_ASSIGN_OR_EXIT(auto connection, connectTo(common));
    std::fprintf(stderr, "picclient load: %u clients, %.1f s, %.2f light changes per second\n",
                 options.clients, options.durationSeconds, options.updateRate);
    auto report = runLoadTest(*connection, options);
    if (!report) return reportError(report.error());
    std::ofstream out(reportPath);
    out << report->dump(2) << "\n";
    if (!out) return reportError(Error{ErrorCode::Io, fmt::format("cannot write {}", reportPath)});
    const auto& latency = (*report)["latency_ms"];
    std::string parts;
    if (const uint64_t partial = (*report)["partial_frames"].get<uint64_t>(); partial > 0)
        parts = fmt::format(" ({} earlier parts; first change p50 {:.1f} p99 {:.1f})", partial,
                            (*report)["first_change_ms"]["p50"].get<double>(),
                            (*report)["first_change_ms"]["p99"].get<double>());
    std::printf("updates %llu, frames %llu%s, skipped %llu, errors %llu; latency ms p50 %.1f p95 "
                "%.1f p99 %.1f max %.1f; bytes per key frame %.0f, per delta %.0f -> %s\n",
                (unsigned long long)(*report)["updates"].get<uint64_t>(),
                (unsigned long long)(*report)["frames_received"].get<uint64_t>(), parts.c_str(),
                (unsigned long long)(*report)["versions_skipped"].get<uint64_t>(),
                (unsigned long long)(*report)["errors"].get<uint64_t>(),
                latency["p50"].get<double>(), latency["p95"].get<double>(),
                latency["p99"].get<double>(), latency["max"].get<double>(),
                (*report)["bytes_per_frame"]["key"].get<double>(),
                (*report)["bytes_per_frame"]["delta"].get<double>(), reportPath.c_str());
    return (*report)["errors"].get<uint64_t>() == 0 ? 0 : 1;
}

/// What `render` and `record` draw with: the view, the shading, the device, the shadow maps,
/// subsamples per pixel and where downloaded scenes are kept.
struct DrawFlags {
    ViewFlags view;
    ShadeFlags shade;
    std::string device;
    uint32_t shadowMapSize = 1024;
    uint32_t samples = 1;
    std::string cacheDir = defaultCacheDir();

    /// Adds the flags to `command`; `samplesHelp` says what --samples defaults to there.
    void addTo(CLI::App& command, const char* samplesHelp) {
        view.addTo(command);
        shade.addTo(command);
        addDeviceOption(command, device);
        command.add_option("--shadow-map-size", shadowMapSize,
                           "texels per side of each shadow-map layer")
            ->check(CLI::Range(16u, 16384u));
        command.add_option("--samples", samples, samplesHelp)
            ->check(CLI::Range(1u, kMaxSamplesPerPixel));
        command.add_option("--cache-dir", cacheDir, "where downloaded scenes are kept");
    }
};

/// A Vulkan context on the asked device and a renderer of `scene` in it (declared in that
/// order: the renderer goes first).
struct ClientRenderer {
    std::unique_ptr<gpu::Context> context;
    std::unique_ptr<Renderer> renderer;
};

Result<ClientRenderer> createRenderer(const DrawFlags& flags, const Scene& scene,
                                      const ClientLayout& layout) {
    gpu::ContextOptions contextOptions;
    contextOptions.deviceName = flags.device;
    ClientRenderer out;
    PIC_TRY_ASSIGN(out.context, gpu::Context::create(contextOptions));
    RendererOptions options;
    options.shadowMapSize = flags.shadowMapSize;
    PIC_TRY_ASSIGN(out.renderer, Renderer::create(*out.context, scene, layout, options));
    return out;
}

struct RenderCommand {
    std::string lightsPath;
    DrawFlags draw;
    ImageOutputFlags output;
    ObjectFlags objects;
    double waitSeconds = 60;
};

/// The scene and layout a view renders: the client's, or with `placements` a copy holding
/// the dynamic objects too, their triangles shaded from the grid (not light-mapped). Warns
/// when the bake's grid leaves much of them without a cache around.
struct ViewScene {
    Scene placed;  ///< with the objects (empty without)
    ClientLayout layout;
    const Scene* scene = nullptr;
};

Result<void> placeInto(ViewScene& view, const ClientScene& client,
                       const std::vector<ObjectPlacement>& placements) {
    view.layout = clientLayoutOf(client);
    view.scene = &client.scene;
    if (placements.empty()) return {};
    PIC_TRY_ASSIGN(view.placed, placeObjects(client.scene, placements));
    view.scene = &view.placed;
    view.layout.sceneHash = view.placed.hash;
    view.layout.triangleUvs.resize(3 * view.placed.triangles.size(), glm::vec2(kNotLightmapped));
    const double covered =
        gridCoverage(view.placed, client.scene.vertices.size(), view.layout.gridOrigin,
                     view.layout.gridCellSize, view.layout.gridDims, client.gridCaches);
    if (const std::string warning = gridCoverageWarning(covered); !warning.empty())
        std::fprintf(stderr, "picclient render: warning: %s\n", warning.c_str());
    return {};
}

int runRender(const Common& common, const RenderCommand& command) {
    const auto start = Clock::now();
    const auto since = [](Clock::time_point t) {
        return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
    };
    const DrawFlags& draw = command.draw;
    auto view = draw.view.toView();
    if (!view) return reportError(view.error());
    if (auto output = command.output.check(); !output) return reportError(output.error());
    PIC_TRY_ASSIGN_OR_EXIT(const std::vector<ObjectPlacement> placements,
                           command.objects.placements());
    std::optional<LightSet> pushed;
    if (!command.lightsPath.empty()) {
        auto lights = readLightSet(command.lightsPath);
        if (!lights) return reportError(lights.error());
        pushed = std::move(*lights);
    }
    PIC_TRY_ASSIGN_OR_EXIT(auto connection, connectTo(common));
    auto joined = connection->joinSession(common.session, common.token);
    if (!joined) return reportError(joined.error());
    const auto sceneStart = Clock::now();
    bool downloaded = false;
    auto client = connection->fetchScene(joined->bake_id(), draw.cacheDir, &downloaded);
    if (!client) return reportError(client.error());
    const double sceneMs = since(sceneStart);

    auto camera = view->cameraIn(client->scene);
    if (!camera) return reportError(camera.error());
    ViewScene shown;
    if (auto placed = placeInto(shown, *client, placements); !placed)
        return reportError(placed.error());

    // Subscribe first, then push: the wait below measures the light change to the frame.
    auto stream = connection->subscribe(common.session, common.token, patienceOf(common));
    uint64_t wanted = joined->version();
    LightSet lights;
    const auto pushStart = Clock::now();
    if (pushed) {
        auto version = connection->setLights(common.session, common.token, *pushed);
        if (!version) return reportError(version.error());
        wanted = *version;
        lights = *pushed;
    } else {
        auto current = wire::fromProto(joined->lights());
        if (!current) return reportError(current.error());
        lights = std::move(*current);
    }
    // A timer ends the stream if the version never comes.
    std::atomic<bool> done{false};
    std::thread timer([&] {
        while (!done && since(pushStart) < command.waitSeconds * 1000.0)
            std::this_thread::sleep_for(std::chrono::milliseconds(10));
        if (!done) stream->cancel();
    });
    FrameDecoder decoder(client->header);
    v1::Frame frame;
    double decodeMs = 0.0, serverMs = 0.0;
    size_t bytes = 0;
    // A budgeted server streams earlier parts first (v1::Frame::part): the image waits for the
    // final state.
    while (!decoder.holds(wanted) && stream->next(frame)) {
        bytes = 0;
        for (const v1::Plane& plane : frame.planes()) bytes += plane.data().size();
        serverMs = frame.update_ms() + frame.encode_ms();
        const auto decodeStart = Clock::now();
        auto applied = decoder.apply(frame);
        if (!applied) {
            done = true;
            timer.join();
            return reportError(applied.error());
        }
        decodeMs = since(decodeStart);
    }
    // Writing the caches into the textures the renderer samples ends the latency.
    Result<CacheTextures> textures = fail(ErrorCode::Internal, "no frame decoded");
    double texturesMs = 0.0;
    if (decoder.holds(wanted)) {
        const auto texturesStart = Clock::now();
        textures = cacheTexturesOf(*client, decoder.frame());
        texturesMs = since(texturesStart);
    }
    const double latencyMs = since(pushStart);
    done = true;
    timer.join();
    stream->cancel();
    if (!decoder.holds(wanted)) {
        grpc::Status status = stream->status();
        if (!status.ok() && status.error_code() != grpc::StatusCode::CANCELLED)
            return reportError(wire::fromStatus(status, "Subscribe"));
        return reportError(Error{ErrorCode::Internal,
                                 fmt::format("version {} did not arrive within {} s", wanted,
                                             command.waitSeconds)});
    }
    if (!textures) return reportError(textures.error());
    // The frame names the light set its caches were computed for: the newest version may be
    // newer than the one pushed or joined.
    if (decoder.lights()) lights = *decoder.lights();

    PIC_TRY_ASSIGN_OR_EXIT(ClientRenderer renderer, createRenderer(draw, *shown.scene, shown.layout));
    if (auto set = renderer.renderer->setCaches(*textures); !set) return reportError(set.error());
    RenderTimings timings;
    auto image = renderer.renderer->render(lights, *camera,
                                           draw.shade.toParams(view->size, draw.samples), &timings);
    if (!image) return reportError(image.error());
    if (auto written = command.output.write(*image); !written) return reportError(written.error());

    std::string passes;
    for (const auto& [pass, ms] : timings.passMs)
        passes += fmt::format("{}{} {:.1f}", passes.empty() ? "" : ", ", pass, ms);
    // Without --lights nothing changed: the time is the session's current frame arriving.
    std::fprintf(
        stderr,
        "picclient render: scene %s in %.0f ms (%s); version %llu: %s %.1f ms (server update + "
        "encode %.1f ms, %zu bytes, decode %.1f ms, textures %.1f ms); "
        "render %ux%u %s, %u samples per pixel, on \"%s\" %.1f ms (%s); total %.0f ms -> %s\n",
        downloaded ? "downloaded" : "kept", sceneMs, client->folder.c_str(),
        (unsigned long long)decoder.version(),
        pushed ? "light change to decoded frame" : "current frame received and decoded in",
        latencyMs, serverMs, bytes, decodeMs, texturesMs, view->size.x, view->size.y,
        draw.shade.component().c_str(), draw.samples, renderer.context->deviceName().c_str(),
        timings.totalMs,
        passes.c_str(), since(start), command.output.path().c_str());
    std::printf("%s\n", command.output.path().c_str());
    return 0;
}

struct RecordCommand {
    DrawFlags draw;
    double fps = 10.0;
    double durationSeconds = 10.0;
    double blendSeconds = 0.5;
    std::string outDir;
    std::string format = "png";
    float exposure = 1.0f;
};

/// A version the stream delivered: its caches and light set, and when it arrived.
struct Arrival {
    CacheValues values;
    std::optional<LightSet> lights;  ///< what the frame named (servers before frames did: none)
    Clock::time_point at;
};

int runRecord(const Common& common, const RecordCommand& command) {
    const DrawFlags& draw = command.draw;
    auto view = draw.view.toView();
    if (!view) return reportError(view.error());
    if (auto ok = CacheBlend::check(command.blendSeconds); !ok) return reportError(ok.error());
    std::error_code ec;
    std::filesystem::create_directories(command.outDir, ec);
    if (ec)
        return reportError(Error{ErrorCode::Io, fmt::format("cannot create {}: {}",
                                                            command.outDir, ec.message())});
    PIC_TRY_ASSIGN_OR_EXIT(auto connection, connectTo(common));
    auto joined = connection->joinSession(common.session, common.token);
    if (!joined) return reportError(joined.error());
    auto client = connection->fetchScene(joined->bake_id(), draw.cacheDir);
    if (!client) return reportError(client.error());
    auto camera = view->cameraIn(client->scene);
    if (!camera) return reportError(camera.error());
    PIC_TRY_ASSIGN_OR_EXIT(ClientRenderer renderer,
                           createRenderer(draw, client->scene, clientLayoutOf(*client)));

    // The stream is read on its own thread (next() blocks); the frames are drawn here at their
    // times, each from the caches blended up to that moment.
    auto stream = connection->subscribe(common.session, common.token, patienceOf(common));
    std::mutex mutex;
    std::vector<Arrival> arrived;
    std::optional<Error> streamError;
    std::thread reader([&] {
        FrameDecoder decoder(client->header);
        v1::Frame frame;
        while (stream->next(frame)) {
            const Result<void> applied = decoder.apply(frame);
            Result<CacheValues> values = applied ? cacheValuesOf(*client, decoder.frame())
                                                 : Result<CacheValues>(std::unexpected(applied.error()));
            std::lock_guard lock(mutex);
            if (!values) {
                streamError = values.error();
                return;
            }
            arrived.push_back({std::move(*values),
                               decoder.lights() ? std::optional<LightSet>(*decoder.lights())
                                                : std::nullopt,
                               Clock::now()});
        }
    });
    const auto stop = [&] {
        stream->cancel();
        reader.join();
    };

    CacheBlend blend(command.blendSeconds);
    std::optional<LightSet> lights;
    const ShadeParams params = draw.shade.toParams(view->size, draw.samples);
    const auto start = Clock::now();
    const auto seconds = [&](Clock::time_point t) {
        return std::chrono::duration<double>(t - start).count();
    };
    const auto period = std::chrono::duration<double>(1.0 / command.fps);
    uint32_t frames = 0, versions = 0;
    bool uploadedSettled = false;  // the textures hold the settled newest version
    double renderMs = 0.0;
    for (auto due = start; seconds(due) < command.durationSeconds;
         due += std::chrono::duration_cast<Clock::duration>(period)) {
        std::this_thread::sleep_until(due);
        {
            std::lock_guard lock(mutex);
            if (streamError) break;
            for (Arrival& a : arrived) {
                if (auto pushed = blend.push(std::move(a.values), seconds(a.at)); !pushed) {
                    stop();
                    return reportError(pushed.error());
                }
                // The direct light follows the newest light set at once; the caches blend.
                if (a.lights) lights = std::move(a.lights);
                if (!lights) lights = LightSet{};
                uploadedSettled = false;
                ++versions;
            }
            arrived.clear();
        }
        const double now = std::max(seconds(Clock::now()), seconds(due));
        const CacheValues* shown = blend.at(now);
        if (!shown) continue;  // nothing received yet
        // Once a blend has settled the textures hold its version until the next arrives.
        if (!uploadedSettled) {
            if (auto set = renderer.renderer->setCaches(cacheTexturesOf(*client, *shown)); !set) {
                stop();
                return reportError(set.error());
            }
            uploadedSettled = blend.settled(now);
        }
        RenderTimings timings;
        auto image = renderer.renderer->render(*lights, *camera, params, &timings);
        if (!image) {
            stop();
            return reportError(image.error());
        }
        renderMs += timings.totalMs;
        const std::string path = (std::filesystem::path(command.outDir) /
                                  fmt::format("frame_{:05}.{}", frames, command.format))
                                     .string();
        if (auto written = writeImage(path, *image, command.exposure); !written) {
            stop();
            return reportError(written.error());
        }
        ++frames;
        // A frame that took longer than the period leaves the skipped slots out.
        while (Clock::now() - due > period) due += std::chrono::duration_cast<Clock::duration>(period);
    }
    stop();
    if (streamError) return reportError(*streamError);
    const double elapsed = seconds(Clock::now());
    std::fprintf(stderr,
                 "picclient record: %u frames in %.1f s (%.1f per second, %.1f ms to render "
                 "each), %u versions blended over %.2f s -> %s\n",
                 frames, elapsed, double(frames) / elapsed, frames ? renderMs / frames : 0.0,
                 versions, command.blendSeconds, command.outDir.c_str());
    std::printf("%s\n", command.outDir.c_str());
    if (frames == 0)
        return reportError(Error{ErrorCode::Internal, fmt::format("no version arrived within {} s: "
                                                                  "nothing was recorded",
                                                                  command.durationSeconds)});
    return 0;
}

}  // namespace

int picclientMain(int argc, char** argv) {
    CLI::App app{"picclient: a thin client of picserver: sessions, light changes, the frame "
                 "stream, load tests and rendering from the streamed caches"};
    app.name("picclient");
    app.require_subcommand(1);
    Common common;

    std::string bakeId;
    CLI::App* session = app.add_subcommand(
        "session", "create a session (its first light set is the glTF's own lights); prints "
                   "{\"session\", \"editor_token\", \"viewer_token\", ...}");
    addServer(*session, common);
    session->add_option("--bake", bakeId, "bake id (default: the server's first bake)");

    std::string lightsPath;
    CLI::App* lights = app.add_subcommand("lights", "push a light set (editor token); prints the "
                                                    "version it produces");
    addServer(*lights, common);
    addSession(*lights, common);
    lights->add_option("--set", lightsPath, "light set JSON (ARCHITECTURE.md §4)")->required();

    uint64_t count = 0;
    double watchSeconds = 0;
    CLI::App* watch = app.add_subcommand("watch", "subscribe and print each version's latency "
                                                  "and bytes");
    addServer(*watch, common);
    addSession(*watch, common);
    watch->add_option("--count", count, "stop after this many frames (0: never)");
    watch->add_option("--duration", watchSeconds, "stop after this many seconds (0: never)")
        ->check(CLI::NonNegativeNumber);

    CLI::App* statsCommand = app.add_subcommand(
        "stats", "print the session's counters (frames, bytes, update and encode ms) as JSON");
    addServer(*statsCommand, common);
    addSession(*statsCommand, common);

    LoadOptions load;
    std::string reportPath;
    CLI::App* loadCommand = app.add_subcommand(
        "load", "N subscribers and an editor moving a light; writes a latency report");
    addServer(*loadCommand, common);
    loadCommand->add_option("--clients", load.clients, "subscribers")->required()
        ->check(CLI::Range(1u, 10000u));
    loadCommand->add_option("--duration", load.durationSeconds, "seconds of light changes")
        ->required()->check(CLI::PositiveNumber);
    loadCommand->add_option("--update-rate", load.updateRate, "light changes per second")
        ->check(CLI::NonNegativeNumber);
    loadCommand->add_option("--session", load.session, "an existing session (default: a new one)");
    loadCommand->add_option("--token", load.editorToken, "its editor token");
    loadCommand->add_option("--move", load.moveMetres,
                            "radius in metres of the circle a point or spot light moves on")
        ->check(CLI::PositiveNumber);
    loadCommand->add_option("--report", reportPath, "JSON report to write")->required();

    RenderCommand render;
    render.draw.samples = 4;
    CLI::App* renderCommand = app.add_subcommand(
        "render", "render one frame headless (Vulkan: a GPU, else lavapipe) shaded with the "
                  "session's current caches; --lights (editor token) is applied first");
    addServer(*renderCommand, common);
    addSession(*renderCommand, common);
    renderCommand->add_option("--lights", render.lightsPath,
                              "light set JSON to push first (needs the editor token)");
    render.draw.addTo(*renderCommand,
                      "subsamples per pixel, averaged: anti-aliasing, each costs a G-buffer and "
                      "a shading pass (default 4; 1: pixel centres; picref shade --spp N is the "
                      "CPU counterpart)");
    render.output.addTo(*renderCommand);
    render.objects.addTo(*renderCommand);
    renderCommand->add_option("--wait", render.waitSeconds, "seconds to wait for the version")
        ->check(CLI::PositiveNumber);

    RecordCommand record;
    CLI::App* recordCommand = app.add_subcommand(
        "record", "render the session's stream as a sequence of frames at a fixed rate, each "
                  "from the caches blended over time from one version to the next");
    addServer(*recordCommand, common);
    addSession(*recordCommand, common);
    record.draw.addTo(*recordCommand, "subsamples per pixel, averaged (default 1)");
    recordCommand->add_option("--fps", record.fps, "frames per second (default 10)")
        ->check(CLI::Range(0.1, 240.0));
    recordCommand->add_option("--duration", record.durationSeconds,
                              "seconds to record (default 10)")
        ->check(CLI::Range(0.001, 86400.0));
    recordCommand->add_option("--blend", record.blendSeconds,
                              "seconds over which the caches move from one version to the next "
                              "(default 0.5; 0: each version at once)")
        ->check(CLI::Range(0.0, 3600.0));
    recordCommand->add_option("--format", record.format, "frame files: png (default) or exr")
        ->check(CLI::IsMember({"png", "exr"}));
    recordCommand->add_option("--exposure", record.exposure,
                              "factor applied before PNG quantisation (default 1)")
        ->check(CLI::PositiveNumber);
    recordCommand->add_option("--out-dir", record.outDir, "folder for frame_00000.png, …")
        ->required();

    if (auto exit = parseCommandLine(app, argc, argv)) return *exit;
    if (recordCommand->parsed()) return runRecord(common, record);
    if (session->parsed()) return runSession(common, bakeId);
    if (lights->parsed()) return runLights(common, lightsPath);
    if (watch->parsed()) return runWatch(common, count, watchSeconds);
    if (renderCommand->parsed()) return runRender(common, render);
    if (statsCommand->parsed()) return runStats(common);
    if (loadCommand->parsed()) {
        if (load.session.empty() != load.editorToken.empty())
            return reportError({ErrorCode::InvalidInput, "--session and --token go together"});
        return runLoad(common, load, reportPath);
    }
    return 2;
}

}  // namespace pic
