#include "bench/budget_benchmark.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <thread>

#include <unistd.h>

#include "bench/bench_common.h"
#include "bench/chart.h"
#include "bench/server_process.h"
#include "bench/stream_benchmark.h"
#include "client/connection.h"
#include "client/load_test.h"
#include "core/bake_file.h"
#include "core/color.h"

namespace pic {

namespace fs = std::filesystem;

namespace {

/// One more subscriber of the load test's session that keeps, per version, the luma plane of
/// its first earlier part and of its final state: how far what a client shows before the final
/// state is from it.
class StateWatcher {
public:
    StateWatcher(PicConnection& connection, const std::string& session, const std::string& token,
                 const v1::SceneHeader& header)
        : mDecoder(header), mStream(connection.subscribe(session, token)),
          mThread([this] { run(); }) {}
    ~StateWatcher() { stop(); }

    void stop() {
        if (!mThread.joinable()) return;
        mStream->cancel();
        mThread.join();
    }

    /// Medians over the versions that reached their final state: the relative RMS difference
    /// of the luma coefficients from it, of the previous final state (what an unbudgeted
    /// client shows until the final state arrives) and of the first part (when one came).
    nlohmann::ordered_json report() const {
        std::vector<double> stale, first;
        const std::vector<float>* previous = nullptr;
        for (const auto& [version, final] : mFinals) {
            if (previous) stale.push_back(relativeRms(*previous, final));
            if (auto part = mFirstParts.find(version); part != mFirstParts.end())
                first.push_back(relativeRms(part->second, final));
            previous = &final;
        }
        return {{"previous_final", median(stale)}, {"first_part", median(first)},
                {"versions", stale.size()}, {"with_parts", first.size()}};
    }

private:
    void run() {
        v1::Frame frame;
        while (mStream->next(frame)) {
            const uint32_t part = frame.part();
            if (!mDecoder.apply(frame)) continue;
            const std::vector<uint16_t>& y = mDecoder.frame().planes[0];
            std::vector<float> luma(y.size());
            for (size_t i = 0; i < y.size(); ++i) luma[i] = halfToFloat(y[i]);
            if (part == 0)
                mFinals[mDecoder.version()] = std::move(luma);
            else if (!mFirstParts.contains(mDecoder.version()))
                mFirstParts[mDecoder.version()] = std::move(luma);
        }
    }

    static double relativeRms(const std::vector<float>& shown, const std::vector<float>& final) {
        double error = 0.0, norm = 0.0;
        for (size_t i = 0; i < final.size(); ++i) {
            const double d = double(shown[i]) - double(final[i]);
            error += d * d;
            norm += double(final[i]) * double(final[i]);
        }
        return norm > 0.0 ? std::sqrt(error / norm) : 0.0;
    }

    FrameDecoder mDecoder;
    std::unique_ptr<FrameStream> mStream;
    std::map<uint64_t, std::vector<float>> mFinals, mFirstParts;
    std::thread mThread;
};

}  // namespace

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
    std::printf("%9s %8s %11s %12s %12s %12s %12s %10s %10s %10s %10s %8s\n", "budget ms", "updates",
                "parts/upd", "first p50", "first p99", "final p50", "final p99", "update ms",
                "server CPU", "stale err", "part err", "errors");
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
        auto created = (*connection)->createSession();
        if (!created) return reportError(created.error());
        auto header = (*connection)->sceneHeader(created->bake_id());
        if (!header) return reportError(header.error());
        StateWatcher watcher(**connection, created->session(), created->viewer_token(), *header);
        LoadOptions load;
        load.session = created->session();
        load.editorToken = created->editor_token();
        load.clients = params.clients;
        load.durationSeconds = params.duration;
        load.updateRate = params.updateRate;
        load.moveMetres = 0.01f * inputs->scene.bounds.diagonal();
        auto report = runLoadOn(server, **connection, load);
        if (!report) return reportError(report.error());
        watcher.stop();
        nlohmann::ordered_json row;
        row["budget_ms"] = budget;
        const double updates = std::max(1.0, double((*report)["updates"].get<uint64_t>()));
        // Parts are counted per subscriber: per update, over all of them.
        const double parts = double((*report)["partial_frames"].get<uint64_t>()) /
                             (updates * double(params.clients));
        row["parts_per_update"] = parts;
        row["server_cpu_ms_per_update"] = (*report)["server_cpu_ms_per_update"];
        row["luma_error"] = watcher.report();
        row["load"] = *report;
        const auto& first = (*report)["first_change_ms"];
        const auto& final = (*report)["latency_ms"];
        std::printf("%9.1f %8.0f %11.2f %12.1f %12.1f %12.1f %12.1f %10.1f %10.1f %10.3f %10.3f %8llu\n",
                    budget, updates, parts, first["p50"].get<double>(), first["p99"].get<double>(),
                    final["p50"].get<double>(), final["p99"].get<double>(),
                    (*report)["server_ms"]["update_p50"].get<double>(),
                    row["server_cpu_ms_per_update"].get<double>(),
                    row["luma_error"]["previous_final"].get<double>(),
                    row["luma_error"]["first_part"].get<double>(),
                    (unsigned long long)(*report)["errors"].get<uint64_t>());
        std::fflush(stdout);
        if ((*report)["errors"].get<uint64_t>() > 0) exit = 1;
        rows.push_back(std::move(row));
    }
    if (!scratch.empty()) fs::remove(scratch);

    // Budgets on the x axis; the unbudgeted run (budget 0) as dashed lines across.
    Chart chart;
    chart.title = fmt::format("Light change to a subscriber's frame, {} subscribers, {} on {}",
                              params.clients, params.backend, device);
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
