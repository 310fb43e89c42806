#include "bench/codec_benchmark.h"

#include <chrono>
#include <cstdio>

#include "bench/bench_common.h"
#include "core/frame_codec.h"
#include "server/cpu/cpu_runtime.h"
#include "server/encoder.h"
#include "server/gpu/gpu_runtime.h"

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
    auto bake = runBake(scene, settingOptions(params.setting, params.linkMode), bakeReport);
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

    const double cacheCoefficients =
        double(bake->caches.size()) *
        double(bake->params.bandsY * bake->params.bandsY + 2 * bake->params.bandsC * bake->params.bandsC);
    const float step = 1e-3f * scene.bounds.diagonal();
    std::vector<double> keyBits, deltaBits, keyCacheBits, deltaCacheBits, encodeMs, decodeMs;
    nlohmann::ordered_json frames = nlohmann::ordered_json::array();
    HalfFrame previous;
    double values = 0.0;
    std::printf("%-7s %12s %12s %14s %14s %10s %10s\n", "update", "key bytes", "delta bytes",
                "key bits/val", "delta bits/val", "encode ms", "decode ms");
    for (int k = 0; k <= params.updates; ++k) {
        if (auto caches = runtime->setLights(changedLights(inputs->lights, k, step, params.change)); !caches)
            return reportError(caches.error());
        auto textures = runtime->textures();
        if (!textures) return reportError(textures.error());
        const HalfFrame frame = halfFrameOf(**textures);
        values = double(frameValues(frame));

        Clock::time_point start = Clock::now();
        auto key = encodeFrame(frame, nullptr, params.zstdLevel);
        const double keyMs = msSince(start);
        if (!key) return reportError(key.error());
        nlohmann::ordered_json row{{"update", k}, {"key_bytes", key->bytes()}, {"key_encode_ms", keyMs}};
        if (k == 0) {
            std::printf("%-7d %12zu %12s %14.2f %14s %10.2f %10s\n", k, key->bytes(), "-",
                        8.0 * double(key->bytes()) / values, "-", keyMs, "-");
        } else {
            start = Clock::now();
            auto delta = encodeFrame(frame, &previous, params.zstdLevel);
            const double deltaMs = msSince(start);
            if (!delta) return reportError(delta.error());
            // The receiver holds the previous version and applies the delta.
            HalfFrame received = previous;
            start = Clock::now();
            if (auto decoded = decodeFrame(*delta, received); !decoded) return reportError(decoded.error());
            const double ms = msSince(start);
            if (!(received == frame)) {
                std::fprintf(stderr, "picbench: error: update %d: decoding the delta frame did not give back the encoder's input\n", k);
                return 1;
            }
            keyBits.push_back(8.0 * double(key->bytes()) / values);
            deltaBits.push_back(8.0 * double(delta->bytes()) / values);
            keyCacheBits.push_back(8.0 * double(key->bytes()) / cacheCoefficients);
            deltaCacheBits.push_back(8.0 * double(delta->bytes()) / cacheCoefficients);
            encodeMs.push_back(deltaMs);
            decodeMs.push_back(ms);
            std::printf("%-7d %12zu %12zu %14.2f %14.2f %10.2f %10.2f\n", k, key->bytes(), delta->bytes(),
                        keyBits.back(), deltaBits.back(), deltaMs, ms);
            row["delta_bytes"] = delta->bytes();
            row["delta_encode_ms"] = deltaMs;
            row["delta_decode_ms"] = ms;
        }
        frames.push_back(row);
        previous = frame;
    }
    std::printf("medians: key %.2f bits per texture value (%.2f per cache coefficient), delta %.2f "
                "(%.2f); encode %.2f ms, decode %.2f ms\n",
                median(keyBits), median(keyCacheBits), median(deltaBits), median(deltaCacheBits),
                median(encodeMs), median(decodeMs));

    nlohmann::ordered_json json;
    json["scene"] = params.scenePath;
    json["setting"] = params.setting;
    json["link_mode"] = params.linkMode;
    json["backend"] = runtime->name();
    json["change"] = params.change;
    json["zstd_level"] = params.zstdLevel;
    json["caches"] = bake->caches.size();
    json["bands"] = {{"y", bake->params.bandsY}, {"c", bake->params.bandsC}};
    json["texture_values_per_frame"] = values;
    json["cache_coefficients"] = cacheCoefficients;
    json["key_bits_per_value_median"] = median(keyBits);
    json["delta_bits_per_value_median"] = median(deltaBits);
    json["key_bits_per_cache_coefficient_median"] = median(keyCacheBits);
    json["delta_bits_per_cache_coefficient_median"] = median(deltaCacheBits);
    json["delta_encode_ms_median"] = median(encodeMs);
    json["delta_decode_ms_median"] = median(decodeMs);
    json["frames"] = frames;
    return writeJson(json, params.jsonPath);
}

}  // namespace pic
