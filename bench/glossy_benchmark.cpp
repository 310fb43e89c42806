#include "bench/glossy_benchmark.h"

#include <cstdio>
#include <filesystem>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "bake/ref/path_tracer.h"
#include "bake/ref/probes.h"
#include "bench/bench_common.h"
#include "core/camera.h"
#include "core/gltf_loader.h"
#include "core/sh.h"
#include "render/cpu/cache_shading.h"
#include "render/cpu_runtime.h"

namespace pic {
namespace {

using Json = nlohmann::ordered_json;

/// The first `count` of every `stride` values, per cache.
std::vector<float> firstCoefficients(const std::vector<float>& values, size_t stride, size_t count) {
    std::vector<float> out;
    const size_t caches = stride ? values.size() / stride : 0;
    out.reserve(caches * count);
    for (size_t c = 0; c < caches; ++c)
        out.insert(out.end(), values.begin() + ptrdiff_t(c * stride),
                   values.begin() + ptrdiff_t(c * stride + count));
    return out;
}

/// Relative RMSE of `image` against `reference`, per pixel and over 4×4 blocks.
Result<std::pair<double, double>> errors(const Image& image, const Image& reference) {
    PIC_TRY_ASSIGN(ImageError pixel, compareImages(image, reference));
    PIC_TRY_ASSIGN(Image a, blockAverage(image, 4));
    PIC_TRY_ASSIGN(Image b, blockAverage(reference, 4));
    PIC_TRY_ASSIGN(ImageError block, compareImages(a, b));
    return std::pair{pixel.relativeRmse, block.relativeRmse};
}

}  // namespace

CacheValues truncateBands(const CacheValues& values, uint32_t bands) {
    PIC_CHECK(bands >= 1 && bands <= values.bandsC && values.bandsC <= values.bandsY);
    CacheValues out;
    out.bandsY = bands;
    out.bandsC = bands;
    const size_t count = size_t{bands} * bands;
    out.y = firstCoefficients(values.y, size_t{values.bandsY} * values.bandsY, count);
    out.co = firstCoefficients(values.co, size_t{values.bandsC} * values.bandsC, count);
    out.cg = firstCoefficients(values.cg, size_t{values.bandsC} * values.bandsC, count);
    return out;
}

int runGlossyBenchmark(const GlossyParams& params) {
    for (const uint32_t b : params.bands)
        if (b < 1 || b > uint32_t(kMaxShBands))
            return reportError({ErrorCode::InvalidInput,
                                fmt::format("--truncate-bands {} is outside 1..{}", b, kMaxShBands)});
    for (const float n : params.exponents)
        if (!(n > 0.0f && std::isfinite(n)))
            return reportError({ErrorCode::InvalidInput,
                                fmt::format("--exponents {} must be finite and > 0", n)});
    if (params.spp < 2)
        return reportError({ErrorCode::InvalidInput,
                            fmt::format("--spp {} must be at least 2 (two halves)", params.spp)});
    auto inputs = loadBenchInputs(params.scenePath, params.lightsPath);
    if (!inputs) return 2;
    const Scene& scene = inputs->scene;
    const EmbreeScene& rays = *inputs->rays;
    const LightSet& lights = inputs->lights;
    auto camera = params.view.cameraIn(scene);
    if (!camera) return reportError(camera.error());

    std::fprintf(stderr, "picbench glossy: baking %s …\n", scene.sourcePath.c_str());
    BakeReport report;
    auto bake = runBake(scene, params.bake, report);
    if (!bake) return reportError(bake.error());
    auto runtime = createCpuRuntime(scene, rays, *bake, BounceParams{});
    if (!runtime) return reportError(runtime.error());
    auto linked = (*runtime)->setLights(lights);
    if (!linked) return reportError(linked.error());

    // Ideal caches: the incident radiance path-traced at every cache and projected to the
    // most bands, of which each lY keeps the first.
    BakeData full = *bake;
    full.params.bandsY = uint32_t(kMaxShBands);
    full.params.bandsC = uint32_t(kMaxShBands);
    ProbeParams probe;
    probe.samples = params.probeSamples;
    probe.seed = params.seed;
    std::fprintf(stderr, "picbench glossy: path tracing %zu ideal caches, %u directions each …\n",
                 bake->caches.size(), params.probeSamples);
    auto ideal = pathTraceProbes(scene, rays, full, lights, probe);
    if (!ideal) return reportError(ideal.error());

    ShadeParams shade;
    shade.width = params.view.size.x;
    shade.height = params.view.size.y;
    shade.samplesPerPixel = params.shadeSpp;
    shade.component = ShadeComponent::Glossy;
    shade.glossyWeight = 1.0f;

    Json json;
    json["scene"] = scene.sourcePath;
    json["size"] = {shade.width, shade.height};
    json["reference_spp"] = params.spp;
    json["probe_samples"] = params.probeSamples;
    json["linked_bands"] = {bake->params.bandsY, bake->params.bandsC};
    json["rows"] = Json::array();
    std::printf("glossy term, relative RMSE per pixel against picref (%u spp), ideal caches "
                "truncated to lY bands | the bake's linked caches (lY %u, lC %u) | the "
                "reference's own noise\n",
                params.spp, bake->params.bandsY, bake->params.bandsC);
    std::printf("%8s", "n");
    for (const uint32_t b : params.bands) std::printf("  lY %u ", b);
    std::printf("  linked   noise\n");

    std::vector<ChartSeries> perBands;
    for (size_t i = 0; i < params.bands.size(); ++i) {
        const float t = params.bands.size() > 1 ? float(i) / float(params.bands.size() - 1) : 0.0f;
        perBands.push_back({fmt::format("ideal caches, lY {}", params.bands[i]),
                            glm::vec3(0.1f + 0.8f * t, 0.3f + 0.3f * (1.0f - t), 0.9f - 0.7f * t)});
    }
    ChartSeries linkedSeries{fmt::format("linked caches (lY {}, lC {})", bake->params.bandsY,
                                         bake->params.bandsC),
                             glm::vec3(0.1f), {}, {}, true};
    ChartSeries noiseSeries{"reference noise", glm::vec3(0.6f), {}, {}, true};

    for (const float n : params.exponents) {
        shade.glossyExponent = n;
        PathTraceParams trace;
        trace.width = shade.width;
        trace.height = shade.height;
        trace.spp = params.spp / 2;
        trace.component = PathTraceParams::Component::Glossy;
        trace.glossyExponent = n;
        trace.glossyWeight = 1.0f;
        std::fprintf(stderr, "picbench glossy: exponent %g: path tracing the reference …\n", n);
        Image halves[2];
        for (int h = 0; h < 2; ++h) {
            trace.seed = params.seed + uint64_t(h) * 7919u;
            auto half = pathTrace(scene, rays, lights, *camera, trace);
            if (!half) return reportError(half.error());
            halves[h] = std::move(*half);
        }
        Image reference = halves[0];
        for (size_t p = 0; p < reference.pixels.size(); ++p)
            reference.pixels[p] = 0.5f * (halves[0].pixels[p] + halves[1].pixels[p]);
        // The mean of two halves differs from the truth by half their difference.
        auto spread = compareImages(halves[0], halves[1]);
        if (!spread) return reportError(spread.error());
        const double noise = 0.5 * spread->relativeRmse;

        Json row;
        row["exponent"] = n;
        row["reference_noise"] = noise;
        row["ideal"] = Json::array();
        std::printf("%8g", n);
        for (size_t i = 0; i < params.bands.size(); ++i) {
            const CacheValues truncated = truncateBands(*ideal, params.bands[i]);
            auto image = shadeFromCaches(scene, rays, *bake, truncated, lights, *camera, shade);
            if (!image) return reportError(image.error());
            auto error = errors(*image, reference);
            if (!error) return reportError(error.error());
            std::printf("  %6.3f", error->first);
            row["ideal"].push_back(
                {{"bands", params.bands[i]}, {"pixel", error->first}, {"block4", error->second}});
            perBands[i].points.push_back({double(n), error->first});
        }
        auto image = shadeFromCaches(scene, rays, *bake, **linked, lights, *camera, shade);
        if (!image) return reportError(image.error());
        auto error = errors(*image, reference);
        if (!error) return reportError(error.error());
        std::printf("  %6.3f  %6.3f\n", error->first, noise);
        row["linked"] = {{"pixel", error->first}, {"block4", error->second}};
        linkedSeries.points.push_back({double(n), error->first});
        noiseSeries.points.push_back({double(n), noise});
        json["rows"].push_back(std::move(row));
    }

    Chart chart;
    chart.title = fmt::format("Glossy lobe from SH caches against path tracing ({})",
                              std::filesystem::path(params.scenePath).stem().string());
    chart.xLabel = "Phong exponent n";
    chart.yLabel = "glossy term, relative RMSE per pixel";
    chart.series = perBands;
    chart.series.push_back(linkedSeries);
    chart.series.push_back(noiseSeries);
    if (int exit = writeJson(json, params.jsonPath); exit != 0) return exit;
    return writeChartFile(chart, chartPathFor(params.jsonPath));
}

}  // namespace pic
