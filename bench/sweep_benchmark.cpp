#include "bench/sweep_benchmark.h"

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <sstream>

#include <nlohmann/json.hpp>

#include "bake/ref/path_tracer.h"
#include "bake/ref/probes.h"
#include "bake/target_error.h"
#include "bench/bench_common.h"
#include "bench/server_process.h"
#include "bench/chart.h"
#include "bench/light_propagation_volume.h"
#include "bench/traced_probes.h"
#include "core/bake_file.h"
#include "core/color.h"
#include "core/frame_codec.h"
#include "core/gltf_loader.h"
#include "core/hash.h"
#include "core/image.h"
#include "render/cpu/cache_shading.h"
#include "render/cpu_runtime.h"
#include "render/gpu_runtime.h"

namespace pic {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;
using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

/// "12.5" for a float flag, without trailing zeros.
std::string flagNumber(double value) { return fmt::format("{:.6g}", value); }

/// Writes `json` to `path` through a temporary file and a rename, so that a killed sweep
/// never leaves half a result behind.
Result<void> writeJsonAtomically(const Json& json, const fs::path& path) {
    const fs::path tmp = path.string() + ".tmp";
    {
        std::ofstream out(tmp);
        out << json.dump(2) << "\n";
        if (!out) return fail(ErrorCode::Io, "cannot write {}", tmp.string());
    }
    std::error_code ec;
    fs::rename(tmp, path, ec);
    if (ec) return fail(ErrorCode::Io, "cannot rename {} to {}: {}", tmp.string(), path.string(), ec.message());
    return {};
}

std::optional<Json> readJson(const fs::path& path) {
    std::ifstream in(path);
    if (!in) return std::nullopt;
    Json json = Json::parse(in, nullptr, false);
    if (json.is_discarded()) return std::nullopt;
    return json;
}

/// Runs `args` as a child process with stdout and stderr into `logPath`; fails naming the
/// command and the log when it does not exit with 0.
Result<void> runChild(const std::vector<std::string>& args, const fs::path& logPath) {
    const pid_t pid = fork();
    if (pid < 0) return fail(ErrorCode::Internal, "fork failed for {}", args.front());
    if (pid == 0) {
        FILE* log = std::fopen(logPath.c_str(), "w");
        if (log) {
            dup2(fileno(log), STDOUT_FILENO);
            dup2(fileno(log), STDERR_FILENO);
        }
        execChild(args);
    }
    int status = 0;
    if (waitpid(pid, &status, 0) < 0) return fail(ErrorCode::Internal, "waitpid failed for {}", args.front());
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        std::string command;
        for (const std::string& a : args) command += (command.empty() ? "" : " ") + a;
        return fail(ErrorCode::Internal, "`{}` failed (exit status {}); its output is in {}", command,
                    WIFEXITED(status) ? WEXITSTATUS(status) : -1, logPath.string());
    }
    return {};
}

/// One view of the sweep with its path-traced reference: the mean of two independent
/// halves, whose difference gives the reference's own noise.
struct ViewReference {
    Camera camera;
    Image indirect, full;
    double indirectNoise = 0.0;  ///< relative RMSE of the mean of the halves against the truth (estimate)
    double fullNoise = 0.0;
};


/// Everything the sweep holds while it runs.
struct SweepContext {
    const SweepParams& params;
    const Scene& scene;
    const LightSet& lights;
    const EmbreeScene* rays;  ///< built over `scene`, which therefore stays where it is
    std::vector<ViewReference> views;
    fs::path dir;
    float step = 0.05f;  ///< metres a timed light change moves the lights
};

Result<Camera> cameraOfView(const SweepContext& context, size_t index) {
    if (context.params.view.camera) return *context.params.view.camera;
    View view = context.params.view;
    view.sceneCameraIndex = context.params.sceneCameras.empty() ? 0 : context.params.sceneCameras[index];
    return view.cameraIn(context.scene);
}

size_t viewCount(const SweepParams& params) {
    return params.view.camera || params.sceneCameras.empty() ? 1 : params.sceneCameras.size();
}

/// The path-traced references of every view, traced once per output folder (kept as EXR).
Result<void> loadOrTraceReferences(SweepContext& context) {
    const SweepParams& params = context.params;
    const fs::path dir = context.dir / "reference";
    std::error_code ec;
    fs::create_directories(dir, ec);
    for (size_t v = 0; v < viewCount(params); ++v) {
        ViewReference view;
        PIC_TRY_ASSIGN(view.camera, cameraOfView(context, v));
        for (const bool indirect : {true, false}) {
            const std::string kind = indirect ? "indirect" : "full";
            Image halves[2];
            for (int h = 0; h < 2; ++h) {
                const fs::path path = dir / fmt::format("view{}_{}_half{}.exr", v, kind, h + 1);
                if (fs::exists(path)) {
                    PIC_TRY_ASSIGN(halves[h], readImage(path.string()));
                    continue;
                }
                std::fprintf(stderr, "picbench sweep: path tracing the %s reference of view %zu, half %d "
                             "(%u spp) …\n", kind.c_str(), v, h + 1, std::max(params.spp / 2, 1u));
                PathTraceParams trace;
                trace.width = params.view.size.x;
                trace.height = params.view.size.y;
                trace.spp = std::max(params.spp / 2, 1u);
                trace.seed = uint64_t(h + 1);
                // The indirect reference holds what pic's caches carry: with emitting surfaces,
                // their first reflection too.
                trace.component = indirect ? PathTraceParams::Component::Cached
                                           : PathTraceParams::Component::Full;
                PIC_TRY_ASSIGN(halves[h], pathTrace(context.scene, *context.rays, context.lights,
                                                    view.camera, trace));
                PIC_TRY(writeImage(path.string(), halves[h]));
            }
            Image mean = meanOfHalves(halves[0], halves[1]);
            (indirect ? view.indirectNoise : view.fullNoise) = halvesNoise(halves[0], halves[1]);
            (indirect ? view.indirect : view.full) = std::move(mean);
        }
        context.views.push_back(std::move(view));
    }
    return {};
}

/// The inputs every figure of an output folder depends on; a folder holding another sweep's
/// figures is refused rather than mixed.
Json inputsSignature(const SweepContext& context) {
    const std::string lights = toJson(context.lights);
    const SweepParams& params = context.params;
    Json views = Json::array();
    for (size_t v = 0; v < viewCount(params); ++v) {
        auto camera = cameraOfView(context, v);
        if (!camera) continue;
        views.push_back({camera->eye.x, camera->eye.y, camera->eye.z, camera->target.x, camera->target.y,
                         camera->target.z, camera->up.x, camera->up.y, camera->up.z, camera->fovyDegrees});
    }
    return {{"scene", fs::path(params.scenePath).filename().string()},
            {"scene_hash", fmt::format("{:016x}", context.scene.hash)},
            {"lights_hash", fmt::format("{:016x}", hashBytes(lights.data(), lights.size()))},
            {"size", fmt::format("{}x{}", params.view.size.x, params.view.size.y)},
            {"views", views},
            {"base_bake_args", params.baseBakeArgs},
            {"reference_spp", params.spp},
            {"probe_samples", params.probeSamples},
            {"shade_spp", params.shadeSpp}};
}

