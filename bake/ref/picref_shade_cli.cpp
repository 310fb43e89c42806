#include "bake/ref/picref_shade_cli.h"

#include <chrono>
#include <cstdio>
#include <memory>
#include <string>

#include <CLI/CLI.hpp>

#include "core/bake_file.h"
#include "core/cli.h"
#include "core/gltf_loader.h"
#include "core/image.h"
#include "core/light_set.h"
#include "core/parallel.h"
#include "rays/embree_scene.h"
#include "render/cpu/cache_shading.h"
#include "render/cpu_runtime.h"
#include "render/gpu_runtime.h"
#include "render/gpu_runtime_flags.h"

namespace pic {
namespace {

using Clock = std::chrono::steady_clock;

double millisecondsSince(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

int reportError(const Error& error) { return pic::reportError("picref shade", error); }

/// What the command line asked for, before any file is read.
struct ShadeCommand {
    std::string scenePath;
    std::string bakePath;
    std::string backend = "cpu";
    GpuRuntimeOptions gpu;  ///< the gpu backend's flags
    std::string lightsPath;
    ViewFlags view;
    ShadeFlags shade;
    int bounces = -1;
    uint32_t spp = 4;  // picclient render --samples' default
    ImageOutputFlags output;
    ObjectFlags objects;
};

/// Checks what can be checked without reading files, so that usage errors come first.
Result<void> checkUsage(const ShadeCommand& command) {
    if (command.bounces < -1)
        return fail(ErrorCode::InvalidInput, "--bounces {} must be ≥ 0 (or −1: until converged)",
                    command.bounces);
    return command.output.check();
}

/// Loads everything, relights on the chosen backend, shades on the CPU and writes the image.
int runShade(const ShadeCommand& command) {
    if (auto usage = checkUsage(command); !usage) return reportError(usage.error());
    auto view = command.view.toView();
    if (!view) return reportError(view.error());
    auto placements = command.objects.placements();
    if (!placements) return reportError(placements.error());

    auto scene = loadScene(command.scenePath);
    if (!scene) return reportError(scene.error());
    // The cheap header check first: a bake of another scene is refused before its arrays load.
    auto info = inspectBakeFile(command.bakePath);
    if (!info) return reportError(info.error());
    if (auto match = checkSceneMatches(*info, scene->hash, command.scenePath); !match)
        return reportError(match.error());
    auto bake = readBakeFile(command.bakePath);
    if (!bake) return reportError(bake.error());

    auto camera = view->cameraIn(*scene);
    if (!camera) return reportError(camera.error());

    auto loaded = loadLightSet(command.lightsPath, *scene);
    if (!loaded) return reportError(loaded.error());
    const LightSet& lights = *loaded;

    auto rays = EmbreeScene::create(*scene);
    if (!rays) return reportError(rays.error());
    Result<std::unique_ptr<Runtime>> runtime;
    if (command.backend == "gpu") {
        auto gpu =
            GpuRuntime::create(*scene, **rays, *bake, BounceParams{command.bounces}, command.gpu);
        if (!gpu) return reportError(gpu.error());
        std::fprintf(stderr, "picref shade: GPU backend on \"%s\", direct visibility by %s\n",
                     (*gpu)->context().deviceName().c_str(),
                     gpu::directVisibilityName((*gpu)->directVisibility()));
        runtime = std::unique_ptr<Runtime>(std::move(*gpu));
    } else {
        runtime = createCpuRuntime(*scene, **rays, *bake, BounceParams{command.bounces});
    }
    if (!runtime) return reportError(runtime.error());

    UpdateStats stats;
    auto values = (*runtime)->setLights(lights, &stats);
    if (!values) return reportError(values.error());
    std::string passes;
    for (const auto& [pass, ms] : stats.passMs)
        passes += fmt::format("{}{} {:.1f}", passes.empty() ? "" : ", ", pass, ms);
    std::fprintf(stderr, "picref shade: update on %s: %d bounces, %.1f ms (ms per pass: %s)\n",
                 (*runtime)->name(), stats.bounces, stats.totalMs, passes.c_str());

    // Dynamic objects join the shaded scene only, as in the client: the caches were lit
    // without them, and their triangles read the grid.
    const Scene* shaded = &*scene;
    const EmbreeScene* shadedRays = rays->get();
    Scene placed;
    std::unique_ptr<EmbreeScene> placedRays;
    BakeData withObjects;
    const BakeData* shadedBake = &*bake;
    if (!placements->empty()) {
        auto built = placeObjects(*scene, *placements);
        if (!built) return reportError(built.error());
        placed = std::move(*built);
        auto builtRays = EmbreeScene::create(placed);
        if (!builtRays) return reportError(builtRays.error());
        placedRays = std::move(*builtRays);
        withObjects = *bake;
        withObjects.sceneHash = placed.hash;
        withObjects.lightmap.triangleUvs.resize(3 * placed.triangles.size(),
                                                glm::vec2(kNotLightmapped));
        const double covered =
            gridCoverage(placed, scene->vertices.size(), bake->grid.origin, bake->grid.cellSize,
                         bake->grid.dims, bake->grid.cacheIndex);
        if (const std::string warning = gridCoverageWarning(covered); !warning.empty())
            std::fprintf(stderr, "picref shade: warning: %s\n", warning.c_str());
        shaded = &placed;
        shadedRays = placedRays.get();
        shadedBake = &withObjects;
    }
    const ShadeParams params = command.shade.toParams(view->size, command.spp);
    const auto shadeStart = Clock::now();
    auto image =
        shadeFromCaches(*shaded, *shadedRays, *shadedBake, **values, lights, *camera, params);
    if (!image) return reportError(image.error());
    const double shadeMs = millisecondsSince(shadeStart);

    if (auto written = command.output.write(*image); !written) return reportError(written.error());
    std::fprintf(stderr, "picref shade: shading %ux%u, %u spp, %s: %.1f ms on %d threads -> %s\n",
                 params.width, params.height, params.samplesPerPixel, command.shade.component().c_str(),
                 shadeMs, workerCount(), command.output.path().c_str());
    return 0;
}

}  // namespace

int picrefShadeMain(int argc, char** argv) {
    CLI::App app{
        "picref shade: relights a bake with the runtime passes on one backend and shades "
        "a camera view from its caches on the CPU"};
    app.name("picref shade");
    ShadeCommand command;
    app.add_option("scene", command.scenePath, "scene file (.gltf or .glb)")->required();
    app.add_option("--bake", command.bakePath, "bake file of this scene (.pic)")->required();
    app.add_option("--backend", command.backend, "runtime backend")
        ->check(CLI::IsMember({"cpu", "gpu"}));
    addGpuRuntimeFlags(app, command.gpu);
    addLightsOption(app, command.lightsPath);
    command.view.addTo(app);
    command.shade.addTo(app);
    app.add_option("--bounces", command.bounces,
                   "cache passes: 0 = direct light only, B = up to B reflections (default: until "
                   "a bounce adds < 0.5 % of the flux, at most 8)");
    app.add_option("--spp", command.spp,
                   "subsamples per pixel, averaged (default 4, as picclient render --samples; "
                   "1: pixel centres)")
        ->check(CLI::Range(1u, kMaxSamplesPerPixel));
    addGlobalFlags(app);
    command.output.addTo(app);
    command.objects.addTo(app);

    if (auto exit = parseCommandLine(app, argc, argv)) return *exit;
    return runShade(command);
}

}  // namespace pic
