#include "bench/runtime_benchmark.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <span>

#include <nlohmann/json.hpp>

#include "bench/bench_common.h"
#include "render/copy_probe.h"
#include "render/cpu/pull.h"
#include "render/cpu/surfel_lighting.h"
#include "render/cpu_runtime.h"
#include "render/gpu_runtime.h"

namespace pic {
namespace {

using Clock = std::chrono::steady_clock;

/// This machine's memcpy bandwidth in bytes/s (median of 7 copies of 256 MiB, after a
/// warm-up copy that also faults the pages in).
double memcpyBandwidth() {
    const size_t bytes = size_t{256} << 20;
    std::vector<char> src(bytes, 1), dst(bytes, 0);
    std::memcpy(dst.data(), src.data(), bytes);
    std::vector<double> rates;
    for (int i = 0; i < 7; ++i) {
        const Clock::time_point start = Clock::now();
        std::memcpy(dst.data(), src.data(), bytes);
        const double s = std::chrono::duration<double>(Clock::now() - start).count();
        rates.push_back(double(bytes) / s);
        src[i] = dst[bytes - 1 - i];  // keep the copies observable
    }
    return median(rates);
}

/// The floor a pass that reads every link once per update is compared with, in bytes copied
/// per second: memcpy on a CPU device (lavapipe's memory is the host's), else a compute
/// shader's copy of one 256 MiB device buffer into another (gpu::computeCopyBandwidth).
/// A GPU's vkCmdCopyBuffer may run on a copy engine far slower than its shaders' path to
/// memory (an H100: 424 GB/s), so it is no floor for a compute pass.
struct MemoryFloor {
    double bytesPerSecond = 0.0;
    bool deviceCopy = false;  ///< measured on the GPU (its timestamps are then honest too)
    std::string device;
};

Result<MemoryFloor> memoryFloor(const std::string& deviceName) {
    PIC_TRY_ASSIGN(auto context, gpu::Context::create({deviceName}));
    MemoryFloor floor{.device = context->deviceName()};
    if (context->isCpuDevice()) {
        floor.bytesPerSecond = memcpyBandwidth();
    } else {
        PIC_TRY_ASSIGN(floor.bytesPerSecond, gpu::computeCopyBandwidth(*context));
        floor.deviceCopy = true;
    }
    return floor;
}

struct BackendFigures {
    std::vector<double> totalMs;
    std::vector<double> cacheLightingWallMs;  ///< GPU: one cache-lighting pass, wall clock
    std::map<std::string, std::vector<double>> passMs;  ///< per update
    int bounces = 0;
    uint64_t shadowTriangles = 0;  ///< GPU: triangles rasterised per update, after culling
    uint64_t shadowTexels = 0;     ///< GPU: texels of the layers rendered per update
    int lightsTraced = 0;          ///< GPU, rays: lights whose rays each update traced
};

/// Times `repeat` updates of each runtime in `runtimes`, each a light change as a renderer
/// beside the runtime sees it: setLights, then textures() (the light-map copy: the CPU twin,
/// and the GPU runtime copying on the host, copy the caches here; on the device, the GPU
/// runtime records the copy in setLights and reads the layers back here). picserver's relight
/// is setLights alone: it streams the caches. The runtimes take turns,
/// update by update, so that a busy spell of a shared machine slows both and their ratio
/// holds.
Result<std::vector<BackendFigures>> timeBackends(std::span<Runtime* const> runtimes,
                                                 const LightSet& base, int repeat, float step,
                                                 const std::string& change) {
    std::vector<BackendFigures> figures(runtimes.size());
    UpdateStats stats;
    for (Runtime* runtime : runtimes) {  // warm-up
        PIC_TRY(runtime->setLights(changedLights(base, 0, step, change), &stats));
        PIC_TRY(runtime->textures());
    }
    const auto msSince = [](Clock::time_point t) {
        return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
    };
    for (int k = 1; k <= repeat; ++k) {
        for (size_t r = 0; r < runtimes.size(); ++r) {
            const Clock::time_point start = Clock::now();
            PIC_TRY(runtimes[r]->setLights(changedLights(base, k, step, change), &stats));
            const Clock::time_point texturesStart = Clock::now();
            PIC_TRY(runtimes[r]->textures());
            stats.passMs["textures"] = msSince(texturesStart);
            BackendFigures& f = figures[r];
            f.totalMs.push_back(msSince(start));
            for (const auto& [pass, ms] : stats.passMs) f.passMs[pass].push_back(ms);
            f.bounces = stats.bounces;
            f.shadowTriangles = stats.shadowTriangles;
            f.shadowTexels = stats.shadowTexels;
            f.lightsTraced = stats.lightsTraced;
        }
    }
    return figures;
}

/// Wall-clock ms of `repeat` calls of `pass`, after one to warm up.
Result<std::vector<double>> timeRepeated(int repeat, const std::function<Result<void>()>& pass) {
    PIC_TRY(pass());
    std::vector<double> ms;
    for (int k = 0; k < repeat; ++k) {
        const Clock::time_point start = Clock::now();
        PIC_TRY(pass());
        ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - start).count());
    }
    return ms;
}