/// Where a bake's caches sit and how many bands they have: what an ideal image depends on.
uint64_t layoutHash(const BakeData& bake) {
    uint64_t h = hashVector(bake.caches);
    h = hashVector(bake.grid.cacheIndex, h);
    h = hashVector(bake.lightmap.cacheIndex, h);
    const uint32_t bands[2] = {bake.params.bandsY, bake.params.bandsC};
    return hashBytes(bands, sizeof bands, h);
}

/// The error figures of one method at one setting, over the views.
struct Accuracy {
    std::vector<ImageError> indirect, full;
    std::vector<double> blotch;  ///< against the ideal caches of the same layout; empty when none
};

Json errorJson(const ImageError& e) {
    return {{"relative_rmse", e.relativeRmse}, {"mean_ratio", e.meanRatio},
            {"channel_ratio", {e.channelRatio.r, e.channelRatio.g, e.channelRatio.b}}};
}

double meanOf(const std::vector<double>& values) {
    double sum = 0.0;
    for (double v : values) sum += v;
    return values.empty() ? 0.0 : sum / double(values.size());
}

Json accuracyJson(const Accuracy& accuracy) {
    Json json;
    std::vector<double> indirect, full, ratio, fullRatio;
    for (const ImageError& e : accuracy.indirect) indirect.push_back(e.relativeRmse), ratio.push_back(e.meanRatio);
    for (const ImageError& e : accuracy.full) full.push_back(e.relativeRmse), fullRatio.push_back(e.meanRatio);
    json["indirect_rmse"] = meanOf(indirect);
    json["indirect_mean_ratio"] = meanOf(ratio);
    json["full_rmse"] = meanOf(full);
    json["full_mean_ratio"] = meanOf(fullRatio);
    json["blotch_index"] = accuracy.blotch.empty() ? Json(nullptr) : Json(meanOf(accuracy.blotch));
    json["views"] = Json::array();
    for (size_t v = 0; v < accuracy.indirect.size(); ++v) {
        Json view = {{"indirect", errorJson(accuracy.indirect[v])}, {"full", errorJson(accuracy.full[v])}};
        if (v < accuracy.blotch.size()) view["blotch_index"] = accuracy.blotch[v];
        json["views"].push_back(view);
    }
    return json;
}

/// Shades `values` at every view, indirect and full.
Result<std::vector<std::pair<Image, Image>>> shadeViews(const SweepContext& context, const BakeData& bake,
                                                        const CacheValues& values) {
    std::vector<std::pair<Image, Image>> images;
    ShadeParams shade;
    shade.width = context.params.view.size.x;
    shade.height = context.params.view.size.y;
    shade.samplesPerPixel = context.params.shadeSpp;
    for (const ViewReference& view : context.views) {
        shade.component = ShadeComponent::Indirect;
        PIC_TRY_ASSIGN(Image indirect, shadeFromCaches(context.scene, *context.rays, bake, values,
                                                        context.lights, view.camera, shade));
        shade.component = ShadeComponent::Full;
        PIC_TRY_ASSIGN(Image full, shadeFromCaches(context.scene, *context.rays, bake, values,
                                                    context.lights, view.camera, shade));
        images.emplace_back(std::move(indirect), std::move(full));
    }
    return images;
}

/// The ideal caches' indirect images of a layout (path-traced probes at `samples`
/// directions), traced once per output folder; `probeMs` receives the tracing time.
Result<std::vector<Image>> idealImages(const SweepContext& context, const BakeData& bake, uint32_t samples,
                                       double& probeMs, const CacheValues** valuesOut = nullptr,
                                       std::optional<CacheValues>* keep = nullptr) {
    const fs::path dir = context.dir / "ideal";
    std::error_code ec;
    fs::create_directories(dir, ec);
    const std::string stem = fmt::format("{:016x}_s{}", layoutHash(bake), samples);
    const fs::path meta = dir / (stem + ".json");
    std::vector<Image> images;
    if (auto json = readJson(meta); json && !keep) {
        bool all = true;
        for (size_t v = 0; v < context.views.size() && all; ++v) {
            auto image = readImage((dir / fmt::format("{}_view{}.exr", stem, v)).string());
            if (!image) all = false;
            else images.push_back(std::move(*image));
        }
        if (all) {
            probeMs = json->value("probe_ms", 0.0);
            return images;
        }
        images.clear();
    }
    std::fprintf(stderr, "picbench sweep: tracing the ideal caches (%zu caches, %u directions) …\n",
                 bake.caches.size(), samples);
    ProbeParams probe;
    probe.samples = samples;
    const Clock::time_point start = Clock::now();
    PIC_TRY_ASSIGN(CacheValues ideal, pathTraceProbes(context.scene, *context.rays, bake, context.lights, probe));
    probeMs = msSince(start);
    PIC_TRY_ASSIGN(auto shaded, shadeViews(context, bake, ideal));
    for (size_t v = 0; v < shaded.size(); ++v) {
        PIC_TRY(writeImage((dir / fmt::format("{}_view{}.exr", stem, v)).string(), shaded[v].first));
        images.push_back(std::move(shaded[v].first));
    }
    PIC_TRY(writeJsonAtomically({{"probe_ms", probeMs}, {"caches", bake.caches.size()}}, meta));
    if (keep) {
        *keep = std::move(ideal);
        if (valuesOut) *valuesOut = &**keep;
    }
    return images;
}

/// The accuracy of cache values `values` of `bake` at every view; blotch index against
/// `ideal` (one indirect image per view) when given.
Result<Accuracy> measureAccuracy(const SweepContext& context, const BakeData& bake, const CacheValues& values,
                                 const std::vector<Image>* ideal) {
    Accuracy accuracy;
    PIC_TRY_ASSIGN(auto shaded, shadeViews(context, bake, values));
    for (size_t v = 0; v < shaded.size(); ++v) {
        PIC_TRY_ASSIGN(ImageError indirect, compareImages(shaded[v].first, context.views[v].indirect));
        PIC_TRY_ASSIGN(ImageError full, compareImages(shaded[v].second, context.views[v].full));
        accuracy.indirect.push_back(indirect);
        accuracy.full.push_back(full);
        if (ideal) {
            PIC_TRY_ASSIGN(double blotch, blotchIndex(shaded[v].first, (*ideal)[v]));
            accuracy.blotch.push_back(blotch);
        }
    }
    return accuracy;
}

