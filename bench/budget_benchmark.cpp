#include "bench/budget_benchmark.h"

#include <cstdio>
#include <filesystem>

#include <unistd.h>

#include "bench/bench_common.h"
#include "bench/chart.h"
#include "bench/server_process.h"
#include "client/connection.h"
#include "client/load_test.h"
#include "core/bake_file.h"

namespace pic {

namespace fs = std::filesystem;

int runBudgetBenchmark(const BudgetBenchmarkParams& params) {
    if (params.budgets.empty()) return reportError(Error{ErrorCode::InvalidInput, "--budgets is empty"});
    auto inputs = loadBenchInputs(params.scenePath, "");
    if (!inputs) return 2;
    std::string bakePath = params.bakePath;
    fs::path scratch;
    if (bakePath.empty()) {
        BakeReport bakeReport;
        std::fprintf(stderr, "picbench: baking %s …\n", params.setting.c_str());
        auto bake = runBake(inputs->scene, settingOptions(params.setting, "rtp"), bakeReport);
        if (!bake) return reportError(bake.error());
        scratch = fs::temp_directory_path() / fmt::format("picbench_budget_{}.pic", getpid());
        if (auto written = writeBakeFile(scratch.string(), *bake); !written)
            return reportError(written.error());
        bakePath = scratch.string();
    }
    const std::string picserver =
        params.picserver.empty() ? siblingProgram("server", "picserver") : params.picserver;

    nlohmann::ordered_json rows = nlohmann::ordered_json::array();
    std::printf("%9s %8s %11s %12s %12s %12s %12s %10s %8s\n", "budget ms", "updates",
                "parts/upd", "first p50", "first p99", "final p50", "final p99", "update ms",
                "errors");
    int exit = 0;
    std::string device;
    for (const double budget : params.budgets) {
        ServerProcess server;
        auto started = startServer(server, {picserver, "--bake", bakePath, "--scene",
                                            params.scenePath, "--listen", "127.0.0.1:0",
                                            "--backend", params.backend, "--update-budget-ms",
                                            fmt::format("{}", budget), "--quiet"});
        if (!started) return reportError(started.error());
        auto connection = PicConnection::connect(server.address);
        if (!connection) return reportError(connection.error());
        if (device.empty())
            if (auto bakes = (*connection)->listBakes(); bakes) device = bakes->device();
        LoadOptions load;
        load.clients = params.clients;
        load.durationSeconds = params.duration;
        load.updateRate = params.updateRate;
        load.moveMetres = 0.01f * inputs->scene.bounds.diagonal();
        auto report = runLoadTest(**connection, load);
        if (!report) return reportError(report.error());
        nlohmann::ordered_json row;
        row["budget_ms"] = budget;
        const double updates = std::max(1.0, double((*report)["updates"].get<uint64_t>()));
        // Parts are counted per subscriber: per update, over all of them.
        const double parts = double((*report)["partial_frames"].get<uint64_t>()) /
                             (updates * double(params.clients));
        row["parts_per_update"] = parts;
        row["load"] = *report;
        const auto& first = (*report)["first_change_ms"];
        const auto& final = (*report)["latency_ms"];
        std::printf("%9.1f %8.0f %11.2f %12.1f %12.1f %12.1f %12.1f %10.1f %8llu\n", budget,
                    updates, parts, first["p50"].get<double>(), first["p99"].get<double>(),
                    final["p50"].get<double>(), final["p99"].get<double>(),
                    (*report)["server_ms"]["update_p50"].get<double>(),
                    (unsigned long long)(*report)["errors"].get<uint64_t>());
        std::fflush(stdout);
        if ((*report)["errors"].get<uint64_t>() > 0) exit = 1;
        rows.push_back(std::move(row));
    }
    if (!scratch.empty()) fs::remove(scratch);

    // Budgets on the x axis; the unbudgeted run (budget 0) as dashed lines across.
    Chart chart;
    chart.title = fmt::format("Light change to a subscriber's frame, {} subscribers, {}",
                              params.clients, params.backend);
    chart.xLabel = "update budget (ms)";
    chart.yLabel = "ms";
    ChartSeries first{"first visible change p50", {0.2f, 0.6f, 0.2f}};
    ChartSeries firstTail{"first visible change p99", {0.55f, 0.8f, 0.55f}};
    ChartSeries final{"final state p50", {0.8f, 0.15f, 0.15f}};
    ChartSeries finalTail{"final state p99", {0.95f, 0.55f, 0.55f}};
    ChartSeries baseline{"unbudgeted p50", {0.4f, 0.4f, 0.4f}};
    baseline.dashed = true;
    double lowest = 0.0, highest = 0.0, unbudgeted = -1.0;
    for (const auto& row : rows) {
        const double budget = row["budget_ms"].get<double>();
        const auto& load = row["load"];
        if (budget <= 0.0) {
            unbudgeted = load["latency_ms"]["p50"].get<double>();
            continue;
        }
        lowest = lowest == 0.0 ? budget : std::min(lowest, budget);
        highest = std::max(highest, budget);
        first.points.push_back({budget, load["first_change_ms"]["p50"].get<double>()});
        firstTail.points.push_back({budget, load["first_change_ms"]["p99"].get<double>()});
        final.points.push_back({budget, load["latency_ms"]["p50"].get<double>()});
        finalTail.points.push_back({budget, load["latency_ms"]["p99"].get<double>()});
    }
    if (!first.points.empty()) {
        chart.series = {first, firstTail, final, finalTail};
        if (unbudgeted >= 0.0) {
            baseline.points = {{lowest, unbudgeted}, {highest, unbudgeted}};
            chart.series.push_back(baseline);
        }
        if (int written = writeChartFile(chart, chartPathFor(params.jsonPath)); written != 0) exit = written;
    }

    nlohmann::ordered_json json;
    json["scene"] = params.scenePath;
    json["bake"] = params.bakePath.empty() ? params.setting : params.bakePath;
    json["backend"] = params.backend;
    json["device"] = device;
    json["clients"] = params.clients;
    json["duration_s"] = params.duration;
    json["update_rate"] = params.updateRate;
    json["runs"] = std::move(rows);
    const int written = writeJson(json, params.jsonPath);
    return exit != 0 ? exit : written;
}

}  // namespace pic