/// Wall-clock ms of the GPU cache-lighting pass alone, from the CPU twin's node flux of
/// `lights` (packed once; its upload and the read-back of the caches included). Lavapipe's
/// timestamps were once seen not to wait for a dispatch to finish (README: they agree with
/// this since), and this does not depend on them; a GPU's timestamps are honest, and its
/// submissions cost more than the pass.
Result<std::vector<double>> timeCacheLighting(GpuRuntime& gpu, const Scene& scene,
                                              const EmbreeScene& rays, const BakeData& bake,
                                              const LightSet& lights, int repeat) {
    std::vector<glm::vec3> nodeFlux(bake.nodes.size());
    directSurfelFlux(scene, rays, bake, lights,
                     std::span<glm::vec3>(nodeFlux.data(), bake.surfels.size()));
    pullFlux(bake, nodeFlux);
    const std::vector<glm::uvec4> light = packNodeLight(bake, nodeFlux);
    return timeRepeated(repeat, [&]() -> Result<void> {
        PIC_TRY(gpu.runCacheLighting(std::span<const glm::uvec4>(light)));
        return {};
    });
}

/// Wall-clock ms of the GPU pull alone (upload of the leaves and read-back of every node
/// included), for the same reason.
Result<std::vector<double>> timePull(GpuRuntime& gpu, const Scene& scene, const EmbreeScene& rays,
                                     const BakeData& bake, const LightSet& lights, int repeat) {
    std::vector<glm::vec3> leaves(bake.surfels.size());
    directSurfelFlux(scene, rays, bake, lights, leaves);
    return timeRepeated(repeat, [&]() -> Result<void> {
        PIC_TRY(gpu.runPull(leaves));
        return {};
    });
}

nlohmann::ordered_json figuresJson(const BackendFigures& f) {
    nlohmann::ordered_json json;
    json["update_ms_median"] = median(f.totalMs);
    json["update_ms"] = f.totalMs;
    json["bounces"] = f.bounces;
    json["shadow_triangles"] = f.shadowTriangles;
    json["shadow_texels"] = f.shadowTexels;
    json["lights_traced"] = f.lightsTraced;
    json["pass_ms_median"] = nlohmann::ordered_json::object();
    for (const auto& [pass, ms] : f.passMs) json["pass_ms_median"][pass] = median(ms);
    return json;
}

/// GPU/CPU ratio of every run against the CPU twin's update time: a scatter per visibility
/// source and link form, and the goal (ratio 1) dashed.
Chart ratioChart(const nlohmann::ordered_json& json) {
    struct Kind {
        const char* visibility;
        const char* linkMode;
        const char* name;
        glm::vec3 color;
    };
    const Kind kinds[] = {
        {"rays", "rtp", "host rays, RTP links", {0.15f, 0.55f, 0.25f}},
        {"rays", "sh", "host rays, SH links", {0.55f, 0.8f, 0.3f}},
        {"shadow-maps", "rtp", "shadow maps, RTP links", {0.85f, 0.4f, 0.1f}},
        {"shadow-maps", "sh", "shadow maps, SH links", {0.95f, 0.7f, 0.2f}},
    };
    Chart chart;
    chart.title = fmt::format("GPU backend against the CPU twin ({})",
                              json["runs"].empty() ? std::string("no runs")
                                                   : json["runs"][0]["device"].get<std::string>());
    chart.xLabel = "CPU twin ms per update (median)";
    chart.yLabel = "GPU ms / CPU twin ms";
    chart.logX = true;
    double lowest = std::numeric_limits<double>::max(), highest = 0.0;
    for (const Kind& kind : kinds) {
        ChartSeries series{kind.name, kind.color};
        series.connected = false;
        for (const auto& run : json["runs"]) {
            if (run["direct_visibility"] != kind.visibility || run["link_mode"] != kind.linkMode)
                continue;
            const double cpuMs = run["cpu"]["update_ms_median"].get<double>();
            series.points.push_back({cpuMs, run["gpu_over_cpu"].get<double>()});
            lowest = std::min(lowest, cpuMs);
            highest = std::max(highest, cpuMs);
        }
        if (!series.points.empty()) chart.series.push_back(std::move(series));
    }
    if (highest > 0.0) {
        ChartSeries goal{"goal: GPU/CPU <= 1", glm::vec3(0.3f)};
        goal.dashed = true;
        goal.points = {{lowest, 1.0}, {highest, 1.0}};
        chart.series.push_back(std::move(goal));
    }
    return chart;
}

}  // namespace