/// Stream bytes of `settled` as a key frame and of `changed` as a delta frame from it.
Result<std::pair<size_t, size_t>> streamBytes(const CacheValues& settled, const CacheValues& changed) {
    const HalfFrame base = halfFrameOf(settled), next = halfFrameOf(changed);
    PIC_TRY_ASSIGN(EncodedFrame key, encodeFrame(base, nullptr));
    PIC_TRY_ASSIGN(EncodedFrame delta, encodeFrame(next, &base));
    return std::pair{key.bytes(), delta.bytes()};
}

/// The bake parameters a point reports.
Json paramsJson(const BakeData& bake) {
    const BakeParams& p = bake.params;
    return {{"surfels", p.surfels},
            {"links", p.linksPerCache},
            {"bands_y", p.bandsY},
            {"bands_c", p.bandsC},
            {"link_mode", p.linkMode == LinkMode::Sh ? "sh" : "rtp"},
            {"grid_cell", p.gridCell},
            {"lightmap_texel", p.lightmapTexel},
            {"link_samples", p.linkSamples},
            {"caches", bake.caches.size()}};
}

/// Bakes one setting with picbake (a child process, so that its peak memory is its own).
Result<Json> bakeSetting(const SweepContext& context, const SweepSetting& setting, const fs::path& bakePath) {
    const SweepParams& params = context.params;
    std::vector<std::string> args{params.picbake.empty() ? siblingProgram("bake", "picbake") : params.picbake, "bake",
                                  params.scenePath, "-o", bakePath.string()};
    const std::vector<std::string> flags = mergeFlags(params.baseBakeArgs, setting.bakeArgs);
    args.insert(args.end(), flags.begin(), flags.end());
    const fs::path log = context.dir / "logs" / (setting.key() + ".log");
    const Clock::time_point start = Clock::now();
    PIC_TRY(runChild(args, log));
    const double wallSeconds = msSince(start) * 1e-3;
    auto timings = readJson(bakePath.string() + ".timings.json");
    if (!timings) return fail(ErrorCode::Internal, "picbake wrote no timings beside {}", bakePath.string());
    std::error_code ec;
    return Json{{"bake_seconds", timings->value("seconds_total", wallSeconds)},
                {"bake_wall_seconds", wallSeconds},
                {"bake_peak_memory_bytes", timings->value("peak_memory_bytes", uint64_t{0})},
                {"bake_file_bytes", uint64_t(fs::file_size(bakePath, ec))}};
}

/// Update ms (medians) of the CPU twin and, when it can be made, the GPU backend, taking
/// turns update by update so that a busy spell of the machine slows both; the settled
/// values under the sweep's lights and after one change (move-one), for accuracy and stream
/// bytes, from the backend whose visibility the setting names.
struct RuntimeFigures {
    double cpuMs = 0.0;
    std::optional<double> gpuMs;
    std::string gpuDevice;
    uint64_t gpuMemory = 0;
    int bounces = 0;
    CacheValues settled, changed;
};

Result<RuntimeFigures> timeRuntimes(const SweepContext& context, const BakeData& bake, const SweepSetting& setting) {
    const SweepParams& params = context.params;
    PIC_TRY_ASSIGN(auto cpu, createCpuRuntime(context.scene, *context.rays, bake, BounceParams{}));
    std::unique_ptr<GpuRuntime> gpu;
    RuntimeFigures figures;
    const bool needGpu = setting.visibility != "rays";
    if (params.gpu || needGpu) {
        GpuRuntimeOptions options;
        options.deviceName = params.device;
        options.directVisibility =
            setting.visibility == "rays" ? gpu::DirectVisibility::Rays : gpu::DirectVisibility::ShadowMaps;
        auto made = GpuRuntime::create(context.scene, *context.rays, bake, BounceParams{}, options);
        if (made) {
            gpu = std::move(*made);
            figures.gpuDevice = gpu->context().deviceName();
            for (const auto& [group, bytes] : gpu->memory()) figures.gpuMemory += bytes;
        } else if (needGpu) {
            return std::unexpected(made.error());
        } else {
            std::fprintf(stderr, "picbench sweep: no GPU backend (%s); CPU twin only\n",
                         made.error().message.c_str());
        }
    }
    std::vector<Runtime*> runtimes{cpu.get()};
    if (gpu) runtimes.push_back(gpu.get());
    std::vector<std::vector<double>> ms(runtimes.size());
    UpdateStats stats;
    for (Runtime* runtime : runtimes) PIC_TRY(runtime->setLights(changedLights(context.lights, 0, context.step, "move-all")));
    for (int k = 1; k <= params.repeat; ++k)
        for (size_t r = 0; r < runtimes.size(); ++r) {
            const Clock::time_point start = Clock::now();
            PIC_TRY(runtimes[r]->setLights(changedLights(context.lights, k, context.step, "move-all"), &stats));
            ms[r].push_back(msSince(start));
            if (r == 0) figures.bounces = stats.bounces;
        }
    figures.cpuMs = median(ms[0]);
    if (gpu) figures.gpuMs = median(ms[1]);
    Runtime* source = needGpu ? static_cast<Runtime*>(gpu.get()) : cpu.get();
    PIC_TRY_ASSIGN(const CacheValues* settled, source->setLights(context.lights));
    figures.settled = *settled;
    PIC_TRY_ASSIGN(const CacheValues* changed, source->setLights(changedLights(context.lights, 1, context.step, "move-one")));
    figures.changed = *changed;
    return figures;
}

/// Measures one setting of pic: bake, update times, accuracy, bytes. The bake file is kept
/// when `keep` (the default setting's, which the baselines use).
Result<Json> measureSetting(const SweepContext& context, const SweepSetting& setting, bool keep) {
    const fs::path bakePath = context.dir / "bakes" / (setting.key() + ".pic");
    Json point{{"method", "pic"}, {"name", setting.name}, {"axis", setting.axis}, {"key", setting.key()},
               {"bake_args", setting.bakeArgs}, {"visibility", setting.visibility}};
    PIC_TRY_ASSIGN(Json bakeFigures, bakeSetting(context, setting, bakePath));
    PIC_TRY_ASSIGN(BakeData bake, readBakeFile(bakePath.string()));
    point["params"] = paramsJson(bake);
    point.update(bakeFigures);
    std::fprintf(stderr, "picbench sweep:   baked in %.1f s (%zu caches); timing updates …\n",
                 bakeFigures["bake_seconds"].get<double>(), bake.caches.size());
    PIC_TRY_ASSIGN(RuntimeFigures runtime, timeRuntimes(context, bake, setting));
    point["cpu_update_ms"] = runtime.cpuMs;
    point["gpu_update_ms"] = runtime.gpuMs ? Json(*runtime.gpuMs) : Json(nullptr);
    point["gpu_device"] = runtime.gpuDevice;
    point["bounces"] = runtime.bounces;
    point["settle_updates"] = 1;
    point["settle_ms"] = runtime.cpuMs;
    point["runtime_memory_bytes"] = runtime.gpuMemory ? runtime.gpuMemory : bakeFigures["bake_file_bytes"].get<uint64_t>();
    PIC_TRY_ASSIGN(auto bytes, streamBytes(runtime.settled, runtime.changed));
    point["stream_key_bytes"] = bytes.first;
    point["stream_delta_bytes"] = bytes.second;
    double probeMs = 0.0;
    PIC_TRY_ASSIGN(std::vector<Image> ideal, idealImages(context, bake, context.params.probeSamples, probeMs));
    PIC_TRY_ASSIGN(Accuracy accuracy, measureAccuracy(context, bake, runtime.settled, &ideal));
    point["accuracy"] = accuracyJson(accuracy);
    if (auto target = readJson(bakePath.string() + ".target.json")) point["target"] = std::move(*target);
    if (!keep && !context.params.keepBakes) {
        std::error_code ec;
        fs::remove(bakePath, ec);
        fs::remove(bakePath.string() + ".timings.json", ec);
        fs::remove(bakePath.string() + ".target.json", ec);
    }
    return point;
}

