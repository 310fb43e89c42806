#include "bench/soak_benchmark.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <thread>
#include <vector>

#include <unistd.h>

#include "bake/bake.h"
#include "bench/bench_common.h"
#include "bench/server_process.h"
#include "client/connection.h"
#include "client/load_test.h"
#include "core/bake_file.h"

namespace pic {

namespace fs = std::filesystem;

int runSoakBenchmark(const SoakBenchmarkParams& params) {
    if (!(params.duration > 0.0) || !(params.updateRate > 0.0) || params.clients == 0)
        return reportError(Error{ErrorCode::InvalidInput,
                                 fmt::format("--duration {}, --update-rate {} and --clients {} must be positive",
                                             params.duration, params.updateRate, params.clients)});
    auto inputs = loadBenchInputs(params.scenePath, "");
    if (!inputs) return 2;
    std::string bakePath = params.bakePath;
    const fs::path madeBake = fs::temp_directory_path() / fmt::format("picbench_soak_{}.pic", getpid());
    if (bakePath.empty()) {
        std::fprintf(stderr, "picbench: baking %s …\n", params.setting.c_str());
        BakeReport report;
        auto bake = runBake(inputs->scene, settingOptions(params.setting, "rtp"), report);
        if (!bake) return reportError(bake.error());
        if (auto written = writeBakeFile(madeBake.string(), *bake); !written) return reportError(written.error());
        bakePath = madeBake.string();
    }

    const std::string picserver = params.picserver.empty() ? siblingProgram("server", "picserver") : params.picserver;
    ServerProcess server;
    // The editor's rate, not the server's limit, is what the soak sets.
    const double limit = std::max(30.0, 2.0 * params.updateRate);
    auto started = startServer(server, {picserver, "--bake", bakePath, "--scene", params.scenePath,
                                        "--listen", "127.0.0.1:0", "--backend", params.backend,
                                        "--bounces", "1", "--set-lights-per-second",
                                        fmt::format("{}", limit), "--quiet"});
    if (bakePath == madeBake.string()) fs::remove(madeBake);  // the server has it open or failed
    if (!started) return reportError(started.error());
    auto connection = PicConnection::connect(server.address);
    if (!connection) return reportError(connection.error());
    (*connection)->setPatience(std::chrono::seconds(30));

    // Resident memory of the server, once a second, from start to end.
    using Clock = std::chrono::steady_clock;
    const auto start = Clock::now();
    std::mutex samplesMutex;
    std::vector<glm::dvec2> rss;  // (seconds, MiB)
    std::atomic<bool> stop{false};
    std::thread sampler([&] {
        while (!stop) {
            const double t = std::chrono::duration<double>(Clock::now() - start).count();
            const double mib = double(residentBytes(server.pid)) / double(1 << 20);
            {
                std::lock_guard lock(samplesMutex);
                rss.push_back({t, mib});
            }
            for (int i = 0; i < 100 && !stop; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
        }
    });

    LoadOptions load;
    load.clients = params.clients;
    load.durationSeconds = params.duration;
    load.updateRate = params.updateRate;
    load.moveMetres = 0.01f * inputs->scene.bounds.diagonal();
    double changesStart = 0.0;
    load.onChangesStart = [&] { changesStart = std::chrono::duration<double>(Clock::now() - start).count(); };
    std::fprintf(stderr, "picbench: soak: %u subscribers, %g light changes a second for %g s …\n",
                 params.clients, params.updateRate, params.duration);
    auto report = runLoadTest(**connection, load);
    stop = true;
    sampler.join();
    if (!report) return reportError(report.error());

    // Growth from the end of the first tenth of the changes to the end.
    const double warmEnd = changesStart + 0.1 * params.duration;
    double warmMib = 0.0, endMib = 0.0, peakMib = 0.0;
    for (const glm::dvec2& sample : rss) {
        if (sample.x <= warmEnd) warmMib = sample.y;
        endMib = sample.y;
        peakMib = std::max(peakMib, sample.y);
    }
    const double growth = warmMib > 0.0 ? 100.0 * (endMib - warmMib) / warmMib : 0.0;
    const auto& r = *report;
    const uint64_t errors = r["errors"].get<uint64_t>();
    const uint64_t lost = r["subscribers_without_last"].get<uint64_t>();
    const bool passed = errors == 0 && lost == 0 && growth < params.maxRssGrowthPercent;

    std::printf("soak: %u subscribers, %llu light changes in %.0f s, latency p50 %.1f ms p99 %.1f ms max "
                "%.1f ms, lost final states %llu, errors %llu, server RSS %.1f MiB after the first "
                "tenth, %.1f MiB at the end (%+.2f %%, limit %g %%), peak %.1f MiB: %s\n",
                params.clients, (unsigned long long)r["updates"].get<uint64_t>(), r["duration_s"].get<double>(),
                r["latency_ms"]["p50"].get<double>(), r["latency_ms"]["p99"].get<double>(),
                r["latency_ms"]["max"].get<double>(), (unsigned long long)lost, (unsigned long long)errors,
                warmMib, endMib, growth, params.maxRssGrowthPercent, peakMib, passed ? "PASSED" : "FAILED");
    std::fflush(stdout);

    Chart chart;
    chart.title = fmt::format("picserver resident memory, {} subscribers, {:g} changes/s", params.clients,
                              params.updateRate);
    chart.xLabel = "seconds";
    chart.yLabel = "MiB";
    ChartSeries memory{"resident memory", {0.2f, 0.4f, 0.8f}};
    memory.points = rss;
    ChartSeries limitLine{fmt::format("+{:g} % of the first tenth's", params.maxRssGrowthPercent), {0.8f, 0.15f, 0.15f}};
    limitLine.dashed = true;
    if (!rss.empty())
        limitLine.points = {{rss.front().x, warmMib * (1.0 + params.maxRssGrowthPercent / 100.0)},
                            {rss.back().x, warmMib * (1.0 + params.maxRssGrowthPercent / 100.0)}};
    chart.series = {memory, limitLine};
    int exit = writeChartFile(chart, chartPathFor(params.jsonPath));

    nlohmann::ordered_json json;
    json["scene"] = params.scenePath;
    json["backend"] = params.backend;
    json["clients"] = params.clients;
    json["update_rate"] = params.updateRate;
    json["duration_s"] = params.duration;
    json["load"] = r;
    json["lost_final_states"] = lost;
    json["rss_mib"] = {{"after_first_tenth", warmMib}, {"end", endMib}, {"peak", peakMib},
                       {"growth_percent", growth}, {"limit_percent", params.maxRssGrowthPercent}};
    nlohmann::ordered_json samples = nlohmann::ordered_json::array();
    for (const glm::dvec2& s : rss) samples.push_back({s.x, s.y});
    json["rss_samples"] = std::move(samples);
    json["passed"] = passed;
    if (int written = writeJson(json, params.jsonPath); written != 0) exit = written;
    return exit != 0 ? exit : (passed ? 0 : 1);
}

}  // namespace pic