int runRuntimeBenchmark(const RuntimeBenchmarkParams& params) {
    auto inputs = loadBenchInputs(params.scenePath, params.lightsPath);
    if (!inputs) return 2;
    const Scene& scene = inputs->scene;
    const float step = 1e-3f * scene.bounds.diagonal();
    auto floor = memoryFloor(params.device);
    if (!floor) return reportError(floor.error());
    const double bandwidth = floor->bytesPerSecond;
    const char* floorName = floor->deviceCopy ? "shader copy" : "memcpy";
    std::printf("%s bandwidth on %s: %.2f GB/s\n", floorName, floor->device.c_str(), bandwidth * 1e-9);

    nlohmann::ordered_json json;
    json["scene"] = params.scenePath;
    json["triangles"] = scene.triangles.size();
    json["floor"] = floorName;
    json["floor_bytes_per_second"] = bandwidth;
    json["runs"] = nlohmann::ordered_json::array();
    std::printf("%-9s %-4s %-7s %-8s %-5s %6s %9s %9s %6s %9s %8s %8s %9s %9s %9s %8s\n", "setting",
                "link", "bounces", "change", "vis", "nC", "cpu ms", "gpu ms", "ratio", "vis ms",
                "k tris", "M texels", "surfels", "pull*", "caches*", "bw ratio");
    for (const std::string& setting : params.settings) {
        for (const std::string& linkMode : params.linkModes) {
            BakeReport bakeReport;
            std::fprintf(stderr, "picbench: baking %s %s …\n", setting.c_str(), linkMode.c_str());
            auto bake = runBake(scene, settingOptions(setting, linkMode, params.chromaBands), bakeReport);
            if (!bake) return reportError(bake.error());
            for (int bounces : params.bounces) {
                const BounceParams bounceParams{bounces};
                auto cpu = createCpuRuntime(scene, *inputs->rays, *bake, bounceParams);
                if (!cpu) return reportError(cpu.error());
                for (const std::string& visibility : params.visibilities) {
                    GpuRuntimeOptions options;
                    options.deviceName = params.device;
                    options.shadowMapSize = params.shadowMapSize;
                    options.shadowEqualFootprint = params.shadowEqualFootprint;
                    auto parsed = gpu::parseDirectVisibility(visibility);
                    if (!parsed) return reportError(parsed.error());
                    options.directVisibility = *parsed;
                    if (params.lightmapCopy != "auto")
                        options.lightmapCopyOnHost = params.lightmapCopy == "host";
                    auto gpu =
                        GpuRuntime::create(scene, *inputs->rays, *bake, bounceParams, options);
                    if (!gpu) return reportError(gpu.error());
                    const bool rays = (*gpu)->directVisibility() == gpu::DirectVisibility::Rays;
                    auto cacheWall = timeCacheLighting(**gpu, scene, *inputs->rays, *bake,
                                                       inputs->lights, params.repeat);
                    if (!cacheWall) return reportError(cacheWall.error());
                    const double cacheWallMs = median(*cacheWall);
                    auto pullWall = timePull(**gpu, scene, *inputs->rays, *bake, inputs->lights,
                                             params.repeat);
                    if (!pullWall) return reportError(pullWall.error());
                    const double pullWallMs = median(*pullWall);
                    const double linkBytes = double((*gpu)->linkBytesPerBounce());
                    for (const std::string& change : params.changes) {
                        const std::array<Runtime*, 2> runtimes{cpu->get(), gpu->get()};
                        auto figures =
                            timeBackends(runtimes, inputs->lights, params.repeat, step, change);
                        if (!figures) return reportError(figures.error());
                        const BackendFigures& cpuFigures = (*figures)[0];
                        const BackendFigures& gpuFigures = (*figures)[1];
                        const auto passMedian = [&](const BackendFigures& f, const char* pass) {
                            auto it = f.passMs.find(pass);
                            return it == f.passMs.end() ? 0.0 : median(it->second);
                        };
                        const double cpuMs = median(cpuFigures.totalMs),
                                     gpuMs = median(gpuFigures.totalMs);
                        // Link bytes per second of one cache-lighting pass: every link is read
                        // once per bounce. Timestamps where they are honest, else wall clock.
                        const double cacheMs = floor->deviceCopy
                                                   ? passMedian(gpuFigures, "cache_lighting") /
                                                         std::max(gpuFigures.bounces, 1)
                                                   : cacheWallMs;
                        const double linkRate = cacheMs > 0.0 ? linkBytes / (cacheMs * 1e-3) : 0.0;
                        std::printf(
                            "%-9s %-4s %-7d %-8s %-5s %6zu %9.1f %9.1f %6.2f %9.1f %8.0f %8.2f "
                            "%9.1f %9.1f %9.1f %8.2f\n",
                            setting.c_str(), linkMode.c_str(), gpuFigures.bounces, change.c_str(),
                            rays ? "rays" : "maps", bake->caches.size(), cpuMs, gpuMs,
                            gpuMs / cpuMs,
                            passMedian(gpuFigures, rays ? "visibility_rays" : "shadow_maps"),
                            double(gpuFigures.shadowTriangles) * 1e-3,
                            double(gpuFigures.shadowTexels) * 1e-6,
                            passMedian(gpuFigures, "surfel_lighting"),
                            floor->deviceCopy ? passMedian(gpuFigures, "pull") : pullWallMs,
                            cacheMs, linkRate / bandwidth);

                        nlohmann::ordered_json run;
                        run["setting"] = setting;
                        run["link_mode"] = linkMode;
                        run["bounces_requested"] = bounces;
                        run["change"] = change;
                        run["surfels"] = bake->surfels.size();
                        run["caches"] = bake->caches.size();
                        run["links_per_cache"] = bake->links.linksPerCache;
                        run["bands"] = {{"y", bake->params.bandsY}, {"c", bake->params.bandsC}};
                        run["device"] = (*gpu)->context().deviceName();
                        run["direct_visibility"] =
                            gpu::directVisibilityName((*gpu)->directVisibility());
                        if (!rays) {
                            run["shadow_map_size"] = params.shadowMapSize;
                            run["shadow_sides"] =
                                params.shadowEqualFootprint ? "footprint" : "uniform";
                        }
                        run["cpu"] = figuresJson(cpuFigures);
                        run["gpu"] = figuresJson(gpuFigures);
                        run["gpu_over_cpu"] = gpuMs / cpuMs;
                        run["cache_lighting_wall_ms_median"] = cacheWallMs;
                        run["pull_wall_ms_median"] = pullWallMs;
                        run["cache_lighting_ms"] = cacheMs;
                        run["cache_lighting_timing"] =
                            floor->deviceCopy ? "timestamps" : "wall clock";
                        run["link_bytes_per_bounce"] = linkBytes;
                        run["link_texel_words"] = (*gpu)->linkTexelWords();
                        run["lightmap_copy"] = (*gpu)->lightmapCopyOnHost() ? "host" : "device";
                        run["cache_lighting_bytes_per_second"] = linkRate;
                        run["bandwidth_ratio"] = linkRate / bandwidth;
                        run["gpu_memory_bytes"] = nlohmann::ordered_json::object();
                        for (const auto& [buffer, bytes] : (*gpu)->memory())
                            run["gpu_memory_bytes"][buffer] = bytes;
                        json["runs"].push_back(run);
                    }
                }
            }
        }
    }
    std::printf(
        "ms: medians per update; vis: the direct light's visibility, shadow maps (GPU\n"
        "timestamps) or rays traced on the host (wall clock); surfels from GPU timestamps;\n"
        "pull* and caches*: one pull and one cache-lighting pass, %s; bw ratio: the\n"
        "latter's link bytes per second over %s\n",
        floor->deviceCopy ? "by timestamps"
                          : "by wall clock with their uploads and read-backs",
        floorName);
    if (int exit = writeJson(json, params.jsonPath); exit != 0) return exit;
    return writeChartFile(ratioChart(json), chartPathFor(params.jsonPath));
}

