#include "bench/accuracy_benchmark.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "bake/ref/path_tracer.h"
#include "bake/ref/probes.h"
#include "bench/bench_common.h"
#include "core/color.h"
#include "core/gltf_loader.h"
#include "core/image.h"
#include "core/light_set.h"
#include "rays/embree_scene.h"
#include "render/cpu/cache_shading.h"
#include "render/cpu_runtime.h"

namespace pic {

namespace {

using Json = nlohmann::ordered_json;
using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

/// Error heat map: |luminance difference| / mean reference luminance, 0 → black, 0.5 → red,
/// ≥ 1 → yellow-white.
Image heatMap(const Image& image, const Image& reference) {
    double mean = 0.0;
    for (const glm::vec3& p : reference.pixels) mean += luminance(p);
    mean = std::max(mean / double(reference.pixels.size()), 1e-30);
    Image heat(image.width, image.height);
    for (size_t i = 0; i < heat.pixels.size(); ++i) {
        float e = static_cast<float>(std::abs(luminance(image.pixels[i]) - luminance(reference.pixels[i])) / mean);
        heat.pixels[i] = glm::vec3(glm::clamp(2.0f * e, 0.0f, 1.0f), glm::clamp(2.0f * e - 1.0f, 0.0f, 1.0f),
                                   glm::clamp(4.0f * e - 3.0f, 0.0f, 1.0f));
    }
    return heat;
}

/// Images placed left to right (all the same height); the heat map is not exposed.
Image sideBySide(const std::vector<Image>& images, const std::vector<float>& scales) {
    uint32_t width = 0;
    for (const Image& image : images) width += image.width;
    Image out(width, images.front().height);
    uint32_t x0 = 0;
    for (size_t k = 0; k < images.size(); ++k) {
        for (uint32_t y = 0; y < images[k].height; ++y)
            for (uint32_t x = 0; x < images[k].width; ++x) out.at(x0 + x, y) = images[k].at(x, y) * scales[k];
        x0 += images[k].width;
    }
    return out;
}

float exposureFor(const Image& reference) {
    double mean = 0.0;
    for (const glm::vec3& p : reference.pixels) mean += luminance(p);
    mean /= double(reference.pixels.size());
    return mean > 0.0 ? static_cast<float>(0.25 / mean) : 1.0f;
}

/// The inputs both modes report.
Json inputsJson(const AccuracyParams& params) {
    Json json;
    json["scene"] = params.scenePath;
    json["lights"] = params.lightsPath.empty() ? "scene" : params.lightsPath;
    json["size"] = fmt::format("{}x{}", params.view.size.x, params.view.size.y);
    json["reference_spp"] = params.spp;
    json["probe_samples"] = params.probeSamples;
    return json;
}

PathTraceParams referenceParams(const AccuracyParams& params, glm::uvec2 size,
                                PathTraceParams::Component component) {
    PathTraceParams trace;
    trace.width = size.x;
    trace.height = size.y;
    trace.spp = params.spp;
    trace.bounces = params.bounces;
    trace.seed = params.seed;
    trace.component = component;
    return trace;
}

Json errorJson(const ImageError& e) {
    return {{"relative_rmse", e.relativeRmse},
            {"rmse", e.rmse},
            {"mean_ratio", e.meanRatio},
            {"channel_ratio", {e.channelRatio.r, e.channelRatio.g, e.channelRatio.b}}};
}

/// `base` with the SH band 0 (`band0`) or the bands above it (otherwise) of `from`, in luma
/// and chroma: which bands of the linked caches the blotches are in.
CacheValues withBands(const CacheValues& base, const CacheValues& from, bool band0) {
    PIC_CHECK(base.bandsY == from.bandsY && base.bandsC == from.bandsC &&
              base.cacheCount() == from.cacheCount());
    CacheValues out = base;
    const size_t strideY = size_t{base.bandsY} * base.bandsY, strideC = size_t{base.bandsC} * base.bandsC;
    for (size_t c = 0; c < base.cacheCount(); ++c) {
        for (size_t i = 0; i < strideY; ++i)
            if ((i == 0) == band0) out.y[c * strideY + i] = from.y[c * strideY + i];
        for (size_t i = 0; i < strideC; ++i)
            if ((i == 0) == band0) {
                out.co[c * strideC + i] = from.co[c * strideC + i];
                out.cg[c * strideC + i] = from.cg[c * strideC + i];
            }
    }
    return out;
}

/// The speed/accuracy trade-off over nL: one reference and one set of ideal caches, one bake
/// per nL, each with its CPU twin's update time (median of three) and its indirect error.
int runLinksSweep(const AccuracyParams& params, const Scene& scene, const EmbreeScene& rays,
                  const Camera& camera, const LightSet& lights, glm::uvec2 size) {
    auto reference = pathTrace(scene, rays, lights, camera,
                               referenceParams(params, size, PathTraceParams::Component::Indirect));
    if (!reference) return reportError(reference.error());

    ShadeParams shade;
    shade.width = size.x;
    shade.height = size.y;
    shade.samplesPerPixel = params.shadeSpp;
    shade.component = ShadeComponent::Indirect;
    std::vector<uint32_t> sweep = params.linksSweep;
    std::sort(sweep.begin(), sweep.end());
    sweep.erase(std::unique(sweep.begin(), sweep.end()), sweep.end());

    Json json = inputsJson(params);
    json["runs"] = Json::array();
    std::optional<double> idealError;
    ChartSeries linked{"linked caches", glm::vec3(0.15f, 0.4f, 0.8f)};
    std::printf("%6s %9s %12s %14s %12s\n", "nL", "caches", "update ms", "indirect RMSE",
                "mean ratio");
    for (const uint32_t links : sweep) {
        BakeOptions options = params.bake;
        options.links = links;
        BakeReport report;
        std::fprintf(stderr, "picbench: baking nL %u …\n", links);
        auto bake = runBake(scene, options, report);
        if (!bake) return reportError(bake.error());
        auto runtime = createCpuRuntime(scene, rays, *bake, BounceParams{params.bounces});
        if (!runtime) return reportError(runtime.error());
        std::vector<double> updateMs;
        const CacheValues* values = nullptr;
        for (int k = 0; k < 3; ++k) {
            const Clock::time_point start = Clock::now();
            auto updated = (*runtime)->setLights(lights, nullptr);
            if (!updated) return reportError(updated.error());
            updateMs.push_back(1e3 * secondsSince(start));
            values = *updated;
        }
        std::sort(updateMs.begin(), updateMs.end());
        auto image = shadeFromCaches(scene, rays, *bake, *values, lights, camera, shade);
        if (!image) return reportError(image.error());
        auto error = compareImages(*image, *reference);
        if (!error) return reportError(error.error());
        if (!idealError) {
            // The ideal caches sit where every bake of this scene puts them (nL changes only
            // the links): their error is the floor that more links approach.
            ProbeParams probe;
            probe.samples = params.probeSamples;
            probe.bounces = params.bounces;
            probe.seed = params.seed;
            auto ideal = pathTraceProbes(scene, rays, *bake, lights, probe);
            if (!ideal) return reportError(ideal.error());
            auto idealImage = shadeFromCaches(scene, rays, *bake, *ideal, lights, camera, shade);
            if (!idealImage) return reportError(idealImage.error());
            auto e = compareImages(*idealImage, *reference);
            if (!e) return reportError(e.error());
            idealError = e->relativeRmse;
            json["ideal_indirect"] = errorJson(*e);
        }
        std::printf("%6u %9zu %12.1f %14.4f %12.4f\n", links, bake->caches.size(), updateMs[1],
                    error->relativeRmse, error->meanRatio);
        linked.points.push_back({updateMs[1], 100.0 * error->relativeRmse});
        linked.labels.push_back(fmt::format("nL {}", links));
        Json run;
        run["links_per_cache"] = links;
        run["unique_caches"] = bake->caches.size();
        run["update_ms_median"] = updateMs[1];
        run["update_ms"] = updateMs;
        run["indirect"] = errorJson(*error);
        json["runs"].push_back(std::move(run));
    }

    Chart chart;
    chart.title = fmt::format("Links per cache: CPU twin update time against error ({})",
                              std::filesystem::path(params.scenePath).stem().string());
    chart.xLabel = "CPU twin ms per update (median of 3)";
    chart.yLabel = "indirect relative RMSE against the path-traced reference, %";
    chart.logX = true;
    ChartSeries floor{"ideal (path-traced) caches", glm::vec3(0.4f), {}, {}, true};
    floor.points = {{linked.points.front().x, 100.0 * *idealError},
                    {linked.points.back().x, 100.0 * *idealError}};
    chart.series = {linked, floor};
    const std::string jsonPath =
        params.jsonPath.empty()
            ? (std::filesystem::path(params.outDir) /
               (std::filesystem::path(params.scenePath).stem().string() + "_links_sweep.json"))
                  .string()
            : params.jsonPath;
    std::error_code ec;
    std::filesystem::create_directories(std::filesystem::path(jsonPath).parent_path(), ec);
    if (int exit = writeJson(json, jsonPath); exit != 0) return exit;
    return writeChartFile(chart, chartPathFor(jsonPath));
}

}  // namespace

int runAccuracyBenchmark(const AccuracyParams& params) {
    const glm::uvec2 size = params.view.size;
    auto scene = loadScene(params.scenePath);
    if (!scene) return reportError(scene.error());
    auto camera = params.view.cameraIn(*scene);
    if (!camera) return reportError(camera.error());
    auto loaded = loadLightSet(params.lightsPath, *scene);
    if (!loaded) return reportError(loaded.error());
    const LightSet& lights = *loaded;
    if (!params.linksSweep.empty()) {
        auto rays = EmbreeScene::create(*scene);
        if (!rays) return reportError(rays.error());
        return runLinksSweep(params, *scene, **rays, *camera, lights, size);
    }

    Json seconds;
    auto start = Clock::now();
    BakeReport bakeReport;
    auto bake = runBake(*scene, params.bake, bakeReport);
    if (!bake) return reportError(bake.error());
    seconds["bake"] = secondsSince(start);

    auto rays = EmbreeScene::create(*scene);
    if (!rays) return reportError(rays.error());
    start = Clock::now();
    auto runtime = createCpuRuntime(*scene, **rays, *bake, BounceParams{params.bounces});
    if (!runtime) return reportError(runtime.error());
    UpdateStats update;
    auto values = (*runtime)->setLights(lights, &update);
    if (!values) return reportError(values.error());
    seconds["runtime_cpu"] = secondsSince(start);

    ShadeParams shade;
    shade.width = size.x;
    shade.height = size.y;
    shade.samplesPerPixel = params.shadeSpp;
    auto shadeBoth = [&](const CacheValues& caches, Image& full, Image& indirect) -> Result<void> {
        shade.component = ShadeComponent::Full;
        PIC_TRY_ASSIGN(full, shadeFromCaches(*scene, **rays, *bake, caches, lights, *camera, shade));
        shade.component = ShadeComponent::Indirect;
        PIC_TRY_ASSIGN(indirect, shadeFromCaches(*scene, **rays, *bake, caches, lights, *camera, shade));
        return {};
    };
    Image oursFull, oursIndirect;
    start = Clock::now();
    if (auto ok = shadeBoth(**values, oursFull, oursIndirect); !ok) return reportError(ok.error());
    seconds["shade"] = secondsSince(start);

    start = Clock::now();
    auto refFull = pathTrace(*scene, **rays, lights, *camera,
                             referenceParams(params, size, PathTraceParams::Component::Full));
    if (!refFull) return reportError(refFull.error());
    seconds["reference_full"] = secondsSince(start);
    start = Clock::now();
    auto refIndirect =
        pathTrace(*scene, **rays, lights, *camera,
                  referenceParams(params, size, PathTraceParams::Component::Indirect));
    if (!refIndirect) return reportError(refIndirect.error());
    seconds["reference_indirect"] = secondsSince(start);

    ProbeParams probe;
    probe.samples = params.probeSamples;
    probe.bounces = params.bounces;
    probe.seed = params.seed;
    start = Clock::now();
    auto ideal = pathTraceProbes(*scene, **rays, *bake, lights, probe);
    if (!ideal) return reportError(ideal.error());
    seconds["probes"] = secondsSince(start);
    Image idealFull, idealIndirect;
    start = Clock::now();
    if (auto ok = shadeBoth(*ideal, idealFull, idealIndirect); !ok) return reportError(ok.error());
    seconds["shade_ideal"] = secondsSince(start);

    auto compare = [&](const Image& a, const Image& b) { return compareImages(a, b); };
    auto eIndirect = compare(oursIndirect, *refIndirect);
    auto eFull = compare(oursFull, *refFull);
    auto eIdealIndirect = compare(idealIndirect, *refIndirect);
    auto eIdealFull = compare(idealFull, *refFull);
    for (const auto* e : {&eIndirect, &eFull, &eIdealIndirect, &eIdealFull})
        if (!*e) return reportError(e->error());
    // Blotches: where the linked caches disagree with the ideal ones beyond a global scale.
    auto blotch = blotchIndex(oursIndirect, idealIndirect);
    if (!blotch) return reportError(blotch.error());
    // Which SH bands the blotches are in: the ideal caches with the linked caches' band 0 put
    // in, and with their bands above 0 put in, each shaded and held against the ideal image.
    double blotchBand0 = 0.0, blotchAbove = 0.0;
    for (const bool band0 : {true, false}) {
        Image full, indirect;
        if (auto ok = shadeBoth(withBands(*ideal, **values, band0), full, indirect); !ok)
            return reportError(ok.error());
        auto b = blotchIndex(indirect, idealIndirect);
        if (!b) return reportError(b.error());
        (band0 ? blotchBand0 : blotchAbove) = *b;
    }

    std::error_code ec;
    std::filesystem::create_directories(params.outDir, ec);
    const std::string stem = std::filesystem::path(params.scenePath).stem().string();
    // Images are named after the JSON file when one is given, so runs with other settings
    // into the same folder do not overwrite each other.
    const std::string base = params.jsonPath.empty()
                                 ? (std::filesystem::path(params.outDir) / stem).string()
                                 : std::filesystem::path(params.jsonPath).replace_extension().string();
    const float exposureIndirect = exposureFor(*refIndirect), exposureFull = exposureFor(*refFull);
    for (const auto& [name, image] : std::vector<std::pair<std::string, const Image*>>{
             {"_ours_full.exr", &oursFull}, {"_ours_indirect.exr", &oursIndirect},
             {"_ref_full.exr", &*refFull}, {"_ref_indirect.exr", &*refIndirect},
             {"_ideal_indirect.exr", &idealIndirect}})
        if (auto ok = writeImage(base + name, *image); !ok) return reportError(ok.error());
    Image indirectSide = sideBySide({oursIndirect, idealIndirect, *refIndirect, heatMap(oursIndirect, *refIndirect)},
                                    {exposureIndirect, exposureIndirect, exposureIndirect, 1.0f});
    Image fullSide = sideBySide({oursFull, idealFull, *refFull, heatMap(oursFull, *refFull)},
                                {exposureFull, exposureFull, exposureFull, 1.0f});
    if (auto ok = writeImage(base + "_indirect_side.png", indirectSide); !ok) return reportError(ok.error());
    if (auto ok = writeImage(base + "_full_side.png", fullSide); !ok) return reportError(ok.error());

    Json json = inputsJson(params);
    json["bake"] = {{"surfels", bake->params.surfels}, {"links_per_cache", bake->params.linksPerCache},
                    {"link_mode", bake->params.linkMode == LinkMode::Sh ? "sh" : "rtp"},
                    {"bands_y", bake->params.bandsY}, {"bands_c", bake->params.bandsC},
                    {"grid_cell", bake->params.gridCell}, {"lightmap_texel", bake->params.lightmapTexel},
                    {"unique_caches", bake->caches.size()}};
    json["runtime_bounces"] = update.bounces;
    json["indirect"] = errorJson(*eIndirect);
    json["full"] = errorJson(*eFull);
    json["ideal_indirect"] = errorJson(*eIdealIndirect);
    json["ideal_full"] = errorJson(*eIdealFull);
    json["blotch_index"] = *blotch;
    json["blotch_index_by_band"] = {{"band_0", blotchBand0}, {"bands_above_0", blotchAbove}};
    json["seconds"] = seconds;
    json["images"] = {base + "_indirect_side.png", base + "_full_side.png"};
    const std::string jsonPath = params.jsonPath.empty() ? base + "_accuracy.json" : params.jsonPath;
    std::ofstream(jsonPath) << json.dump(2) << "\n";

    std::printf("%s: %ux%u, reference %u spp, %d runtime bounces, %zu caches\n", stem.c_str(), size.x,
                size.y, params.spp, update.bounces, bake->caches.size());
    std::printf("  %-22s %14s %12s %22s\n", "", "relative RMSE", "mean ratio", "R G B ratios");
    for (const auto& [name, e] : {std::pair{"indirect (linked)", &*eIndirect},
                                  std::pair{"indirect (ideal)", &*eIdealIndirect},
                                  std::pair{"full (linked)", &*eFull},
                                  std::pair{"full (ideal)", &*eIdealFull}})
        std::printf("  %-22s %14.4f %12.4f %8.3f %6.3f %6.3f\n", name, e->relativeRmse, e->meanRatio,
                    e->channelRatio.r, e->channelRatio.g, e->channelRatio.b);
    std::printf("  blotch index (linked against ideal caches, indirect, 4x4 blocks, mean-matched): %.4f\n",
                *blotch);
    std::printf("  the same with only the linked caches' band 0 (ideal above it): %.4f; with only their "
                "bands above 0 (ideal band 0): %.4f\n",
                blotchBand0, blotchAbove);
    std::printf("  seconds: %s\n", seconds.dump().c_str());
    std::printf("  wrote %s, %s_indirect_side.png, %s_full_side.png (ours | ideal caches | path traced | error)\n",
                jsonPath.c_str(), base.c_str(), base.c_str());
    return 0;
}

}  // namespace pic