/// A method the sweep compares pic with, run on the default bake's caches.
struct Baseline {
    std::string key, name, method;
    Json settings;
    /// Makes the method; returns a function that runs one update under a light set.
    std::function<Result<std::function<Result<const CacheValues*>(const LightSet&)>>(const BakeData&, uint64_t&)> make;
    int settleUpdates = 1;  ///< updates until a light change has fully reached the caches
};

std::vector<Baseline> baselines(const SweepParams& params, const SweepContext& context) {
    std::vector<Baseline> list;
    const bool fine = params.grid == "fine";
    auto wants = [&](const char* name) {
        return std::find(params.baselines.begin(), params.baselines.end(), name) != params.baselines.end();
    };
    if (wants("traced")) {
        std::vector<std::pair<uint32_t, uint32_t>> levels{{16, 1}, {64, 1}, {256, 1}, {64, 4}};
        if (fine) levels = {{8, 1}, {16, 1}, {32, 1}, {64, 1}, {128, 1}, {256, 1}, {1024, 1}, {64, 4}, {256, 4}};
        for (const auto& [rays, subsets] : levels) {
            Baseline b;
            b.method = "traced_probes";
            b.key = fmt::format("traced_k{}_s{}", rays, subsets);
            b.name = subsets == 1 ? fmt::format("probes K {}", rays) : fmt::format("probes K {} 1/{}", rays, subsets);
            b.settings = {{"rays_per_cache", rays}, {"subsets", subsets}, {"hysteresis", 0.0}};
            // Each update adds one bounce (the hits read the previous update's caches); a
            // light change has reached the caches when the bounces the runtime's progressive
            // mode computes at most (8) have, every cache once per `subsets` updates.
            b.settleUpdates = 8 * int(subsets);
            b.make = [&context, rays, subsets](const BakeData& bake, uint64_t& memory)
                -> Result<std::function<Result<const CacheValues*>(const LightSet&)>> {
                TracedProbeParams p;
                p.raysPerCache = rays;
                p.subsets = subsets;
                PIC_TRY_ASSIGN(auto probes, TracedProbes::create(context.scene, *context.rays, bake, p));
                memory = probes->memoryBytes();
                std::shared_ptr<TracedProbes> shared(std::move(probes));
                return [shared](const LightSet& lights) { return shared->update(lights); };
            };
            list.push_back(std::move(b));
        }
    }
    if (wants("lpv")) {
        std::vector<uint32_t> levels{16, 32, 64};
        if (fine) levels = {8, 16, 32, 48, 64, 96};
        for (const uint32_t resolution : levels) {
            Baseline b;
            b.method = "lpv";
            b.key = fmt::format("lpv_r{}", resolution);
            b.name = fmt::format("LPV {}", resolution);
            LpvParams defaults;
            b.settings = {{"resolution", resolution}, {"iterations", defaults.iterations}, {"rsm_size", defaults.rsmSize}};
            b.make = [&context, resolution](const BakeData& bake, uint64_t& memory)
                -> Result<std::function<Result<const CacheValues*>(const LightSet&)>> {
                LpvParams p;
                p.resolution = resolution;
                PIC_TRY_ASSIGN(auto lpv, LightPropagationVolume::create(context.scene, *context.rays, bake, p));
                memory = lpv->memoryBytes();
                std::shared_ptr<LightPropagationVolume> shared(std::move(lpv));
                return [shared](const LightSet& lights) { return shared->update(lights); };
            };
            list.push_back(std::move(b));
        }
    }
    return list;
}

/// Measures a baseline on the default bake: update ms (median), the caches after it settled
/// under the sweep's lights, one change after that for the delta frame.
Result<Json> measureBaseline(const SweepContext& context, const Baseline& baseline, const BakeData& bake,
                             const std::vector<Image>& ideal) {
    uint64_t memory = 0;
    PIC_TRY_ASSIGN(auto update, baseline.make(bake, memory));
    std::vector<double> ms;
    const CacheValues* values = nullptr;
    const int updates = std::max(baseline.settleUpdates, context.params.repeat);
    for (int k = 0; k < updates; ++k) {
        const Clock::time_point start = Clock::now();
        PIC_TRY_ASSIGN(values, update(context.lights));
        ms.push_back(msSince(start));
    }
    const CacheValues settled = *values;
    PIC_TRY_ASSIGN(values, update(changedLights(context.lights, 1, context.step, "move-one")));
    PIC_TRY_ASSIGN(auto bytes, streamBytes(settled, *values));
    PIC_TRY_ASSIGN(Accuracy accuracy, measureAccuracy(context, bake, settled, &ideal));
    const double updateMs = median(ms);
    return Json{{"method", baseline.method},
                {"name", baseline.name},
                {"axis", baseline.method},
                {"key", baseline.key},
                {"settings", baseline.settings},
                {"params", paramsJson(bake)},
                {"cpu_update_ms", updateMs},
                {"gpu_update_ms", nullptr},
                {"settle_updates", baseline.settleUpdates},
                {"settle_ms", updateMs * baseline.settleUpdates},
                {"runtime_memory_bytes", memory},
                {"stream_key_bytes", bytes.first},
                {"stream_delta_bytes", bytes.second},
                {"accuracy", accuracyJson(accuracy)}};
}