int runShadowBenchmark(const ShadowBenchmarkParams& params) {
    auto inputs = loadBenchInputs(params.scenePath, params.lightsPath);
    if (!inputs) return 2;
    const Scene& scene = inputs->scene;
    const float step = 1e-3f * scene.bounds.diagonal();
    BakeReport bakeReport;
    std::fprintf(stderr, "picbench: baking %s rtp …\n", params.setting.c_str());
    auto bake = runBake(scene, settingOptions(params.setting, "rtp"), bakeReport);
    if (!bake) return reportError(bake.error());
    const size_t nS = bake->surfels.size();

    nlohmann::ordered_json json;
    json["scene"] = params.scenePath;
    json["triangles"] = scene.triangles.size();
    json["setting"] = params.setting;
    json["surfels"] = nS;
    json["runs"] = nlohmann::ordered_json::array();
    std::printf("%-6s %-9s %9s %10s %10s %10s %12s %12s\n", "size", "sides", "M texels", "gpu ms",
                "cpu ms", "gpu/cpu", "rel L1", "surfels >1%");
    // Wall-clock ms of the GPU's direct light (every light's visibility and surfel lighting,
    // read-back included) against the CPU twin's rays, and how far its flux is from theirs.
    const auto measure = [&](const GpuRuntimeOptions& options) -> Result<nlohmann::ordered_json> {
        PIC_TRY_ASSIGN(auto gpu,
                       GpuRuntime::create(scene, *inputs->rays, *bake, BounceParams{1}, options));
        std::vector<double> gpuMs, cpuMs;
        double l1 = 0.0, norm = 0.0;
        size_t differing = 0, compared = 0;
        uint64_t texels = 0;
        for (int k = 0; k <= params.repeat; ++k) {  // k = 0 warms up
            // Every light moves, so every shadow map is rendered (every light traced) each time.
            const LightSet lights = changedLights(inputs->lights, k, step, "move-all");
            UpdateStats stats;
            Clock::time_point start = Clock::now();
            PIC_TRY_ASSIGN(std::vector<glm::vec3> direct, gpu->runDirect(lights, &stats));
            const double g =
                std::chrono::duration<double, std::milli>(Clock::now() - start).count();
            texels = stats.shadowTexels;
            std::vector<glm::vec3> rays(nS);
            start = Clock::now();
            directSurfelFlux(scene, *inputs->rays, *bake, lights, rays);
            const double c =
                std::chrono::duration<double, std::milli>(Clock::now() - start).count();
            if (k == 0) continue;
            gpuMs.push_back(g);
            cpuMs.push_back(c);
            float brightest = 0.0f;
            for (const glm::vec3& f : rays) brightest = std::max({brightest, f.r, f.g, f.b});
            for (size_t i = 0; i < nS; ++i) {
                bool differs = false;
                for (int ch = 0; ch < 3; ++ch) {
                    const double d = std::abs(double(direct[i][ch]) - double(rays[i][ch]));
                    l1 += d;
                    norm += std::abs(double(rays[i][ch]));
                    differs |=
                        d > 0.01 * std::max(std::abs(rays[i][ch]), std::abs(direct[i][ch])) &&
                        d > 1e-6 * brightest;
                }
                differing += differs;
            }
            compared += nS;
        }
        nlohmann::ordered_json row;
        row["direct_visibility"] = gpu::directVisibilityName(gpu->directVisibility());
        row["texels"] = texels;
        row["device"] = gpu->context().deviceName();
        row["gpu_direct_ms_median"] = median(gpuMs);
        row["cpu_direct_ms_median"] = median(cpuMs);
        row["gpu_direct_ms"] = gpuMs;
        row["relative_l1"] = norm > 0.0 ? l1 / norm : 0.0;
        row["fraction_surfels_differing"] = compared ? double(differing) / double(compared) : 0.0;
        return row;
    };
    const auto printRow = [](const nlohmann::ordered_json& row, const std::string& size,
                             const std::string& sides) {
        const double gpuMs = row["gpu_direct_ms_median"], cpuMs = row["cpu_direct_ms_median"];
        std::printf("%-6s %-9s %9.2f %10.1f %10.1f %10.2f %11.2f%% %11.2f%%\n", size.c_str(),
                    sides.c_str(), double(row["texels"].get<uint64_t>()) * 1e-6, gpuMs, cpuMs,
                    gpuMs / cpuMs, 100.0 * row["relative_l1"].get<double>(),
                    100.0 * row["fraction_surfels_differing"].get<double>());
    };

    std::vector<ChartSeries> series;
    for (const std::string& sides : params.sides) {
        const bool footprint = sides == "footprint";
        ChartSeries tradeoff{fmt::format("relative L1, {} sides", sides),
                             footprint ? glm::vec3(0.85f, 0.35f, 0.1f) : glm::vec3(0.12f, 0.35f, 0.75f)};
        ChartSeries differingSeries{fmt::format("surfels > 1 % off, {} sides", sides),
                                    footprint ? glm::vec3(0.9f, 0.65f, 0.2f) : glm::vec3(0.35f, 0.6f, 0.9f),
                                    {}, {}, true};
        for (uint32_t size : params.sizes) {
            GpuRuntimeOptions options;
            options.deviceName = params.device;
            options.shadowMapSize = size;
            options.shadowEqualFootprint = footprint;
            options.directVisibility = gpu::DirectVisibility::ShadowMaps;
            auto row = measure(options);
            if (!row) return reportError(row.error());
            printRow(*row, std::to_string(size), sides);
            (*row)["size"] = size;
            (*row)["sides"] = sides;
            tradeoff.points.push_back({(*row)["gpu_direct_ms_median"].get<double>(),
                                       100.0 * (*row)["relative_l1"].get<double>()});
            tradeoff.labels.push_back(fmt::format("{0}x{0}", size));
            differingSeries.points.push_back(
                {(*row)["gpu_direct_ms_median"].get<double>(),
                 100.0 * (*row)["fraction_surfels_differing"].get<double>()});
            json["runs"].push_back(std::move(*row));
        }
        series.push_back(tradeoff);
        series.push_back(differingSeries);
    }
    // The other end of the trade-off: the CPU twin's own rays, traced for the GPU's surfel
    // lighting (DirectVisibility::Rays), exact by construction.
    GpuRuntimeOptions rayOptions;
    rayOptions.deviceName = params.device;
    rayOptions.directVisibility = gpu::DirectVisibility::Rays;
    auto rayRow = measure(rayOptions);
    if (!rayRow) return reportError(rayRow.error());
    printRow(*rayRow, "-", "rays");
    series.push_back(ChartSeries{"host rays (exact)",
                                 glm::vec3(0.2f, 0.6f, 0.3f),
                                 {{(*rayRow)["gpu_direct_ms_median"].get<double>(),
                                   100.0 * (*rayRow)["relative_l1"].get<double>()}},
                                 {"rays"}});
    json["runs"].push_back(std::move(*rayRow));
    std::printf(
        "gpu: shadow maps of every light (rays: every light's rays, traced on the host) +\n"
        "direct surfel lighting (wall clock, read-back included); cpu: the twin's rays;\n"
        "errors: GPU direct surfel flux against the rays;\n"
        "sides: uniform, every layer size²; footprint, perspective layers only as wide as\n"
        "give an orthographic layer's texel at the median distance of the lit surfaces\n");
    Chart chart;
    chart.title = fmt::format("Shadow-map size: time against error ({} rtp, {})", params.setting,
                              json["runs"].empty() ? std::string("no device")
                                                   : json["runs"][0]["device"].get<std::string>());
    chart.xLabel = "GPU visibility + direct surfel lighting, ms (median)";
    chart.yLabel = "% of the direct surfel flux against the CPU twin's rays";
    chart.series = std::move(series);
    if (int exit = writeJson(json, params.jsonPath); exit != 0) return exit;
    return writeChartFile(chart, chartPathFor(params.jsonPath));
}

}  // namespace pic
