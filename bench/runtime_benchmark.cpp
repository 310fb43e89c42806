#include "bench/runtime_benchmark.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>

#include <nlohmann/json.hpp>

#include "bake/bake.h"
#include "bake/embree_scene.h"
#include "core/gltf_loader.h"
#include "core/light_set.h"
#include "server/cpu/cpu_runtime.h"
#include "server/cpu/pull.h"
#include "server/cpu/surfel_lighting.h"
#include "server/gpu/gpu_runtime.h"

namespace pic {
namespace {

using Clock = std::chrono::steady_clock;

double median(std::vector<double> values) {
    if (values.empty()) return 0.0;
    std::sort(values.begin(), values.end());
    const size_t n = values.size();
    return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

/// This machine's memcpy bandwidth in bytes/s (median of 7 copies of 256 MiB, after a
/// warm-up copy that also faults the pages in): the floor a pass that reads every link once
/// per update is compared with.
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

/// Paper 000 Table 2's two settings as bake options.
BakeOptions settingOptions(const std::string& setting, const std::string& linkMode) {
    BakeOptions options;
    const bool high = setting == "high";
    options.surfels = high ? 131072u : 32768u;
    options.links = high ? 254u : 128u;
    options.bandsY = high ? 4u : 3u;
    options.bandsC = 2u;
    options.linkMode = linkMode == "sh" ? LinkMode::Sh : LinkMode::Rtp;
    return options;
}

/// The light set of update `k`: every light moves by a small step (point and spot lights
/// along x, directional lights tilt), so each update re-renders its shadow maps.
LightSet movedLights(const LightSet& base, int k, float step) {
    LightSet lights = base;
    for (Light& light : lights.lights) {
        const float offset = step * float((k % 2) ? 1 : -1) * float(1 + k % 3);
        if (light.type == LightType::Directional)
            light.direction = glm::normalize(light.direction + glm::vec3(0.01f * offset / step, 0.0f, 0.0f));
        else
            light.position.x += offset;
    }
    return lights;
}

struct BackendFigures {
    std::vector<double> totalMs;
    std::vector<double> cacheLightingWallMs;  ///< GPU: one cache-lighting pass, wall clock
    std::map<std::string, std::vector<double>> passMs;  ///< per update
    int bounces = 0;
    uint64_t shadowTriangles = 0;  ///< GPU: triangles rasterised per update, after culling
};

Result<BackendFigures> timeBackend(Runtime& runtime, const LightSet& base, int repeat, float step) {
    BackendFigures figures;
    UpdateStats stats;
    PIC_TRY(runtime.setLights(movedLights(base, 0, step), &stats));  // warm-up
    for (int k = 1; k <= repeat; ++k) {
        PIC_TRY(runtime.setLights(movedLights(base, k, step), &stats));
        figures.totalMs.push_back(stats.totalMs);
        for (const auto& [pass, ms] : stats.passMs) figures.passMs[pass].push_back(ms);
        figures.bounces = stats.bounces;
        figures.shadowTriangles = stats.shadowTriangles;
    }
    return figures;
}

/// Wall-clock ms of the GPU cache-lighting pass alone, from the CPU twin's node flux of
/// `lights` (upload of node flux and read-back of the caches included). Lavapipe's
/// timestamps do not wait for a dispatch to finish, so this is the pass's honest time there.
Result<std::vector<double>> timeCacheLighting(GpuRuntime& gpu, const Scene& scene,
                                              const EmbreeScene& rays, const BakeData& bake,
                                              const LightSet& lights, int repeat) {
    std::vector<glm::vec3> nodeFlux(bake.nodes.size());
    directSurfelFlux(scene, rays, bake, lights,
                     std::span<glm::vec3>(nodeFlux.data(), bake.surfels.size()));
    pullFlux(bake, nodeFlux);
    std::vector<double> ms;
    PIC_TRY(gpu.runCacheLighting(nodeFlux));  // warm-up
    for (int k = 0; k < repeat; ++k) {
        const Clock::time_point start = Clock::now();
        PIC_TRY(gpu.runCacheLighting(nodeFlux));
        ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - start).count());
    }
    return ms;
}

nlohmann::ordered_json figuresJson(const BackendFigures& f) {
    nlohmann::ordered_json json;
    json["update_ms_median"] = median(f.totalMs);
    json["update_ms"] = f.totalMs;
    json["bounces"] = f.bounces;
    json["shadow_triangles"] = f.shadowTriangles;
    json["pass_ms_median"] = nlohmann::ordered_json::object();
    for (const auto& [pass, ms] : f.passMs) json["pass_ms_median"][pass] = median(ms);
    return json;
}

}  // namespace