/// The ideal caches as a method: path-traced probes at `samples` directions on the default
/// bake's layout; their cost is the tracing.
Result<Json> measureIdeal(const SweepContext& context, const BakeData& bake, uint32_t samples,
                          const std::vector<Image>& floorImages) {
    std::optional<CacheValues> kept;
    const CacheValues* values = nullptr;
    double probeMs = 0.0;
    PIC_TRY(idealImages(context, bake, samples, probeMs, &values, &kept));
    PIC_TRY_ASSIGN(Accuracy accuracy, measureAccuracy(context, bake, *values, &floorImages));
    ProbeParams probe;
    probe.samples = samples;
    PIC_TRY_ASSIGN(CacheValues changed, pathTraceProbes(context.scene, *context.rays, bake,
                                                        changedLights(context.lights, 1, context.step, "move-one"), probe));
    PIC_TRY_ASSIGN(auto bytes, streamBytes(*values, changed));
    return Json{{"method", "ideal"},
                {"name", fmt::format("ideal {}", samples)},
                {"axis", "ideal"},
                {"key", fmt::format("ideal_s{}", samples)},
                {"settings", {{"directions", samples}}},
                {"params", paramsJson(bake)},
                {"cpu_update_ms", probeMs},
                {"gpu_update_ms", nullptr},
                {"settle_updates", 1},
                {"settle_ms", probeMs},
                {"runtime_memory_bytes", uint64_t(values->y.size() + values->co.size() + values->cg.size()) * 4},
                {"stream_key_bytes", bytes.first},
                {"stream_delta_bytes", bytes.second},
                {"accuracy", accuracyJson(accuracy)}};
}

/// Adds to every point its indirect error against the truth: the measured error with the
/// reference's own noise taken out per view, √max(e² − n², 0) (the reference's noise and
/// the point's error are independent, so their squares add), averaged over the views.
void addErrorAgainstTruth(std::vector<Json>& points, const std::vector<ViewReference>& views) {
    for (Json& p : points)
        for (const bool indirect : {true, false}) {
            const Json& perView = p["accuracy"]["views"];
            double sum = 0.0;
            for (size_t v = 0; v < perView.size() && v < views.size(); ++v) {
                const double e = perView[v][indirect ? "indirect" : "full"]["relative_rmse"].get<double>();
                const double n = indirect ? views[v].indirectNoise : views[v].fullNoise;
                sum += std::sqrt(std::max(e * e - n * n, 0.0));
            }
            p["accuracy"][indirect ? "indirect_rmse_vs_truth" : "full_rmse_vs_truth"] =
                perView.empty() ? 0.0 : sum / double(perView.size());
        }
}

/// The component the charts hold against the truth: what the settings change (the direct
/// light of punctual lights is exact whatever the bake).
constexpr const char* kChartedComponent = "indirect";

/// The autotune check of every `picbake --target-error` point against the grid: its error
/// against the truth at most E, and its update against the cheapest grid point that meets E
/// (CPU twin ms, and links read per update, caches × nL, which no busy spell of the machine
/// moves).
Json autotuneChecks(const std::vector<Json>& points, const std::string& component) {
    Json checks = Json::array();
    const std::string key = component + "_rmse_vs_truth";
    for (const Json& t : points) {
        if (t["method"] != "target") continue;
        const double target = t["target_error"].get<double>();
        const double error = t["accuracy"][key].get<double>();
        const Json* cheapest = nullptr;
        for (const Json& p : points)
            if (p["method"] == "pic" && p["accuracy"][key].get<double>() <= target &&
                (!cheapest || p["settle_ms"].get<double>() < (*cheapest)["settle_ms"].get<double>()))
                cheapest = &p;
        auto linkReads = [](const Json& p) {
            return double(p["params"]["caches"].get<uint64_t>()) * p["params"]["links"].get<double>();
        };
        Json check{{"target_error", target},
                   {"error", error},
                   {"meets", error <= target},
                   {"chosen", t.contains("target") ? t["target"]["chosen"] : Json(nullptr)},
                   {"predicted_error", t.contains("target") ? t["target"]["predicted_error"] : Json(nullptr)},
                   {"update_ms", t["settle_ms"]},
                   {"link_reads", linkReads(t)}};
        if (cheapest) {
            check["cheapest_swept"] = {{"name", (*cheapest)["name"]},
                                       {"error", (*cheapest)["accuracy"][key]},
                                       {"update_ms", (*cheapest)["settle_ms"]},
                                       {"link_reads", linkReads(*cheapest)}};
            check["cost_ratio"] = t["settle_ms"].get<double>() / (*cheapest)["settle_ms"].get<double>();
            check["link_reads_ratio"] = linkReads(t) / linkReads(*cheapest);
            // Two timings of the same bake differ by up to a fifth on this shared machine: the
            // same settings (links read and surfels within 10 %) count as the same cost.
            const bool sameWork = check["link_reads_ratio"].get<double>() <= 1.1 &&
                                  t["params"]["surfels"].get<double>() <= 1.1 * (*cheapest)["params"]["surfels"].get<double>();
            check["within_10_percent"] = check["cost_ratio"].get<double>() <= 1.1 || sameWork;
        } else {
            check["cheapest_swept"] = nullptr;
        }
        checks.push_back(check);
    }
    return checks;
}

/// One row of the CSV per point.
void writeCsv(const std::vector<Json>& points, const fs::path& path) {
    std::ofstream out(path);
    out << "method,name,axis,surfels,links,bands_y,bands_c,link_mode,grid_cell,lightmap_texel,link_samples,"
           "visibility,caches,bake_seconds,bake_peak_memory_bytes,bake_file_bytes,cpu_update_ms,gpu_update_ms,"
           "settle_updates,settle_ms,runtime_memory_bytes,stream_key_bytes,stream_delta_bytes,indirect_rmse,"
           "indirect_rmse_vs_truth,indirect_mean_ratio,full_rmse,full_rmse_vs_truth,full_mean_ratio,blotch_index\n";
    auto field = [](const Json& json, const char* key) -> std::string {
        if (!json.contains(key) || json[key].is_null()) return "";
        const Json& v = json[key];
        if (v.is_string()) return v.get<std::string>();
        if (v.is_number_float()) return fmt::format("{:.6g}", v.get<double>());
        return v.dump();
    };
    for (const Json& p : points) {
        const Json& params = p["params"];
        const Json& a = p["accuracy"];
        std::vector<std::string> cells{
            field(p, "method"), "\"" + field(p, "name") + "\"", field(p, "axis"), field(params, "surfels"),
            field(params, "links"), field(params, "bands_y"), field(params, "bands_c"), field(params, "link_mode"),
            field(params, "grid_cell"), field(params, "lightmap_texel"), field(params, "link_samples"),
            field(p, "visibility"), field(params, "caches"), field(p, "bake_seconds"),
            field(p, "bake_peak_memory_bytes"), field(p, "bake_file_bytes"), field(p, "cpu_update_ms"),
            field(p, "gpu_update_ms"), field(p, "settle_updates"), field(p, "settle_ms"),
            field(p, "runtime_memory_bytes"), field(p, "stream_key_bytes"), field(p, "stream_delta_bytes"),
            field(a, "indirect_rmse"), field(a, "indirect_rmse_vs_truth"), field(a, "indirect_mean_ratio"), field(a, "full_rmse"),
            field(a, "full_rmse_vs_truth"), field(a, "full_mean_ratio"), field(a, "blotch_index")};
        for (size_t i = 0; i < cells.size(); ++i) out << (i ? "," : "") << cells[i];
        out << "\n";
    }
}

