#include "bench/picbench_cli.h"

#include <CLI/CLI.hpp>

#include "bake/bake_options_cli.h"
#include "bench/accuracy_benchmark.h"
#include "bench/glossy_benchmark.h"
#include "bench/bake_benchmark.h"
#include "bench/bench_common.h"
#include "bench/codec_benchmark.h"
#include "bench/image_compare.h"
#include "bench/link_error_benchmark.h"
#include "bench/runtime_benchmark.h"
#include "bench/stability_benchmark.h"
#include "bench/soak_benchmark.h"
#include "bench/budget_benchmark.h"
#include "bench/stream_benchmark.h"
#include "bench/sweep_benchmark.h"
#include "core/cli.h"

namespace pic {

namespace {

/// --scene FILE, the scene a benchmark runs on.
void addSceneOption(CLI::App& command, std::string& path) {
    command.add_option("--scene", path, "scene file (.gltf or .glb)")->required();
}

/// --chroma-bands L: lC of the settings' bakes (settingOptions).
void addChromaBandsOption(CLI::App& command, uint32_t& bands) {
    command.add_option("--chroma-bands", bands, "SH bands for chroma lC <= lY (default 2)")
        ->check(CLI::Range(1u, 8u));
}

/// --setting moderate|high: a row of paper 000's Table 2 (settingOptions).
void addSettingOption(CLI::App& command, std::string& setting) {
    command.add_option("--setting", setting, "paper 000 Table 2 setting (default: moderate)")
        ->check(CLI::IsMember({"moderate", "high"}));
}

/// The flags of `picbench sweep` and `picbench autotune`.
struct SweepFlags {
    SweepParams params;
    ViewFlags view;
    BakeOptionFlags bake;

    void addTo(CLI::App& command) {
        addSceneOption(command, params.scenePath);
        addLightsOption(command, params.lightsPath);
        view.addTo(command, {.size = "96x72", .sceneCamera = 0});
        command.add_option("--scene-cameras", params.sceneCameras,
                           "views: these scene cameras, each measured and the errors averaged (default: "
                           "--scene-camera's)");
        command.add_option("--grid", params.grid,
                           "settings grid: coarse (each parameter alone at 1-3 levels around the scene's "
                           "defaults, plus two cheaper diagonals; about 22 bakes) or fine (more levels "
                           "and a dearer diagonal; for a bigger machine) (default coarse)")
            ->check(CLI::IsMember({"coarse", "fine"}));
        command.add_option("--baselines", params.baselines,
                           "methods to compare with: ideal, traced, lpv (default: all three)")
            ->check(CLI::IsMember({"ideal", "traced", "lpv"}));
        command.add_option("--spp", params.spp, "reference samples per pixel (default 256)")
            ->check(CLI::Range(2u, 1u << 20));
        command.add_option("--probe-samples", params.probeSamples, "directions per ideal cache (default 256)")
            ->check(CLI::Range(4u, 1u << 20));
        command.add_option("--shade-spp", params.shadeSpp, "subsamples per pixel shading from caches (default 2)")
            ->check(CLI::Range(1u, 4096u));
        command.add_option("--repeat", params.repeat, "timed updates per backend (default 5)")
            ->check(CLI::Range(1, 1000));
        command.add_flag("!--no-gpu", params.gpu, "time the CPU twin only");
        addDeviceOption(command, params.device);
        command.add_option("--out-dir", params.outDir,
                           "folder of the sweep: references, finished points, CSV, JSON, charts; a "
                           "killed sweep resumes from it (default out/sweep/<scene>)");
        command.add_option("--picbake", params.picbake, "picbake binary (default: the build tree's)");
        command.add_option("--max-points", params.maxPoints,
                           "measure only the first N settings of the grid (default: all)");
        command.add_flag("--keep-bakes", params.keepBakes, "keep every setting's .pic file");
        bake.addTo(command);
    }

