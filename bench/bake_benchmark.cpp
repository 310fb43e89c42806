#include "bench/bake_benchmark.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "bench/bench_common.h"
#include "core/bake_file.h"
#include "core/gltf_loader.h"
#include "core/parallel.h"

namespace pic {

int runBakeBenchmark(const BakeBenchmarkParams& params) {
    using Clock = std::chrono::steady_clock;
    auto loadStart = Clock::now();
    auto scene = loadScene(params.scenePath);
    if (!scene) return reportError(scene.error());
    double loadSeconds = std::chrono::duration<double>(Clock::now() - loadStart).count();

    std::vector<std::string> stageOrder;
    std::map<std::string, std::vector<double>> stageSeconds;
    std::vector<double> totals;
    BakeData last;
    BakeReport lastReport;
    for (uint32_t r = 0; r < std::max(1u, params.repeat); ++r) {
        BakeReport report;
        auto start = Clock::now();
        auto bake = runBake(*scene, params.options, report);
        if (!bake) return reportError(bake.error());
        totals.push_back(std::chrono::duration<double>(Clock::now() - start).count());
        for (const auto& [stage, s] : report.seconds) {
            if (!stageSeconds.count(stage)) stageOrder.push_back(stage);
            stageSeconds[stage].push_back(s);
        }
        std::fprintf(stderr, "repeat %u/%u: %.2f s\n", r + 1, params.repeat, totals.back());
        last = std::move(*bake);
        lastReport = report;
    }

    // Bytes per section come from writing the last bake once.
    std::string tmp = (std::filesystem::temp_directory_path() /
                       ("picbench_" + std::to_string(::getpid()) + ".pic")).string();
    auto written = writeBakeFile(tmp, last);
    if (!written) return reportError(written.error());
    auto info = inspectBakeFile(tmp);
    std::filesystem::remove(tmp);
    if (!info) return reportError(info.error());

    nlohmann::ordered_json json;
    json["scene"] = params.scenePath;
    json["triangles"] = scene->triangles.size();
    json["threads"] = workerCount();
    json["repeat"] = params.repeat;
    json["params"] = {{"surfels", last.params.surfels},
                      {"links_per_cache", last.params.linksPerCache},
                      {"link_mode", last.params.linkMode == LinkMode::Sh ? "sh" : "rtp"},
                      {"bands_y", last.params.bandsY},
                      {"bands_c", last.params.bandsC},
                      {"grid_cell", last.params.gridCell},
                      {"lightmap_texel", last.params.lightmapTexel},
                      {"link_samples", last.params.linkSamples},
                      {"link_final_samples", last.params.linkFinalSamples}};
    json["caches"] = {{"unique", last.caches.size()}, {"grid", info->gridCaches}, {"lightmap", info->lightmapCaches}};
    json["load_seconds"] = loadSeconds;
    json["seconds_median"] = nlohmann::ordered_json::object();
    for (const std::string& stage : stageOrder) json["seconds_median"][stage] = median(stageSeconds[stage]);
    json["total_seconds_median"] = median(totals);
    json["peak_memory_bytes"] = peakMemoryBytes();
    json["rays"] = lastReport.links.rays;
    json["bytes"] = nlohmann::ordered_json::object();
    for (const auto& [name, bytes] : info->sectionBytes) json["bytes"][name] = bytes;
    json["file_bytes"] = info->fileSize;

    std::printf("scene %s: %zu triangles, %u threads, %u repeat(s)\n", params.scenePath.c_str(),
                scene->triangles.size(), workerCount(), params.repeat);
    std::printf("nS %u, nL %u (%s), unique caches %zu (grid %llu, light-map texels %llu)\n",
                last.params.surfels, last.params.linksPerCache,
                last.params.linkMode == LinkMode::Sh ? "sh" : "rtp", last.caches.size(),
                static_cast<unsigned long long>(info->gridCaches),
                static_cast<unsigned long long>(info->lightmapCaches));
    std::printf("%-14s %10s\n", "stage", "median s");
    std::printf("%-14s %10.2f\n", "load", loadSeconds);
    for (const std::string& stage : stageOrder) std::printf("%-14s %10.2f\n", stage.c_str(), median(stageSeconds[stage]));
    std::printf("%-14s %10.2f\n", "total", median(totals));
    std::printf("peak memory %.2f GiB, %.1f M link rays\n", peakMemoryBytes() / double(1ull << 30),
                lastReport.links.rays / 1e6);
    for (const auto& [name, bytes] : info->sectionBytes)
        std::printf("section %-16s %12llu bytes\n", name.c_str(), static_cast<unsigned long long>(bytes));
    if (!params.jsonPath.empty()) {
        std::ofstream out(params.jsonPath);
        out << json.dump(2) << "\n";
        if (!out) {
            std::fprintf(stderr, "picbench: error: cannot write %s\n", params.jsonPath.c_str());
            return 1;
        }
        std::printf("wrote %s\n", params.jsonPath.c_str());
    }
    return 0;
}

}  // namespace pic