int runRuntimeBenchmark(const RuntimeBenchmarkParams& params) {
    auto scene = loadScene(params.scenePath);
    if (!scene) {
        std::fprintf(stderr, "picbench: error: %s\n", scene.error().message.c_str());
        return exitCode(scene.error());
    }
    auto lights = loadLightSet(params.lightsPath, *scene);
    if (!lights) {
        std::fprintf(stderr, "picbench: error: %s\n", lights.error().message.c_str());
        return exitCode(lights.error());
    }
    if (lights->lights.empty())
        std::fprintf(stderr, "picbench: warning: the light set has no punctual lights\n");
    auto rays = EmbreeScene::create(*scene);
    if (!rays) {
        std::fprintf(stderr, "picbench: error: %s\n", rays.error().message.c_str());
        return exitCode(rays.error());
    }
    const float step = 1e-3f * scene->bounds.diagonal();
    const double bandwidth = memcpyBandwidth();
    std::printf("memcpy bandwidth: %.2f GB/s\n", bandwidth * 1e-9);

    nlohmann::ordered_json json;
    json["scene"] = params.scenePath;
    json["triangles"] = scene->triangles.size();
    json["memcpy_bytes_per_second"] = bandwidth;
    json["runs"] = nlohmann::ordered_json::array();
    std::printf("%-9s %-4s %-7s %6s %9s %9s %6s %9s %8s %9s %9s %9s %8s\n", "setting", "link",
                "bounces", "nC", "cpu ms", "gpu ms", "ratio", "shadow", "k tris", "surfels", "pull",
                "caches*", "bw ratio");
    for (const std::string& setting : params.settings) {
        for (const std::string& linkMode : params.linkModes) {
            BakeReport report;
            std::fprintf(stderr, "picbench: baking %s %s …\n", setting.c_str(), linkMode.c_str());
            auto bake = runBake(*scene, settingOptions(setting, linkMode), report);
            if (!bake) {
                std::fprintf(stderr, "picbench: error: %s\n", bake.error().message.c_str());
                return exitCode(bake.error());
            }
            for (int bounces : params.bounces) {
                const BounceParams bounceParams{bounces};
                auto cpu = createCpuRuntime(*scene, **rays, *bake, bounceParams);
                GpuRuntimeOptions options;
                options.deviceName = params.device;
                options.shadowMapSize = params.shadowMapSize;
                auto gpu = GpuRuntime::create(*scene, **rays, *bake, bounceParams, options);
                if (!cpu || !gpu) {
                    const Error& e = !cpu ? cpu.error() : gpu.error();
                    std::fprintf(stderr, "picbench: error: %s\n", e.message.c_str());
                    return exitCode(e);
                }
                auto cpuFigures = timeBackend(**cpu, *lights, params.repeat, step);
                auto gpuFigures = timeBackend(**gpu, *lights, params.repeat, step);
                if (!cpuFigures || !gpuFigures) {
                    const Error& e = !cpuFigures ? cpuFigures.error() : gpuFigures.error();
                    std::fprintf(stderr, "picbench: error: %s\n", e.message.c_str());
                    return exitCode(e);
                }
                auto cacheWall = timeCacheLighting(**gpu, *scene, **rays, *bake, *lights, params.repeat);
                if (!cacheWall) {
                    std::fprintf(stderr, "picbench: error: %s\n", cacheWall.error().message.c_str());
                    return exitCode(cacheWall.error());
                }
                const auto passMedian = [&](const BackendFigures& f, const char* pass) {
                    auto it = f.passMs.find(pass);
                    return it == f.passMs.end() ? 0.0 : median(it->second);
                };
                const double cpuMs = median(cpuFigures->totalMs), gpuMs = median(gpuFigures->totalMs);
                // Link bytes per second of one GPU cache-lighting pass (wall clock): every link
                // is read once per bounce.
                const double cacheMs = median(*cacheWall);
                const double linkBytes = double((*gpu)->linkBytesPerBounce());
                const double linkRate = cacheMs > 0.0 ? linkBytes / (cacheMs * 1e-3) : 0.0;
                std::printf("%-9s %-4s %-7d %6zu %9.1f %9.1f %6.2f %9.1f %8.0f %9.1f %9.1f %9.1f %8.2f\n",
                            setting.c_str(), linkMode.c_str(), gpuFigures->bounces,
                            bake->caches.size(), cpuMs, gpuMs, gpuMs / cpuMs,
                            passMedian(*gpuFigures, "shadow_maps"),
                            double(gpuFigures->shadowTriangles) * 1e-3,
                            passMedian(*gpuFigures, "surfel_lighting"),
                            passMedian(*gpuFigures, "pull"), cacheMs, linkRate / bandwidth);

                nlohmann::ordered_json run;
                run["setting"] = setting;
                run["link_mode"] = linkMode;
                run["bounces_requested"] = bounces;
                run["surfels"] = bake->surfels.size();
                run["caches"] = bake->caches.size();
                run["links_per_cache"] = bake->links.linksPerCache;
                run["bands"] = {{"y", bake->params.bandsY}, {"c", bake->params.bandsC}};
                run["device"] = (*gpu)->context().deviceName();
                run["cpu"] = figuresJson(*cpuFigures);
                run["gpu"] = figuresJson(*gpuFigures);
                run["gpu_over_cpu"] = gpuMs / cpuMs;
                run["cache_lighting_wall_ms_median"] = cacheMs;
                run["link_bytes_per_bounce"] = linkBytes;
                run["cache_lighting_bytes_per_second"] = linkRate;
                run["bandwidth_ratio"] = linkRate / bandwidth;
                run["gpu_memory_bytes"] = nlohmann::ordered_json::object();
                for (const auto& [buffer, bytes] : (*gpu)->memory()) run["gpu_memory_bytes"][buffer] = bytes;
                json["runs"].push_back(run);
            }
        }
    }
    std::ofstream out(params.jsonPath);
    out << json.dump(2) << "\n";
    if (!out) {
        std::fprintf(stderr, "picbench: error: could not write %s\n", params.jsonPath.c_str());
        return 1;
    }
    std::printf("ms: medians per update; shadow, surfels, pull from GPU timestamps; caches* is one\n"
                "cache-lighting pass by wall clock (lavapipe's timestamps do not wait for it)\n");
    std::printf("written %s\n", params.jsonPath.c_str());
    return 0;
}

}  // namespace pic