    /// The parameters after parsing.
    Result<SweepParams> toParams() {
        PIC_TRY_ASSIGN(params.view, view.toView());
        if (params.sceneCameras.empty()) params.sceneCameras = {params.view.sceneCameraIndex};
        params.baseBakeArgs = bake.toArgs();
        return params;
    }
};

}  // namespace

int picbenchMain(int argc, char** argv) {
    CLI::App app{"picbench: pic benchmarks (timings, memory, bytes) printed and written as JSON"};
    app.require_subcommand(1);
    addGlobalFlags(app);

    CLI::App* bake = app.add_subcommand("bake", "time every bake stage on one scene");
    BakeBenchmarkParams params;
    BakeOptionFlags flags;
    addSceneOption(*bake, params.scenePath);
    bake->add_option("--repeat", params.repeat, "bakes to run; stage times are medians (default 1)")
        ->check(CLI::PositiveNumber);
    bake->add_option("--json", params.jsonPath, "write the figures to this JSON file");
    flags.addTo(*bake);

    CLI::App* accuracy = app.add_subcommand("accuracy", "error of the cache term against a path-traced reference");
    AccuracyParams accuracyParams;
    BakeOptionFlags accuracyFlags;
    addSceneOption(*accuracy, accuracyParams.scenePath);
    addLightsOption(*accuracy, accuracyParams.lightsPath);
    ViewFlags accuracyView;
    accuracyView.addTo(*accuracy, {.size = "256x256", .sceneCamera = 0});
    accuracy->add_option("--spp", accuracyParams.spp, "reference samples per pixel (default 256)")->check(CLI::PositiveNumber);
    accuracy->add_option("--probe-samples", accuracyParams.probeSamples, "path-traced directions per ideal cache (default 1024)")
        ->check(CLI::PositiveNumber);
    accuracy->add_option("--shade-spp", accuracyParams.shadeSpp, "subsamples per pixel when shading from caches (default 4)")
        ->check(CLI::PositiveNumber);
    accuracy->add_option("--bounces", accuracyParams.bounces, "bounces (default: converged / unlimited)");
    accuracy->add_option("--out-dir", accuracyParams.outDir, "folder for images and JSON (default out/accuracy)");
    accuracy->add_option("--json", accuracyParams.jsonPath, "JSON file (default <out-dir>/<scene>_accuracy.json)");
    accuracy->add_option("--ref-seed", accuracyParams.seed, "path tracer seed (default 1)");
    accuracy
        ->add_option("--links-sweep", accuracyParams.linksSweep,
                     "links per cache to sweep: one bake each, the CPU twin's update time "
                     "against the indirect error, JSON and a PNG chart (replaces --links)")
        ->expected(1, -1)
        ->check(CLI::Range(1u, 4096u));
    accuracyFlags.addTo(*accuracy);

    CLI::App* glossy = app.add_subcommand(
        "glossy", "the glossy lobe from SH caches against the same lobe path-traced, over the "
                  "lobe's exponent and the SH bands (a table, JSON and a PNG chart)");
    GlossyParams glossyParams;
    BakeOptionFlags glossyFlags;
    addSceneOption(*glossy, glossyParams.scenePath);
    addLightsOption(*glossy, glossyParams.lightsPath);
    ViewFlags glossyView;
    glossyView.addTo(*glossy, {.size = "96x96", .sceneCamera = 0});
    glossy->add_option("--spp", glossyParams.spp, "reference samples per pixel (default 1024)")
        ->check(CLI::Range(2u, 1u << 20));
    glossy->add_option("--probe-samples", glossyParams.probeSamples,
                       "path-traced directions per ideal cache (default 2048)")
        ->check(CLI::PositiveNumber);
    glossy->add_option("--shade-spp", glossyParams.shadeSpp,
                       "subsamples per pixel shading from the caches (default 4)")
        ->check(CLI::Range(1u, 4096u));
    glossy->add_option("--truncate-bands", glossyParams.bands, "lY of the truncated ideal caches (default 1-8)")
        ->expected(1, -1);
    glossy->add_option("--exponents", glossyParams.exponents,
                       "Phong exponents (default 1 2 5 10 20 30)")
        ->expected(1, -1);
    glossy->add_option("--json", glossyParams.jsonPath, "JSON file; the PNG goes beside it (default out/glossy/glossy.json)");
    glossy->add_option("--ref-seed", glossyParams.seed, "path tracer and probe seed (default 1)");
    glossyFlags.addTo(*glossy);

    CLI::App* links = app.add_subcommand(
        "links", "decompose the linked caches' one-bounce error against path-traced radiance");
    LinkErrorParams linkParams;
    BakeOptionFlags linkFlags;
    addSceneOption(*links, linkParams.scenePath);
    addLightsOption(*links, linkParams.lightsPath);
    links->add_option("--caches", linkParams.caches, "caches to examine, spread over all (default 400)")
        ->check(CLI::PositiveNumber);
    links->add_option("--directions", linkParams.directions, "path-traced directions per cache (default 1024)")
        ->check(CLI::PositiveNumber);
    links->add_flag("--one-sided-truth", linkParams.oneSidedTruth,
                    "the traced first bounce takes no light off the back of a surface, as the surfels do (default: both faces reflect, as picref's path tracer)");
    links->add_option("--near", linkParams.near,
                      "x,y,z,r: examine only the caches within r metres of (x, y, z), the region an image shows (default: all caches)")
        ->delimiter(',')
        ->expected(4);
    links->add_option("--json", linkParams.jsonPath, "write the ratios to this JSON file");
    links->add_option("--ref-seed", linkParams.seed, "path tracer seed (default 1)");
    linkFlags.addTo(*links);

    CLI::App* runtime = app.add_subcommand(
        "runtime", "GPU backend against the CPU twin: ms per pass and update, link bandwidth, memory");
    RuntimeBenchmarkParams runtimeParams;
    addSceneOption(*runtime, runtimeParams.scenePath);
    addLightsOption(*runtime, runtimeParams.lightsPath);
    runtime->add_option("--settings", runtimeParams.settings, "paper 000 Table 2 settings (default: moderate high)")
        ->check(CLI::IsMember({"moderate", "high"}));
    runtime->add_option("--link-modes", runtimeParams.linkModes, "link forms (default: rtp sh)")
        ->check(CLI::IsMember({"rtp", "sh"}));
    addChromaBandsOption(*runtime, runtimeParams.chromaBands);
    runtime->add_option("--bounces", runtimeParams.bounces,
                        "bounces per update, −1 = progressive (default: 1 -1)");
    runtime->add_option("--repeat", runtimeParams.repeat, "timed updates per backend (default 5)")
        ->check(CLI::Range(1, 1000));
    addDeviceOption(*runtime, runtimeParams.device);
    runtime->add_option("--shadow-map-size", runtimeParams.shadowMapSize, "texels per shadow-map side (default 1024)")
        ->check(CLI::Range(16u, 16384u));
    runtime->add_option_function<std::string>(
               "--shadow-sides",
               [&](const std::string& sides) { runtimeParams.shadowEqualFootprint = sides == "footprint"; },
               "perspective shadow-map layers: footprint (as wide as gives the orthographic texel at "
               "the median surface distance) or uniform (all --shadow-map-size; default footprint)")
        ->check(CLI::IsMember({"footprint", "uniform"}));
    runtime
        ->add_option("--visibility", runtimeParams.visibilities,
                     "direct visibility of the GPU backend, one runtime each: auto (rays on a "
                     "CPU device, shadow maps on a GPU), shadow-maps, rays (default: auto)")
        ->check(CLI::IsMember({"auto", "shadow-maps", "rays"}));
    runtime
        ->add_option("--lightmap-copy", runtimeParams.lightmapCopy,
                     "where the GPU backend copies the caches into the textures: auto (the host "
                     "on a CPU device, the device on a GPU), host, device (default: auto)")
        ->check(CLI::IsMember({"auto", "host", "device"}));
    runtime->add_option("--changes", runtimeParams.changes,
                        "light changes: move-all, move-one, recolour (default: all three)")
        ->check(CLI::IsMember({"move-all", "move-one", "recolour"}));
    runtime->add_option("--json", runtimeParams.jsonPath, "JSON file (default out/runtime_benchmark.json)");

    CLI::App* shadows = app.add_subcommand(
        "shadows", "shadow-map size against time and direct-light error (GPU against the CPU twin's rays)");
    ShadowBenchmarkParams shadowParams;
    addSceneOption(*shadows, shadowParams.scenePath);
    addLightsOption(*shadows, shadowParams.lightsPath);
    addSettingOption(*shadows, shadowParams.setting);
    shadows->add_option("--sizes", shadowParams.sizes, "texels per shadow-map side (default: 256 512 1024 2048)")
        ->check(CLI::Range(16u, 16384u));
    shadows->add_option("--sides", shadowParams.sides,
                        "perspective layer sides: uniform, footprint (default: both)")
        ->check(CLI::IsMember({"uniform", "footprint"}));
    shadows->add_option("--repeat", shadowParams.repeat, "timed light changes per size (default 5)")
        ->check(CLI::Range(1, 1000));
    addDeviceOption(*shadows, shadowParams.device);
    shadows->add_option("--json", shadowParams.jsonPath, "JSON file (default out/shadow_benchmark.json)");

    CLI::App* codec = app.add_subcommand(
        "codec", "stream frame sizes (key and delta, bits per SH coefficient) and codec ms under light changes");
    CodecBenchmarkParams codecParams;
    addSceneOption(*codec, codecParams.scenePath);
    addLightsOption(*codec, codecParams.lightsPath);
    addSettingOption(*codec, codecParams.setting);
    addChromaBandsOption(*codec, codecParams.chromaBands);
    codec->add_option("--link-mode", codecParams.linkMode, "link form (default: rtp)")
        ->check(CLI::IsMember({"rtp", "sh"}));
    codec->add_option("--backend", codecParams.backend, "runtime backend (default: cpu)")
        ->check(CLI::IsMember({"cpu", "gpu"}));
    codec->add_option("--change", codecParams.change, "light change per update: move-one, move-all, recolour (default: move-one)")
        ->check(CLI::IsMember({"move-all", "move-one", "recolour"}));
    codec->add_option("--updates", codecParams.updates, "light changes after the first frame (default 10)")
        ->check(CLI::Range(1, 100000));
    codec
        ->add_option("--zstd-levels", codecParams.zstdLevels,
                     "zstd levels to code every frame at, charted as size against encode time "
                     "(default 1 3 6 9 19)")
        ->check(CLI::Range(1, 19));
    codec->add_option("--json", codecParams.jsonPath, "JSON file (default out/codec_benchmark.json)");

    CLI::App* budget = app.add_subcommand(
        "budget", "picserver --update-budget-ms: time to the first visible change and to the "
                  "final state against the budget, under load");
    BudgetBenchmarkParams budgetParams;
    addSceneOption(*budget, budgetParams.scenePath);
    budget->add_option("--bake", budgetParams.bakePath, "the scene's bake (default: one at --setting)")
        ->check(CLI::ExistingFile);
    addSettingOption(*budget, budgetParams.setting);
    budget->add_option("--backend", budgetParams.backend, "server backend (default: gpu)")
        ->check(CLI::IsMember({"cpu", "gpu"}));
    budget->add_option("--budgets", budgetParams.budgets,
                       "budgets in ms, 0 the unbudgeted baseline (default: 0 5 10 20 40 80)")
        ->check(CLI::Range(0.0, 1e6));
    budget->add_option("--clients", budgetParams.clients, "subscribers (default 64)")
        ->check(CLI::Range(1u, 10000u));
    budget->add_option("--duration", budgetParams.duration, "seconds of light changes per budget (default 10)")
        ->check(CLI::Range(0.1, 3600.0));
    budget->add_option("--update-rate", budgetParams.updateRate, "light changes per second (default 2)")
        ->check(CLI::Range(0.01, 1000.0));
    budget->add_option("--picserver", budgetParams.picserver, "picserver binary (default: the build tree's)");
    budget->add_option("--json", budgetParams.jsonPath, "JSON file (default out/budget_benchmark.json)");

    CLI::App* stream = app.add_subcommand(
        "stream", "the server under load: light-change latency to N subscribers, server CPU per "
                  "update, bytes per key and delta frame");
    StreamBenchmarkParams streamParams;
    addSceneOption(*stream, streamParams.scenePath);
    addSettingOption(*stream, streamParams.setting);
    stream->add_option("--link-mode", streamParams.linkMode, "link form (default: rtp)")
        ->check(CLI::IsMember({"rtp", "sh"}));
    stream->add_option("--backend", streamParams.backend, "server backend (default: gpu)")
        ->check(CLI::IsMember({"cpu", "gpu"}));
    stream->add_option("--bounces", streamParams.bounces, "cache passes per update (default 1)")
        ->check(CLI::Range(-1, 64));
    stream->add_option("--clients", streamParams.clients, "subscriber counts (default: 1 16 64 200)")
        ->check(CLI::Range(1u, 10000u));
    stream->add_option("--duration", streamParams.duration, "seconds of light changes per count (default 10)")
        ->check(CLI::PositiveNumber);
    stream->add_option("--update-rate", streamParams.updateRate, "light changes per second (default 2)")
        ->check(CLI::PositiveNumber);
    stream->add_option("--picserver", streamParams.picserver, "picserver binary (default: the build tree's)");
    stream->add_option("--json", streamParams.jsonPath, "JSON file (default out/stream_benchmark.json)");

    CLI::App* soak = app.add_subcommand(
        "soak", "the server held under load for a long time: no lost final state, resident "
                "memory growth, latency");
    SoakBenchmarkParams soakParams;
    addSceneOption(*soak, soakParams.scenePath);
    soak->add_option("--bake", soakParams.bakePath, "serve this bake of the scene (default: bake it at --setting)");
    addSettingOption(*soak, soakParams.setting);
    soak->add_option("--backend", soakParams.backend, "server backend (default: gpu)")
        ->check(CLI::IsMember({"cpu", "gpu"}));
    soak->add_option("--clients", soakParams.clients, "subscribers (default 200)")->check(CLI::Range(1u, 10000u));
    soak->add_option("--update-rate", soakParams.updateRate, "light changes per second (default 10)")
        ->check(CLI::PositiveNumber);
    soak->add_option("--duration", soakParams.duration, "seconds (default 600)")->check(CLI::PositiveNumber);
    soak->add_option("--max-rss-growth", soakParams.maxRssGrowthPercent,
                     "per cent of resident memory the server may grow by after the first tenth (default 5)")
        ->check(CLI::PositiveNumber);
    soak->add_option("--picserver", soakParams.picserver, "picserver binary (default: the build tree's)");
    soak->add_option("--json", soakParams.jsonPath, "JSON file (default out/soak.json), the chart beside it");

    CLI::App* stability = app.add_subcommand(
        "stability", "paper 000 §5.2 / 001 §7 failure cases against path tracing, a moving "
                     "light's flicker, random light sets checked for NaN, Inf and negative light");
    StabilityParams stabilityParams;
    BakeOptionFlags stabilityFlags;
    std::string stabilitySize = "64x48", randomSize = "32x24";
    stability->add_option("--scene-dir", stabilityParams.sceneDir,
                          "folder of the generated test scenes (default build/scenes)");
    stability->add_option("--cases", stabilityParams.cases,
                          "cases to run: leak spot colors moving random (default: all)")
        ->check(CLI::IsMember({"leak", "spot", "colors", "moving", "random"}));
    stability->add_option("--size", stabilitySize, "image size of the cases and the moving light (default 64x48)");
    stability->add_option("--spp", stabilityParams.settings.spp,
                          "path-traced reference samples per pixel; 0: none (default 256)");
    stability->add_option("--probe-samples", stabilityParams.settings.probeSamples,
                          "directions per ideal cache for the failure cases; 0: none (default 256)");
    stability->add_option("--shade-spp", stabilityParams.settings.shadeSpp,
                          "subsamples per pixel shading from the caches (default 2)")
        ->check(CLI::Range(1u, 4096u));
    stability->add_option("--steps", stabilityParams.steps, "moving-light steps (default 60)")
        ->check(CLI::Range(2u, 100000u));
    stability->add_option("--moving-scene", stabilityParams.movingScene,
                          "generated scene the light moves through (default furnished_room)");
    stability->add_option("--moving-probe-samples", stabilityParams.movingProbeSamples,
                          "directions per ideal cache at each moving-light step; 0: no ideal "
                          "sequence (default 128)");
    stability->add_option("--blend-intervals", stabilityParams.blendIntervals,
                          "blend times of a client drawing the moving light, in update "
                          "intervals (default 0 1 2 4)")
        ->check(CLI::NonNegativeNumber);
    stability->add_option("--frames-per-update", stabilityParams.framesPerUpdate,
                          "frames the blending client draws per version (default 4)")
        ->check(CLI::Range(1u, 64u));
    stability->add_option("--random-sets", stabilityParams.randomSets,
                          "random light sets, spread over the scenes in turn (default 1000)");
    stability->add_option("--random-scenes", stabilityParams.randomScenes,
                          "generated scenes the random sets relight (default: the nine small ones)");
    stability->add_option("--random-size", randomSize, "image size shaded per random set (default 32x24)");
    stability->add_option("--ref-seed", stabilityParams.settings.seed,
                          "first random-set seed, path seed of the moving light, path tracer seed (default 1)");
    stability->add_option("--json", stabilityParams.jsonPath,
                          "JSON file; PNGs go beside it (default out/stability/stability.json)");
    stabilityFlags.addTo(*stability);

    CLI::App* compare = app.add_subcommand(
        "compare", "relative RMSE of an image against a reference, per pixel and over blocks");
    ImageCompareParams compareParams;
    compare->add_option("image", compareParams.imagePath, "image to measure (.exr, .png, …)")
        ->required();
    compare->add_option("reference", compareParams.referencePath, "reference of the same size")
        ->required();
    compare->add_option("--blocks", compareParams.blocks,
                        "block sides in pixels the images are averaged over first (default 1 4 16)")
        ->check(CLI::PositiveNumber);
    compare->add_option("--json", compareParams.jsonPath, "write the figures to this JSON file");

    CLI::App* sweep = app.add_subcommand(
        "sweep", "bake and relight a scene over a grid of settings and the methods users would run "
                 "instead; error against the path-traced reference, update ms, memory, bytes; CSV, "
                 "JSON and Pareto charts");
    SweepFlags sweepFlags;
    sweepFlags.addTo(*sweep);
    sweep->add_option("--target-errors", sweepFlags.params.targetErrors,
                      "also bake with picbake --target-error E for each E and check each choice "
                      "against the grid (as autotune does)")
        ->check(CLI::Range(1e-6, 10.0));
    CLI::App* autotune = app.add_subcommand(
        "autotune", "the sweep, then picbake --target-error E for each E, each choice measured and "
                    "checked: its error against the truth at most E, its update at most 1.1 x the "
                    "cheapest swept point's that meets E");
    SweepFlags autotuneFlags;
    autotuneFlags.addTo(*autotune);
    autotune->add_option("--target-errors", autotuneFlags.params.targetErrors, "targets E to check")
        ->required()
        ->check(CLI::Range(1e-6, 10.0));

    if (auto exit = parseCommandLine(app, argc, argv)) return *exit;
    if (compare->parsed()) return runImageCompare(compareParams);
    for (SweepFlags* flags : {&sweepFlags, &autotuneFlags})
        if ((flags == &sweepFlags ? sweep : autotune)->parsed()) {
            auto params = flags->toParams();
            if (!params) return reportError(params.error());
            return runSweepBenchmark(*params);
        }
    if (stability->parsed()) {
        auto size = parseImageSize(stabilitySize);
        if (!size) return reportError(size.error());
        auto small = parseImageSize(randomSize);
        if (!small) return reportError(small.error());
        stabilityParams.settings.size = *size;
        stabilityParams.randomSize = *small;
        stabilityParams.bake = stabilityFlags.toOptions();
        return runStabilityBenchmark(stabilityParams);
    }
    if (accuracy->parsed()) {
        auto view = accuracyView.toView();
        if (!view) return reportError(view.error());
        accuracyParams.view = *view;
        accuracyParams.bake = accuracyFlags.toOptions();
        return runAccuracyBenchmark(accuracyParams);
    }
    if (glossy->parsed()) {
        auto view = glossyView.toView();
        if (!view) return reportError(view.error());
        glossyParams.view = *view;
        glossyParams.bake = glossyFlags.toOptions();
        return runGlossyBenchmark(glossyParams);
    }
    if (runtime->parsed()) return runRuntimeBenchmark(runtimeParams);
    if (shadows->parsed()) return runShadowBenchmark(shadowParams);
    if (codec->parsed()) return runCodecBenchmark(codecParams);
    if (budget->parsed()) return runBudgetBenchmark(budgetParams);
    if (stream->parsed()) return runStreamBenchmark(streamParams);
    if (soak->parsed()) return runSoakBenchmark(soakParams);
    if (links->parsed()) {
        linkParams.bake = linkFlags.toOptions();
        return runLinkErrorBenchmark(linkParams);
    }
    params.options = flags.toOptions();
    return runBakeBenchmark(params);
}

}  // namespace pic
