#include "bench/codec_benchmark.h"

#include <chrono>
#include <cstdio>

#include "bench/bench_common.h"
#include "core/frame_codec.h"
#include "render/cpu_runtime.h"
#include "render/gpu_runtime.h"

namespace pic {
namespace {

using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

}  // namespace

int runCodecBenchmark(const CodecBenchmarkParams& params) {
    auto inputs = loadBenchInputs(params.scenePath, params.lightsPath);
    if (!inputs) return 2;
    const Scene& scene = inputs->scene;
    BakeReport bakeReport;
    std::fprintf(stderr, "picbench: baking %s %s …\n", params.setting.c_str(), params.linkMode.c_str());
    auto bake = runBake(scene, settingOptions(params.setting, params.linkMode, params.chromaBands), bakeReport);
    if (!bake) return reportError(bake.error());
    std::unique_ptr<Runtime> runtime;
    if (params.backend == "gpu") {
        auto gpu = GpuRuntime::create(scene, *inputs->rays, *bake, BounceParams{});
        if (!gpu) return reportError(gpu.error());
        runtime = std::move(*gpu);
    } else {
        auto cpu = createCpuRuntime(scene, *inputs->rays, *bake, BounceParams{});
        if (!cpu) return reportError(cpu.error());
        runtime = std::move(*cpu);
    }

    const double values =
        double(bake->caches.size()) * double(bake->params.bandsY * bake->params.bandsY +
                                             2 * bake->params.bandsC * bake->params.bandsC);
    const float step = 1e-3f * scene.bounds.diagonal();
    // Per zstd level, over the updates after the first (whose delta has no base).
    struct LevelSamples {
        std::vector<double> keyBits, deltaBits, keyMs, deltaMs, decodeMs;
    };
    std::vector<LevelSamples> samples(params.zstdLevels.size());
    nlohmann::ordered_json frames = nlohmann::ordered_json::array();
    HalfFrame previous;
    for (int k = 0; k <= params.updates; ++k) {
        std::fprintf(stderr, "picbench: update %d of %d\n", k, params.updates);
        auto caches = runtime->setLights(changedLights(inputs->lights, k, step, params.change));
        if (!caches) return reportError(caches.error());
        const HalfFrame frame = halfFrameOf(**caches);

        nlohmann::ordered_json row{{"update", k}, {"levels", nlohmann::ordered_json::array()}};
        for (size_t i = 0; i < params.zstdLevels.size(); ++i) {
            const int level = params.zstdLevels[i];
            LevelSamples& sampled = samples[i];
            Clock::time_point start = Clock::now();
            auto key = encodeFrame(frame, nullptr, level);
            const double keyMs = msSince(start);
            if (!key) return reportError(key.error());
            nlohmann::ordered_json entry{
                {"zstd_level", level}, {"key_bytes", key->bytes()}, {"key_encode_ms", keyMs}};
            if (k > 0) {
                start = Clock::now();
                auto delta = encodeFrame(frame, &previous, level);
                const double deltaMs = msSince(start);
                if (!delta) return reportError(delta.error());
                // The receiver holds the previous version and applies the delta.
                HalfFrame received = previous;
                start = Clock::now();
                if (auto decoded = decodeFrame(*delta, received); !decoded)
                    return reportError(decoded.error());
                const double decodeMs = msSince(start);
                if (!(received == frame)) {
                    std::fprintf(stderr,
                                 "picbench: error: update %d, zstd level %d: decoding the delta "
                                 "frame did not give back the encoder's input\n",
                                 k, level);
                    return 1;
                }
                sampled.keyBits.push_back(8.0 * double(key->bytes()) / values);
                sampled.deltaBits.push_back(8.0 * double(delta->bytes()) / values);
                sampled.keyMs.push_back(keyMs);
                sampled.deltaMs.push_back(deltaMs);
                sampled.decodeMs.push_back(decodeMs);
                entry["delta_bytes"] = delta->bytes();
                entry["delta_encode_ms"] = deltaMs;
                entry["delta_decode_ms"] = decodeMs;
            }
            row["levels"].push_back(std::move(entry));
        }
        frames.push_back(std::move(row));
        previous = frame;
    }

    std::printf("medians over %d updates\n", params.updates);
    std::printf("%5s %8s %10s %14s %16s %11s %13s %9s\n", "zstd", "key kB", "delta kB",
                "key bits/coef", "delta bits/coef", "key enc ms", "delta enc ms", "decode ms");
    nlohmann::ordered_json levels = nlohmann::ordered_json::array();
    Chart chart;
    chart.title = fmt::format("Stream frame size against encode time per zstd level, {} {}",
                              params.setting, params.linkMode);
    chart.xLabel = "encode ms (median)";
    chart.yLabel = "bits per cache coefficient (median)";
    chart.logX = true;
    ChartSeries keySeries{"key frames", {0.2f, 0.35f, 0.75f}},
        deltaSeries{"delta frames", {0.85f, 0.45f, 0.1f}};
    for (size_t i = 0; i < params.zstdLevels.size(); ++i) {
        const LevelSamples& level = samples[i];
        const double keyBits = median(level.keyBits), deltaBits = median(level.deltaBits);
        nlohmann::ordered_json entry;
        entry["zstd_level"] = params.zstdLevels[i];
        entry["key_bits_per_coefficient_median"] = keyBits;
        entry["delta_bits_per_coefficient_median"] = deltaBits;
        entry["key_encode_ms_median"] = median(level.keyMs);
        entry["delta_encode_ms_median"] = median(level.deltaMs);
        entry["delta_decode_ms_median"] = median(level.decodeMs);
        std::printf("%5d %8.1f %10.1f %14.2f %16.2f %11.2f %13.2f %9.2f\n", params.zstdLevels[i],
                    keyBits * values / 8e3, deltaBits * values / 8e3, keyBits, deltaBits,
                    median(level.keyMs), median(level.deltaMs), median(level.decodeMs));
        const std::string label = fmt::format("zstd {}", params.zstdLevels[i]);
        keySeries.points.push_back({median(level.keyMs), keyBits});
        keySeries.labels.push_back(label);
        deltaSeries.points.push_back({median(level.deltaMs), deltaBits});
        deltaSeries.labels.push_back(label);
        levels.push_back(std::move(entry));
    }
    keySeries.connected = deltaSeries.connected = params.zstdLevels.size() > 1;
    chart.series = {keySeries, deltaSeries};
    const int charted = writeChartFile(chart, chartPathFor(params.jsonPath));

    nlohmann::ordered_json json;
    json["scene"] = params.scenePath;
    json["setting"] = params.setting;
    json["link_mode"] = params.linkMode;
    json["backend"] = runtime->name();
    json["change"] = params.change;
    json["caches"] = bake->caches.size();
    json["bands"] = {{"y", bake->params.bandsY}, {"c", bake->params.bandsC}};
    json["coefficients_per_frame"] = values;
    json["levels"] = std::move(levels);
    json["frames"] = std::move(frames);
    const int written = writeJson(json, params.jsonPath);
    return charted != 0 ? charted : written;
}

}  // namespace pic
