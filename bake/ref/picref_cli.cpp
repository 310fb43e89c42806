#include "bake/ref/picref_cli.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "bake/ref/path_tracer.h"
#include "bake/ref/probes.h"
#include "core/bake_file.h"
#include "core/cli.h"
#include "core/gltf_loader.h"
#include "core/image.h"
#include "core/light_set.h"
#include "core/parallel.h"
#include "rays/embree_scene.h"

namespace pic {

namespace {

using Json = nlohmann::ordered_json;
namespace fs = std::filesystem;

int reportError(const Error& error) { return pic::reportError("picref", error); }

/// Says how many path samples were NaN, infinite or negative and counted as zero, if any.
void warnAboutRejectedSamples(const PathTraceStats& stats) {
    if (stats.rejected)
        std::fprintf(stderr,
                     "picref: warning: %llu of %llu samples were NaN, infinite or negative "
                     "and counted as zero\n",
                     static_cast<unsigned long long>(stats.rejected),
                     static_cast<unsigned long long>(stats.samples));
}

/// Writes `bytes` to `path` through a temporary file and a rename.
Result<void> writeFileAtomically(const std::string& path, const std::string& bytes) {
    std::string temporary = path + ".tmp";
    {
        std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
        out.write(bytes.data(), std::streamsize(bytes.size()));
        if (!out) return fail(ErrorCode::Io, "cannot write '{}'", temporary);
    }
    std::error_code ec;
    fs::rename(temporary, path, ec);
    if (ec)
        return fail(ErrorCode::Io, "cannot rename '{}' to '{}': {}", temporary, path, ec.message());
    return {};
}

/// The flags of `picref SCENE …`.
struct RenderArgs {
    std::string scenePath;
    View view;
    uint32_t spp = 0;
    int bounces = -1;
    std::string component = "full";
    float glossyExponent = 0.0f;
    float glossyWeight = 0.0f;
    std::string lightsPath;
    uint64_t seed = 1;
    ImageOutputFlags output;
    ObjectFlags objects;
};

int runRender(const RenderArgs& args) {
    if (args.spp == 0)
        return reportError({ErrorCode::InvalidInput, "--spp must be at least 1, got 0"});
    if (args.component == "glossy" && args.glossyExponent <= 0.0f)
        return reportError({ErrorCode::InvalidInput,
                            "--component glossy needs the lobe: --glossy N --glossy-weight W"});
    if (args.bounces < -1)
        return reportError(
            {ErrorCode::InvalidInput,
             fmt::format("--bounces must be -1 (unlimited) or >= 0, got {}", args.bounces)});
    if (auto output = args.output.check(); !output) return reportError(output.error());
    auto placements = args.objects.placements();
    if (!placements) return reportError(placements.error());

    auto scene = loadScene(args.scenePath);
    if (!scene) return reportError(scene.error());
    // Dynamic objects are part of the scene the reference traces: their shadows, their
    // reflections and the light they block all count.
    if (!placements->empty()) scene = placeObjects(*scene, *placements);
    if (!scene) return reportError(scene.error());
    auto camera = args.view.cameraIn(*scene);
    if (!camera) return reportError(camera.error());
    auto lights = loadLightSet(args.lightsPath, *scene);
    if (!lights) return reportError(lights.error());
    auto rays = EmbreeScene::create(*scene);
    if (!rays) return reportError(rays.error());

    PathTraceParams params;
    params.width = args.view.size.x;
    params.height = args.view.size.y;
    params.spp = args.spp;
    params.bounces = args.bounces;
    params.component = args.component == "direct"     ? PathTraceParams::Component::Direct
                       : args.component == "indirect" ? PathTraceParams::Component::Indirect
                       : args.component == "cached"   ? PathTraceParams::Component::Cached
                       : args.component == "glossy"   ? PathTraceParams::Component::Glossy
                                                      : PathTraceParams::Component::Full;
    params.seed = args.seed;
    params.glossyExponent = args.glossyExponent;
    params.glossyWeight = args.glossyWeight;
    PathTraceStats stats;
    auto image = pathTrace(*scene, **rays, *lights, *camera, params, &stats);
    if (!image) return reportError(image.error());
    if (auto written = args.output.write(*image); !written) return reportError(written.error());

    std::fprintf(
        stderr,
        "picref: %ux%u, %u spp, %s, bounces %d: %.3f s, %.3f M samples/s on %d threads -> %s\n",
        params.width, params.height, params.spp, args.component.c_str(), params.bounces,
        stats.seconds, double(stats.samples) / stats.seconds / 1e6, workerCount(),
        args.output.path().c_str());
    warnAboutRejectedSamples(stats);
    return 0;
}

/// The flags of `picref probes BAKE.pic …`.
struct ProbeArgs {
    std::string bakePath;
    std::string scenePath;
    std::string lightsPath;
    ProbeParams params;
    std::string outPath;
    std::string binaryPath;
};

/// The binary form of the ideal caches (--binary): no header, little-endian float32 arrays
/// in CacheValues order, one after the other: y (nC·lY² values), co (nC·lC²), cg (nC·lC²),
/// each cache-major; nC, lY and lC are in the JSON written beside it.
std::string binaryCacheValues(const CacheValues& values) {
    std::string bytes;
    for (const std::vector<float>* array : {&values.y, &values.co, &values.cg})
        bytes.append(reinterpret_cast<const char*>(array->data()), array->size() * sizeof(float));
    return bytes;
}

int runProbes(const ProbeArgs& args) {
    if (args.params.samples == 0)
        return reportError({ErrorCode::InvalidInput, "--samples must be at least 1, got 0"});
    if (args.params.bounces < -1)
        return reportError(
            {ErrorCode::InvalidInput,
             fmt::format("--bounces must be -1 (unlimited) or >= 0, got {}", args.params.bounces)});
    if (auto ok = checkOutputPath(args.outPath, {".json"}, "--out"); !ok)
        return reportError(ok.error());
    if (!args.binaryPath.empty())
        if (auto ok = checkOutputPath(args.binaryPath, {".bin"}, "--binary"); !ok)
            return reportError(ok.error());

    auto info = inspectBakeFile(args.bakePath);
    if (!info) return reportError(info.error());
    auto scene = loadScene(args.scenePath);
    if (!scene) return reportError(scene.error());
    if (auto matches = checkSceneMatches(*info, scene->hash, args.scenePath); !matches)
        return reportError(matches.error());
    auto bake = readBakeFile(args.bakePath);
    if (!bake) return reportError(bake.error());
    auto lights = loadLightSet(args.lightsPath, *scene);
    if (!lights) return reportError(lights.error());
    auto rays = EmbreeScene::create(*scene);
    if (!rays) return reportError(rays.error());

    PathTraceStats stats;
    auto values = pathTraceProbes(*scene, **rays, *bake, *lights, args.params, &stats);
    if (!values) return reportError(values.error());

    Json out;
    out["bake"] = args.bakePath;
    out["scene"] = args.scenePath;
    out["bands"] = {{"y", values->bandsY}, {"c", values->bandsC}};
    out["samples"] = args.params.samples;
    out["bounces"] = args.params.bounces;
    out["seed"] = args.params.seed;
    out["indirect_only"] = args.params.indirectOnly;
    if (!args.binaryPath.empty()) out["binary"] = args.binaryPath;
    Json caches = Json::array();
    const size_t countY = size_t(values->bandsY) * values->bandsY;
    const size_t countC = size_t(values->bandsC) * values->bandsC;
    for (size_t c = 0; c < bake->caches.size(); ++c) {
        const Cache& cache = bake->caches[c];
        Json entry;
        entry["position"] = {cache.position.x, cache.position.y, cache.position.z};
        entry["kind"] = cache.kind == gpu::kCacheKindLightmap ? "lightmap" : "grid";
        if (cache.kind == gpu::kCacheKindLightmap)
            entry["normal"] = {cache.normal.x, cache.normal.y, cache.normal.z};
        entry["y"] = std::vector<float>(values->y.begin() + std::ptrdiff_t(c * countY),
                                        values->y.begin() + std::ptrdiff_t((c + 1) * countY));
        entry["co"] = std::vector<float>(values->co.begin() + std::ptrdiff_t(c * countC),
                                         values->co.begin() + std::ptrdiff_t((c + 1) * countC));
        entry["cg"] = std::vector<float>(values->cg.begin() + std::ptrdiff_t(c * countC),
                                         values->cg.begin() + std::ptrdiff_t((c + 1) * countC));
        caches.push_back(std::move(entry));
    }
    out["caches"] = std::move(caches);

    if (!args.binaryPath.empty())
        if (auto written = writeFileAtomically(args.binaryPath, binaryCacheValues(*values));
            !written)
            return reportError(written.error());
    if (auto written = writeFileAtomically(args.outPath, out.dump(1) + "\n"); !written)
        return reportError(written.error());

    std::fprintf(
        stderr,
        "picref: %zu caches, %u samples each: %.3f s, %.3f M samples/s on %d threads -> %s\n",
        bake->caches.size(), args.params.samples, stats.seconds,
        double(stats.samples) / std::max(stats.seconds, 1e-9) / 1e6, workerCount(),
        args.outPath.c_str());
    warnAboutRejectedSamples(stats);
    return 0;
}

}  // namespace

int picrefMain(int argc, char** argv) {
    CLI::App app{
        "picref: path-traced reference images (picref SCENE …) and ideal caches "
        "(picref probes BAKE.pic …)"};
    app.require_subcommand(0, 1);
    addGlobalFlags(app);

    RenderArgs render;
    CLI::Option* sceneOption = app.add_option("scene", render.scenePath, "scene file (.gltf or .glb)");
    ViewFlags viewFlags;
    viewFlags.addTo(app);
    render.output.addTo(app, false);
    std::vector<CLI::Option*> renderOnly = {
        sceneOption,
        app.get_option("--camera"),
        app.get_option("--scene-camera"),
        app.get_option("--size"),
        app.add_option("--spp", render.spp, "samples per pixel"),
        app.add_option("--bounces", render.bounces,
                       "indirect bounces B: 0 = direct light only, -1 = unlimited (default)"),
        app.add_option("--component", render.component,
                       "full (default), direct, indirect, cached (what pic's caches carry: the "
                       "indirect light and the emitting surfaces' and the sky's first "
                       "reflection), or glossy (the --glossy lobe's term alone)")
            ->check(CLI::IsMember({"full", "direct", "indirect", "cached", "glossy"})),
        app.add_option("--glossy", render.glossyExponent,
                       "Phong exponent of a glossy lobe at the visible surface, as picclient "
                       "render --glossy adds it (> 0)")
            ->check(CLI::PositiveNumber),
        app.add_option("--glossy-weight", render.glossyWeight,
                       "factor on the glossy lobe's radiance (≥ 0)")
            ->check(CLI::NonNegativeNumber),
        addLightsOption(app, render.lightsPath),
        app.add_option("--seed", render.seed, "random seed (default 1)"),
        app.get_option("--exposure"),
        app.get_option("--out"),
    };

    render.objects.addTo(app);
    renderOnly.push_back(app.get_option("--object"));
    renderOnly.push_back(app.get_option("--transform"));
    app.get_option("--glossy")->needs(app.get_option("--glossy-weight"));
    app.get_option("--glossy-weight")->needs(app.get_option("--glossy"));

    CLI::App* probesCommand =
        app.add_subcommand("probes", "path-traced incident radiance SH at every cache of a bake");
    ProbeArgs probes;
    probesCommand->add_option("bake", probes.bakePath, "bake file (.pic)")->required();
    probesCommand->add_option("--scene", probes.scenePath, "the scene the bake was made from")
        ->required();
    addLightsOption(*probesCommand, probes.lightsPath);
    probesCommand->add_option("--samples", probes.params.samples,
                              "directions per cache (default 1024)");
    probesCommand->add_option(
        "--bounces", probes.params.bounces,
        "reflections B before light reaches a cache (0 = emitters and the sky only, "
        "-1 = unlimited)");
    probesCommand->add_option("--seed", probes.params.seed, "random seed (default 1)");
    bool withPunctual = false;
    probesCommand->add_flag("--with-punctual", withPunctual,
                            "also project the punctual lights' direct light (as deltas)");
    probesCommand->add_option("--out", probes.outPath, "JSON file to write")->required();
    probesCommand->add_option("--binary", probes.binaryPath,
                              "also write the raw float32 arrays y, co, cg");

    if (auto exit = parseCommandLine(app, argc, argv)) return *exit;
    if (probesCommand->parsed()) {
        // Options of the image form that reached the parent are mistakes, not silently ignored.
        for (const CLI::Option* option : renderOnly)
            if (option->count() > 0)
                return reportError(
                    {ErrorCode::InvalidInput,
                     fmt::format("{} does not apply to `picref probes`", option->get_name())});
        probes.params.indirectOnly = !withPunctual;
        return runProbes(probes);
    }

    if (render.scenePath.empty())
        return reportError(
            {ErrorCode::InvalidInput,
             "missing SCENE: picref SCENE (--camera … | --scene-camera N) --size WxH "
             "--spp N --out FILE, or picref probes / picref shade"});
    auto view = viewFlags.toView();
    if (!view) return reportError(view.error());
    render.view = *view;
    if (app.get_option("--spp")->count() == 0)
        return reportError({ErrorCode::InvalidInput, "--spp is required"});
    return runRender(render);
}

}  // namespace pic