/// The series colour of each method.
glm::vec3 methodColor(const std::string& method) {
    if (method == "pic") return {0.12f, 0.40f, 0.80f};
    if (method == "ideal") return {0.35f, 0.35f, 0.35f};
    if (method == "traced_probes") return {0.85f, 0.45f, 0.10f};
    if (method == "target") return {0.80f, 0.10f, 0.10f};
    return {0.20f, 0.60f, 0.25f};
}

const char* methodName(const std::string& method) {
    if (method == "pic") return "pic (one bake per setting)";
    if (method == "ideal") return "ideal caches (path-traced probes)";
    if (method == "traced_probes") return "ray-traced probes at runtime";
    if (method == "target") return "picbake --target-error";
    return "light propagation volume";
}

/// One panel: indirect error against `costKey`, every method a series, the Pareto front over
/// all points drawn and labelled.
Chart costPanel(const std::vector<Json>& points, const std::string& component, const std::string& title,
                const std::string& xLabel, const std::function<std::optional<double>(const Json&)>& cost,
                double noise) {
    Chart chart;
    chart.title = title;
    chart.xLabel = xLabel;
    chart.yLabel = component + " relative RMSE against the truth";
    chart.logX = true;
    chart.logY = true;
    chart.yFromZero = false;
    std::map<std::string, ChartSeries> series;
    std::vector<glm::dvec2> all;
    std::vector<std::string> names;
    for (const Json& p : points) {
        const std::optional<double> x = cost(p);
        const double y = p["accuracy"][component + "_rmse_vs_truth"].get<double>();
        if (!x || *x <= 0.0 || !(y > 0.0)) continue;
        const std::string method = p["method"].get<std::string>();
        auto [it, inserted] = series.try_emplace(method);
        if (inserted) {
            it->second.name = methodName(method);
            it->second.color = methodColor(method);
            it->second.connected = false;
        }
        it->second.points.push_back({*x, y});
        all.push_back({*x, y});
        names.push_back(p["name"].get<std::string>());
    }
    for (auto& [method, s] : series) chart.series.push_back(std::move(s));
    const std::vector<size_t> front = paretoFront(all);
    if (!front.empty()) {
        // Labels closer than 1/16 of the log x range to the last one written would overlap.
        const double span = std::log10(all[front.back()].x / all[front.front()].x);
        double lastLabel = -1e30;
        ChartSeries line{"Pareto front (labelled)", glm::vec3(0.0f), {}, {}, false, true};
        for (size_t i : front) {
            line.points.push_back(all[i]);
            const double at = std::log10(all[i].x);
            const bool room = at - lastLabel >= span / 16.0;
            line.labels.push_back(room ? names[i] : "");
            if (room) lastLabel = at;
        }
        chart.series.push_back(std::move(line));
    }
    if (noise > 0.0 && !all.empty()) {
        double lo = all.front().x, hi = all.front().x;
        for (const glm::dvec2& p : all) lo = std::min(lo, p.x), hi = std::max(hi, p.x);
        chart.series.push_back({"reference noise (errors near it are not resolved)", glm::vec3(0.6f), {{lo, noise}, {hi, noise}}, {}, true, true});
    }
    return chart;
}

Result<void> writeSweepCharts(const std::vector<Json>& points, const SweepContext& context, const fs::path& path) {
    const std::string component = kChartedComponent;
    double noise = 0.0;
    for (const ViewReference& v : context.views)
        noise += v.indirectNoise / double(context.views.size());
    const std::string scene = fs::path(context.params.scenePath).stem().string();
    auto number = [](const Json& p, const char* key) -> std::optional<double> {
        if (!p.contains(key) || p[key].is_null()) return std::nullopt;
        return p[key].get<double>();
    };
    std::vector<Chart> panels{
        costPanel(points, component, "error against the time a light change takes to settle (CPU, 2 cores)",
                  "ms until the caches hold the change (pic: one update; probes: 8 updates per subset)",
                  [&](const Json& p) { return number(p, "settle_ms"); }, noise),
        costPanel(points, component, "error against runtime memory", "bytes the runtime holds (pic: GPU buffers)",
                  [&](const Json& p) { return number(p, "runtime_memory_bytes"); }, noise),
        costPanel(points, component, "error against stream bytes", "bytes of a key frame (zstd level 1)",
                  [&](const Json& p) { return number(p, "stream_key_bytes"); }, noise),
        costPanel(points, component, "error against the GPU backend's update (pic only)",
                  "ms per update on the GPU backend",
                  [&](const Json& p) { return number(p, "gpu_update_ms"); }, noise),
    };
    // A panel without points (no GPU) is left out rather than drawn empty.
    std::erase_if(panels, [](const Chart& c) {
        for (const ChartSeries& s : c.series)
            if (!s.dashed && !s.points.empty()) return false;
        return true;
    });
    return writeCharts(panels, fmt::format("{}: speed against accuracy", scene), path.string(), 2);
}

/// The default bake's parameters, read back from its point.
SweepDefaults defaultsOf(const BakeData& bake) {
    const BakeParams& p = bake.params;
    return {p.surfels, p.linksPerCache, p.bandsY, p.bandsC, p.gridCell, p.lightmapTexel, p.linkSamples};
}

}  // namespace

std::string SweepSetting::key() const {
    std::string key;
    for (size_t i = 0; i < bakeArgs.size(); ++i) {
        // Where the pilot keeps its measurements, the sweep's lights and views (in its
        // signature) do not tell settings apart.
        if (bakeArgs[i] == "--pilot-cache" || bakeArgs[i] == "--lights" || bakeArgs[i] == "--pilot-camera") {
            ++i;
            continue;
        }
        std::string part = bakeArgs[i];
        if (part.starts_with("--")) part = (key.empty() ? "" : "_") + part.substr(2);
        for (char& c : part)
            if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '_') c = '-';
        key += part;
    }
    if (key.empty()) key = "default";
    if (visibility != "rays") key += "_" + visibility;
    return key;
}

std::vector<std::string> mergeFlags(const std::vector<std::string>& base,
                                    const std::vector<std::string>& overrides) {
    std::vector<std::string> merged;
    for (size_t i = 0; i + 1 < base.size(); i += 2)
        if (std::find(overrides.begin(), overrides.end(), base[i]) == overrides.end())
            merged.insert(merged.end(), {base[i], base[i + 1]});
    merged.insert(merged.end(), overrides.begin(), overrides.end());
    return merged;
}

