#include "bench/stream_benchmark.h"

#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include <sys/wait.h>
#include <unistd.h>

#include "bench/bench_common.h"
#include "bench/server_process.h"
#include "client/connection.h"
#include "client/load_test.h"
#include "core/bake_file.h"

namespace pic {
namespace {

namespace fs = std::filesystem;

}  // namespace

Result<nlohmann::ordered_json> runLoadOn(const ServerProcess& server, PicConnection& connection,
                                         LoadOptions load) {
    double cpuBefore = 0.0, cpuAfter = 0.0;
    load.onChangesStart = [&] { cpuBefore = cpuSeconds(server.pid); };
    load.onChangesEnd = [&] { cpuAfter = cpuSeconds(server.pid); };
    PIC_TRY_ASSIGN(nlohmann::ordered_json report, runLoadTest(connection, load));
    const double updates = std::max(1.0, double(report["updates"].get<uint64_t>()));
    report["server_cpu_ms_per_update"] = 1000.0 * (cpuAfter - cpuBefore) / updates;
    return report;
}

int runStreamBenchmark(const StreamBenchmarkParams& params) {
    auto inputs = loadBenchInputs(params.scenePath, "");
    if (!inputs) return 2;
    BakeReport bakeReport;
    std::fprintf(stderr, "picbench: baking %s %s …\n", params.setting.c_str(), params.linkMode.c_str());
    auto bake = runBake(inputs->scene, settingOptions(params.setting, params.linkMode), bakeReport);
    if (!bake) return reportError(bake.error());
    const fs::path bakePath = fs::temp_directory_path() / fmt::format("picbench_stream_{}.pic", getpid());
    if (auto written = writeBakeFile(bakePath.string(), *bake); !written)
        return reportError(written.error());

    const std::string picserver = params.picserver.empty() ? siblingProgram("server", "picserver") : params.picserver;
    ServerProcess server;
    auto started = startServer(server, {picserver, "--bake", bakePath.string(), "--scene",
                                        params.scenePath, "--listen", "127.0.0.1:0", "--backend",
                                        params.backend, "--bounces", std::to_string(params.bounces),
                                        "--quiet"});
    fs::remove(bakePath);  // the server has it open or failed
    if (!started) return reportError(started.error());
    auto connection = PicConnection::connect(server.address);
    if (!connection) return reportError(connection.error());

    // A frame's values: every cache's SH coefficients (core/frame_codec.h).
    const double values = [&] {
        const double lY = bake->params.bandsY, lC = bake->params.bandsC;
        return double(bake->caches.size()) * (lY * lY + 2.0 * lC * lC);
    }();
    nlohmann::ordered_json rows = nlohmann::ordered_json::array();
    std::printf("%8s %8s %9s %9s %9s %9s %10s %10s %12s %11s %11s %10s %10s %8s\n", "clients",
                "updates", "p50 ms", "p95 ms", "p99 ms", "max ms", "update ms", "encode ms",
                "server CPU", "key KiB", "delta KiB", "key b/coef", "dlt b/coef", "errors");
    int exit = 0;
    for (uint32_t clients : params.clients) {
        LoadOptions load;
        load.clients = clients;
        load.durationSeconds = params.duration;
        load.updateRate = params.updateRate;
        load.moveMetres = 0.01f * inputs->scene.bounds.diagonal();
        auto report = runLoadOn(server, **connection, load);
        if (!report) return reportError(report.error());
        nlohmann::ordered_json row = *report;
        const double updates = std::max(1.0, double(row["updates"].get<uint64_t>()));
        row["values_per_frame"] = values;
        const double keyBytes = row["bytes_per_frame"]["key"].get<double>();
        const double deltaBytes = row["bytes_per_frame"]["delta"].get<double>();
        row["bits_per_value"] = {{"key", 8.0 * keyBytes / values}, {"delta", 8.0 * deltaBytes / values}};
        const auto& latency = row["latency_ms"];
        std::printf("%8u %8.0f %9.1f %9.1f %9.1f %9.1f %10.1f %10.1f %12.1f %11.1f %11.1f %10.2f "
                    "%10.2f %8llu\n",
                    clients, updates, latency["p50"].get<double>(), latency["p95"].get<double>(),
                    latency["p99"].get<double>(), latency["max"].get<double>(),
                    row["server_ms"]["update_p50"].get<double>(),
                    row["server_ms"]["encode_p50"].get<double>(),
                    row["server_cpu_ms_per_update"].get<double>(), keyBytes / 1024.0,
                    deltaBytes / 1024.0, row["bits_per_value"]["key"].get<double>(),
                    row["bits_per_value"]["delta"].get<double>(),
                    (unsigned long long)row["errors"].get<uint64_t>());
        std::fflush(stdout);
        if (row["errors"].get<uint64_t>() > 0) exit = 1;
        rows.push_back(std::move(row));
    }

    Chart chart;
    chart.title = fmt::format("Light change to decoded frame, {} {} on {}", params.setting,
                              params.linkMode, params.backend);
    chart.xLabel = "subscribers";
    chart.yLabel = "ms";
    chart.logX = true;
    ChartSeries p50{"latency p50", {0.2f, 0.6f, 0.2f}}, p99{"latency p99", {0.8f, 0.15f, 0.15f}};
    ChartSeries update{"server update (p50)", {0.4f, 0.4f, 0.4f}};
    ChartSeries goal{"goal: p99 <= 100 ms at 64", {0.8f, 0.15f, 0.15f}};
    goal.dashed = true;
    for (const auto& row : rows) {
        const double n = row["clients"].get<double>();
        p50.points.push_back({n, row["latency_ms"]["p50"].get<double>()});
        p99.points.push_back({n, row["latency_ms"]["p99"].get<double>()});
        update.points.push_back({n, row["server_ms"]["update_p50"].get<double>()});
    }
    goal.points = {{p50.points.front().x, 100.0}, {p50.points.back().x, 100.0}};
    chart.series = {p50, p99, update, goal};
    if (int written = writeChartFile(chart, chartPathFor(params.jsonPath)); written != 0) exit = written;

    auto bakes = (*connection)->listBakes();
    nlohmann::ordered_json json;
    json["scene"] = params.scenePath;
    json["setting"] = params.setting;
    json["link_mode"] = params.linkMode;
    json["backend"] = params.backend;
    json["device"] = bakes ? bakes->device() : "";
    json["bounces"] = params.bounces;
    json["duration_s"] = params.duration;
    json["update_rate"] = params.updateRate;
    json["caches"] = bake->caches.size();
    json["runs"] = std::move(rows);
    const int written = writeJson(json, params.jsonPath);
    return exit != 0 ? exit : written;
}

}  // namespace pic