Result<std::vector<SweepSetting>> sweepGrid(const std::string& grid, const SweepDefaults& d) {
    if (grid != "coarse" && grid != "fine")
        return fail(ErrorCode::InvalidInput, "unknown sweep grid '{}': coarse or fine", grid);
    const bool fine = grid == "fine";
    std::vector<SweepSetting> settings{{"default", "default", {}, "rays"}};
    auto add = [&](const std::string& axis, const std::string& name, std::vector<std::string> args,
                   const std::string& visibility = "rays") {
        settings.push_back({name, axis, std::move(args), visibility});
    };
    auto surfels = [&](double scale) { return std::to_string(std::max<uint32_t>(256, uint32_t(std::lround(d.surfels * scale)))); };
    for (double s : fine ? std::vector<double>{0.125, 0.25, 0.5, 2.0, 4.0} : std::vector<double>{0.25, 0.5, 2.0})
        add("nS", fmt::format("nS x{}", flagNumber(s)), {"--surfels", surfels(s)});
    for (double s : fine ? std::vector<double>{0.125, 0.25, 0.5, 2.0, 4.0} : std::vector<double>{0.25, 0.5, 2.0}) {
        const uint32_t links = std::max<uint32_t>(8, uint32_t(std::lround(d.links * s)));
        add("nL", fmt::format("nL {}", links), {"--links", std::to_string(links)});
    }
    for (uint32_t bands : fine ? std::vector<uint32_t>{1, 2, 4, 5} : std::vector<uint32_t>{2, 4}) {
        if (bands == d.bandsY) continue;
        const uint32_t chroma = std::min(d.bandsC, bands);
        add("lY", fmt::format("lY {}", bands), {"--bands", std::to_string(bands), "--chroma-bands", std::to_string(chroma)});
    }
    for (uint32_t bands : fine ? std::vector<uint32_t>{1, 3} : std::vector<uint32_t>{1, 3}) {
        if (bands == d.bandsC || bands > d.bandsY) continue;
        add("lC", fmt::format("lC {}", bands), {"--chroma-bands", std::to_string(bands)});
    }
    add("link form", "SH links", {"--link-mode", "sh"});
    for (double s : fine ? std::vector<double>{4.0, 2.0, 0.5} : std::vector<double>{2.0, 0.5})
        add("grid cell", fmt::format("grid cell x{}", flagNumber(s)), {"--grid-cell", flagNumber(d.gridCell * s)});
    for (double s : fine ? std::vector<double>{4.0, 2.0, 0.5} : std::vector<double>{2.0, 0.5})
        add("texel", fmt::format("texel x{}", flagNumber(s)), {"--lightmap-texel", flagNumber(d.lightmapTexel * s)});
    for (uint32_t samples : fine ? std::vector<uint32_t>{2, 4, 8, 32, 64} : std::vector<uint32_t>{4, 64})
        if (samples != d.linkSamples)
            add("link samples", fmt::format("link samples {}", samples), {"--link-samples", std::to_string(samples)});
    add("visibility", "shadow maps", {}, "shadow-maps");
    // The diagonal: every parameter a step cheaper (or dearer) at once, where the front's ends
    // lie when no single parameter dominates the cost.
    auto diagonal = [&](const std::string& name, double scale, uint32_t bandsY, uint32_t bandsC, uint32_t samples) {
        add("diagonal", name,
            {"--surfels", surfels(scale), "--links", std::to_string(std::max<uint32_t>(8, uint32_t(std::lround(d.links * scale)))),
             "--bands", std::to_string(bandsY), "--chroma-bands", std::to_string(std::min(bandsC, bandsY)),
             "--grid-cell", flagNumber(d.gridCell / std::sqrt(scale)), "--lightmap-texel",
             flagNumber(d.lightmapTexel / std::sqrt(scale)), "--link-samples", std::to_string(samples)});
    };
    // lY stays: 2 bands lose the l = 2 band of the irradiance, which no other saving offsets,
    // and the lY axis charts it alone.
    diagonal("cheapest", 0.25, d.bandsY, 1, 4);
    diagonal("cheap", 0.5, d.bandsY, 1, 8);
    if (fine) diagonal("dearer", 2.0, d.bandsY + 1, d.bandsC + 1, 32);
    return settings;
}

int runSweepBenchmark(const SweepParams& params) {
    auto inputs = loadBenchInputs(params.scenePath, params.lightsPath);
    if (!inputs) return 2;
    SweepContext context{params, inputs->scene, inputs->lights, inputs->rays.get(), {}, {}};
    context.step = 0.01f * glm::length(context.scene.bounds.extent());
    context.dir = params.outDir.empty() ? fs::path("out") / "sweep" / fs::path(params.scenePath).stem() : fs::path(params.outDir);
    std::error_code ec;
    for (const char* sub : {"points", "bakes", "logs"}) fs::create_directories(context.dir / sub, ec);
    if (ec) return reportError(Error{ErrorCode::Io, fmt::format("cannot create {}: {}", context.dir.string(), ec.message())});

    // Refuse a folder that holds figures of other inputs: mixing them would chart nonsense.
    const Json signature = inputsSignature(context);
    const fs::path signaturePath = context.dir / "inputs.json";
    if (auto existing = readJson(signaturePath); existing && *existing != signature)
        return reportError(Error{ErrorCode::InvalidInput,
                                 fmt::format("{} holds a sweep of other inputs ({}); give another --out-dir or "
                                             "delete it",
                                             context.dir.string(), existing->dump())});
    if (auto written = writeJsonAtomically(signature, signaturePath); !written) return reportError(written.error());
    if (auto references = loadOrTraceReferences(context); !references) return reportError(references.error());

    // The default bake first: the grid scales its parameters, the baselines use its caches.
    std::vector<Json> points;
    auto runPoint = [&](const std::string& key, size_t index, size_t total, const std::string& name,
                        const std::function<Result<Json>()>& measure) -> Result<void> {
        const fs::path path = context.dir / "points" / (key + ".json");
        if (auto done = readJson(path)) {
            std::fprintf(stderr, "picbench sweep: [%zu/%zu] %s: measured already\n", index, total, name.c_str());
            points.push_back(std::move(*done));
            return {};
        }
        std::fprintf(stderr, "picbench sweep: [%zu/%zu] %s …\n", index, total, name.c_str());
        PIC_TRY_ASSIGN(Json point, measure());
        PIC_TRY(writeJsonAtomically(point, path));
        const Json& a = point["accuracy"];
        std::fprintf(stderr, "picbench sweep:   indirect RMSE %.4f, mean ratio %.3f, %.1f ms to settle\n",
                     a["indirect_rmse"].get<double>(), a["indirect_mean_ratio"].get<double>(),
                     point["settle_ms"].get<double>());
        points.push_back(std::move(point));
        return {};
    };

    const SweepSetting defaultSetting{"default", "default", {}, "rays"};
    const fs::path defaultBake = context.dir / "bakes" / (defaultSetting.key() + ".pic");
    if (auto ok = runPoint(defaultSetting.key(), 1, 1, "default", [&] { return measureSetting(context, defaultSetting, true); }); !ok)
        return reportError(ok.error());
    if (!fs::exists(defaultBake)) {
        // Measured in an earlier run whose bake is gone: bake it again for the grid and the baselines.
        if (auto baked = bakeSetting(context, defaultSetting, defaultBake); !baked) return reportError(baked.error());
    }
    auto bake = readBakeFile(defaultBake.string());
    if (!bake) return reportError(bake.error());
    auto grid = sweepGrid(params.grid, defaultsOf(*bake));
    if (!grid) return reportError(grid.error());
    std::vector<SweepSetting> settings(grid->begin() + 1, grid->end());
    if (params.maxPoints > 0 && settings.size() + 1 > params.maxPoints) settings.resize(params.maxPoints - 1);
    const std::vector<Baseline> others = baselines(params, context);
    const bool ideal = std::find(params.baselines.begin(), params.baselines.end(), "ideal") != params.baselines.end();
    const size_t total = 1 + settings.size() + others.size() + (ideal ? 2 : 0);
    for (size_t i = 0; i < settings.size(); ++i) {
        const SweepSetting& setting = settings[i];
        if (auto ok = runPoint(setting.key(), i + 2, total, setting.name, [&] { return measureSetting(context, setting, false); }); !ok)
            return reportError(ok.error());
    }
    double floorMs = 0.0;
    auto floorImages = idealImages(context, *bake, params.probeSamples, floorMs);
    if (!floorImages) return reportError(floorImages.error());
    size_t index = 2 + settings.size();
    if (ideal)
        for (const uint32_t samples : {std::max(params.probeSamples / 4, 1u), params.probeSamples}) {
            if (auto ok = runPoint(fmt::format("ideal_s{}", samples), index++, total, fmt::format("ideal caches, {} directions", samples),
                                   [&] { return measureIdeal(context, *bake, samples, *floorImages); });
                !ok)
                return reportError(ok.error());
        }
    for (const Baseline& baseline : others)
        if (auto ok = runPoint(baseline.key, index++, total, baseline.name,
                               [&] { return measureBaseline(context, baseline, *bake, *floorImages); });
            !ok)
            return reportError(ok.error());
    for (const double target : params.targetErrors) {
        // The pilot measures as the sweep does (image size, reference samples, lights, views:
        // what a user who knows their review's viewpoints gives it) and keeps its
        // measurements in the sweep's folder for the next target. How it does from views of
        // its own is for scenes outside the sweep to show.
        SweepSetting setting{fmt::format("target {}", flagNumber(target)), "target",
                             {"--target-error", flagNumber(target), "--pilot-size",
                              fmt::format("{}x{}", params.view.size.x, params.view.size.y), "--pilot-spp",
                              std::to_string(params.spp), "--pilot-cache", (context.dir / "pilot").string()},
                             "rays"};
        if (!params.lightsPath.empty()) setting.bakeArgs.insert(setting.bakeArgs.end(), {"--lights", params.lightsPath});
        for (const ViewReference& view : context.views) {
            const Camera& v = view.camera;
            setting.bakeArgs.insert(setting.bakeArgs.end(),
                                    {"--pilot-camera", fmt::format("{},{},{},{},{},{},{},{},{},{}", v.eye.x, v.eye.y, v.eye.z,
                                                                   v.target.x, v.target.y, v.target.z, v.up.x, v.up.y,
                                                                   v.up.z, v.fovyDegrees)});
        }
        if (auto ok = runPoint(setting.key(), index++, total + params.targetErrors.size(), setting.name,
                               [&]() -> Result<Json> {
                                   PIC_TRY_ASSIGN(Json point, measureSetting(context, setting, false));
                                   point["method"] = "target";
                                   point["target_error"] = target;
                                   return point;
                               });
            !ok)
            return reportError(ok.error());
    }

    // The whole sweep: JSON, CSV and the charts.
    Json json;
    json["inputs"] = signature;
    json["grid"] = params.grid;
    const std::string component = kChartedComponent;
    json["charted_component"] = component;
    Json noise = Json::array();
    for (const ViewReference& v : context.views) noise.push_back({{"indirect", v.indirectNoise}, {"full", v.fullNoise}});
    json["reference_noise"] = noise;
    addErrorAgainstTruth(points, context.views);
    json["points"] = points;
    const Json checks = autotuneChecks(points, component);
    if (!checks.empty()) json["autotune"] = checks;
    const fs::path jsonPath = context.dir / "sweep.json";
    if (auto written = writeJsonAtomically(json, jsonPath); !written) return reportError(written.error());
    writeCsv(points, context.dir / "sweep.csv");
    const fs::path chartPath = context.dir / "sweep.png";
    if (auto charted = writeSweepCharts(points, context, chartPath); !charted) return reportError(charted.error());

    std::printf("%-26s %8s %10s %10s %10s %9s %9s %9s %9s   (%s vs truth: the charts' error)\n", "point",
                "caches", "settle ms", "GPU ms", "memory", "key B", "indirect", "vs truth", "ratio",
                component.c_str());
    for (const Json& p : points) {
        const Json& a = p["accuracy"];
        std::printf("%-26s %8d %10.1f %10s %10.3g %9d %9.4f %9.4f %9.3f\n", p["name"].get<std::string>().c_str(),
                    p["params"]["caches"].get<int>(), p["settle_ms"].get<double>(),
                    p["gpu_update_ms"].is_null() ? "-" : fmt::format("{:.1f}", p["gpu_update_ms"].get<double>()).c_str(),
                    double(p["runtime_memory_bytes"].get<uint64_t>()), p["stream_key_bytes"].get<int>(),
                    a["indirect_rmse"].get<double>(), a[component + "_rmse_vs_truth"].get<double>(),
                    a[component + "_mean_ratio"].get<double>());
    }
    std::printf("reference noise (%s, relative RMSE of the reference itself): %.4f\n", component.c_str(),
                noise.empty() ? 0.0 : noise[0][component].get<double>());
    for (const Json& c : checks) {
        const bool swept = !c["cheapest_swept"].is_null();
        std::printf("--target-error %g: chose '%s' (predicted %.4f); %s error against the truth %.4f: %s; %.1f ms "
                    "per update%s\n",
                    c["target_error"].get<double>(), c["chosen"].is_null() ? "?" : c["chosen"].get<std::string>().c_str(),
                    c["predicted_error"].is_null() ? 0.0 : c["predicted_error"].get<double>(), component.c_str(),
                    c["error"].get<double>(), c["meets"].get<bool>() ? "meets it" : "MISSES it", c["update_ms"].get<double>(),
                    swept ? fmt::format(", {:.2f} x the cheapest swept point that meets it ('{}', {:.1f} ms; link reads "
                                        "{:.2f} x): {}",
                                        c["cost_ratio"].get<double>(), c["cheapest_swept"]["name"].get<std::string>(),
                                        c["cheapest_swept"]["update_ms"].get<double>(), c["link_reads_ratio"].get<double>(),
                                        c["within_10_percent"].get<bool>() ? "within 10 %" : "NOT within 10 %")
                                .c_str()
                          : "; no swept point meets it");
    }
    std::printf("wrote %s, %s, %s\n", jsonPath.c_str(), (context.dir / "sweep.csv").c_str(), chartPath.c_str());
    return 0;
}

}  // namespace pic
