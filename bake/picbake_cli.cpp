#include "bake/picbake_cli.h"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "bake/bake.h"
#include "bake/bake_options_cli.h"
#include "bake/target_error.h"
#include "core/bake_file.h"
#include "core/camera.h"
#include "core/cli.h"
#include "core/gltf_loader.h"
#include "core/image.h"
#include "core/parallel.h"
#include "core/progress.h"

namespace pic {

namespace {

using Json = nlohmann::ordered_json;

const char* toString(LinkMode mode) { return mode == LinkMode::Sh ? "sh" : "rtp"; }

std::string humanBytes(uint64_t bytes) {
    if (bytes >= (1ull << 30)) return fmt::format("{:.2f} GiB", bytes / double(1ull << 30));
    if (bytes >= (1ull << 20)) return fmt::format("{:.2f} MiB", bytes / double(1ull << 20));
    if (bytes >= (1ull << 10)) return fmt::format("{:.1f} KiB", bytes / double(1ull << 10));
    return fmt::format("{} B", bytes);
}

/// Stage timings live beside the bake, so the bake itself stays byte-identical across runs.
std::string timingsPath(const std::string& bakePath) { return bakePath + ".timings.json"; }

/// So does the --target-error pilot's prediction, which `info --json` shows under "target".
std::string targetPath(const std::string& bakePath) { return bakePath + ".target.json"; }

/// Writes `json` to `path` through a temporary file; a warning if it cannot.
void writeBeside(const Json& json, const std::string& path) {
    const std::string tmp = path + ".tmp";
    std::ofstream out(tmp);
    out << json.dump(2) << "\n";
    out.close();
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (!out || ec) std::fprintf(stderr, "picbake: warning: could not write %s\n", path.c_str());
}

int reportError(const Error& error) { return pic::reportError("picbake", error); }

/// Prints what the pilot measured, what it chose and why.
void printTarget(const TargetChoice& choice, const TargetErrorParams& params) {
    fmt::print("  target          indirect relative RMSE {}{} against path tracing; pilot {}x{} at {} spp "
               "(its own noise {:.3f}), {:.1f} s, on {}\n",
               params.error,
               params.budgetMs ? fmt::format(" within {} ms per update", *params.budgetMs) : "",
               params.size.x, params.size.y, params.spp, choice.noise, choice.pilotSeconds,
               fmt::join(choice.views, "; "));
    for (size_t i = 0; i < choice.rungs.size(); ++i) {
        const TargetRung& r = choice.rungs[i];
        fmt::print("    {} {:<6} nS {:>7} nL {:>4} lY {} lC {} cell {:.3g} m texel {:.3g} m: {:>6} caches, error {:.4f}{}, "
                   "{:.1f} ms per update (modelled {:.1f}){}: {}\n",
                   i == choice.chosen ? "->" : "  ", r.kind, r.params.surfels, r.params.linksPerCache, r.params.bandsY,
                   r.params.bandsC, r.params.gridCell, r.params.lightmapTexel, r.caches, r.error,
                   r.predictedError ? fmt::format(" (predicted {:.4f})", *r.predictedError) : "", r.updateMs,
                   r.predictedMs, r.cached ? ", kept" : "", r.name);
    }
    const TargetRung& chosen = choice.rungs[choice.chosen];
    fmt::print("  models          {} combinations ranked; cost {:.3g} ms per 1000 link reads, {:.3g} per 1000 link "
               "read coefficients, {:.3g} per 1000 surfels, {:.3g} per update; error sums scaled by {:.2f}\n",
               choice.combinations, 1e3 * choice.cost.coefficients[0], 1e3 * choice.cost.coefficients[1],
               1e3 * choice.cost.coefficients[2], choice.cost.coefficients[3], choice.errorScale);
    if (choice.met)
        fmt::print("  chose           '{}': the cheapest bake measured within {} x {} = {:.4f} (error {:.4f})\n",
                   chosen.name, params.safety, params.error, params.safety * params.error, chosen.error);
    else
        std::fprintf(stderr,
                     "picbake: warning: no bake reached %.4f (%.2f x the target %g)%s; wrote '%s', the most "
                     "accurate within the budget (error %.4f)\n",
                     params.safety * params.error, params.safety, params.error,
                     params.budgetMs ? " within the budget" : "", chosen.name.c_str(), chosen.error);
}

/// Writes the stage timings of `report` beside `outPath`; returns their total.
double writeTimings(const BakeReport& report, const std::string& outPath) {
    Json timings;
    timings["seconds"] = Json::object();
    double total = 0.0;
    for (const auto& [stage, s] : report.seconds) {
        timings["seconds"][stage] = s;
        total += s;
    }
    timings["seconds_total"] = total;
    timings["peak_memory_bytes"] = report.peakMemoryBytes;
    timings["threads"] = workerCount();
    writeBeside(timings, timingsPath(outPath));
    return total;
}

/// "load 0.12, rays 0.40, …"
std::string stageList(const BakeReport& report) {
    std::string stages;
    for (const auto& [stage, s] : report.seconds)
        stages += fmt::format("{}{} {:.2f}", stages.empty() ? "" : ", ", stage, s);
    return stages;
}

int runBakeCommand(const std::string& scenePath, const std::string& outPath, const BakeOptions& options,
                   const std::optional<TargetErrorParams>& target) {
    using Clock = std::chrono::steady_clock;
    auto start = Clock::now();
    auto loaded = loadScene(scenePath);
    if (!loaded) return reportError(loaded.error());
    const Scene& scene = *loaded;
    double loadSeconds = std::chrono::duration<double>(Clock::now() - start).count();

    BakeReport report;
    std::optional<TargetChoice> choice;
    Result<BakeData> bake = fail(ErrorCode::Internal, "not baked");
    if (target) {
        auto chosen = chooseBakeForTarget(scene, options, *target);
        if (!chosen) return reportError(chosen.error());
        choice = std::move(*chosen);
        report = choice->report;
        bake = std::move(choice->bake);
        // The pilot's own time: what it spent beyond the chosen rung's bake stages.
        double stages = 0.0;
        for (const auto& [stage, seconds] : report.seconds) stages += seconds;
        report.seconds.insert(report.seconds.begin(), {"pilot", std::max(choice->pilotSeconds - stages, 0.0)});
    } else {
        bake = runBake(scene, options, report);
        if (!bake) return reportError(bake.error());
    }
    report.seconds.insert(report.seconds.begin(), {"load", loadSeconds});

    auto writeStart = Clock::now();
    if (auto written = writeBakeFile(outPath, *bake); !written) return reportError(written.error());
    report.seconds.emplace_back("write", std::chrono::duration<double>(Clock::now() - writeStart).count());

    const double total = writeTimings(report, outPath);
    std::error_code ec;
    if (choice)
        writeBeside(targetJson(*choice, *target), targetPath(outPath));
    else
        std::filesystem::remove(targetPath(outPath), ec);  // a stale prediction of another bake

    auto info = inspectBakeFile(outPath);
    if (!info) return reportError(info.error());
    const BakeParams& p = bake->params;
    auto withDefault = [&](const char* key, const std::string& value) {
        auto it = bake->defaults.find(key);
        return it == bake->defaults.end() ? value : fmt::format("{}  (default: {})", value, it->second);
    };
    fmt::print("pic bake: {} -> {}\n", scenePath, outPath);
    fmt::print("  scene           {} triangles, {} materials, {} lights, {} cameras, area {:.4g} m², "
               "extent {:.3g} x {:.3g} x {:.3g} m\n",
               scene.triangles.size(), scene.materials.size(), scene.lights.size(), scene.cameras.size(),
               scene.totalArea, scene.bounds.extent().x, scene.bounds.extent().y, scene.bounds.extent().z);
    fmt::print("  surfels nS      {}\n", withDefault("surfels", std::to_string(p.surfels)));
    fmt::print("  surfel discs    {:.3f} of their area on their own surfaces\n", report.discShareOnSurface);
    if (report.discShareOnSurface < kMinDiscShareOnSurface)
        std::fprintf(stderr,
                     "picbake: note: only %.2f of the surfels' disc area lies on their surfaces (a default "
                     "count keeps %.2f): caches near surfaces narrower than a disc will read too little "
                     "light; a larger --surfels draws them better\n",
                     report.discShareOnSurface, kMinDiscShareOnSurface);
    fmt::print("  hierarchy       {}, {} nodes, {} levels\n", hierarchyName(p.hierarchy), bake->nodes.size(),
               bake->levelOffsets.size() - 1);
    fmt::print("  grid cell       {}\n", withDefault("grid_cell", fmt::format("{:.4g} m", p.gridCell)));
    fmt::print("  grid caches     {}: {} vertices of {}x{}x{}, {} inside solid geometry ({} copy a neighbour){}\n",
               gridCachesName(p.gridCaches), info->gridCaches, bake->grid.dims.x, bake->grid.dims.y,
               bake->grid.dims.z, report.gridInsideSolid, report.gridDuplicates,
               p.gridCaches == GridCaches::Surfaces
                   ? fmt::format(", {} that only dynamic objects would read left out (--grid-caches volume or space keeps them)",
                                 report.gridUnread)
                   : "");
    fmt::print("  lightmap texel  {}\n", withDefault("lightmap_texel", fmt::format("{:.4g} m", p.lightmapTexel)));
    fmt::print("  lightmap        {}x{} atlas, {} charts, {} texels with a cache ({} duplicates), "
               "{} caches relocated, {} rejected behind geometry, {} triangles too small for it "
               "(shaded from the grid)\n",
               bake->lightmap.width, bake->lightmap.height, bake->lightmap.chartCount, info->lightmapCaches,
               report.lightmapDuplicates, report.lightmapRelocated, report.lightmapRejected,
               report.lightmapGridShaded);
    fmt::print("  unique caches   {} ({} that see no surface were dropped)\n", bake->caches.size(),
               report.blindCachesDropped);
    fmt::print("  links nL        {}\n", withDefault("links", std::to_string(p.linksPerCache)));
    fmt::print(
        "  link mode       {}, {} samples per node ({} final), {:.1f} links used per cache, "
        "{:.3g} sr visible per cache, {:.3g} M rays\n",
        toString(p.linkMode), p.linkSamples, p.linkFinalSamples, report.links.meanLinksUsed,
        report.links.meanVisibleSolidAngle, report.links.rays / 1e6);
    fmt::print("  flux weights    {}\n", p.exposureRays > 0
                                            ? fmt::format("exposure, {} rays per surfel", p.exposureRays)
                                            : std::string("uniform (--exposure-rays 0)"));
    fmt::print("  sky transfer    {}\n", p.skyRays > 0
                                            ? fmt::format("{} rays per surfel and cache", p.skyRays)
                                            : std::string("none (--sky-rays 0): skies are refused"));
    fmt::print("  links read      {}\n", p.linkReads == LinkReads::Node
                                            ? "the linked node's flux (--link-reads node)"
                                            : "the part of the node the cache sees");
    fmt::print("  links chosen by {}\n", p.linkCut == LinkCut::SolidAngle
                                             ? "visible solid angle (--link-cut solid-angle)"
                                             : "the bound on their error, solid angle × radius");
    fmt::print("  bands           y {}, c {}{}\n", p.bandsY, p.bandsC,
               bake->defaults.count("bands") ? "  (default)" : "");
    fmt::print("  seed            {}\n", p.seed);
    std::string sections;
    for (const auto& [name, bytes] : info->sectionBytes)
        sections += fmt::format("{}{} {}", sections.empty() ? "" : ", ", name, humanBytes(bytes));
    fmt::print("  bytes           {} total: {}\n", humanBytes(info->fileSize), sections);
    fmt::print("  seconds         {} (total {:.2f}) on {} threads\n", stageList(report), total, workerCount());
    fmt::print("  peak memory     {}\n", humanBytes(report.peakMemoryBytes));
    if (choice) printTarget(*choice, *target);
    if (report.links.clampedCoefficients)
        fmt::print("  warning         {} SH link coefficients exceeded the half-float range and were clamped\n",
                   report.links.clampedCoefficients);
    return 0;
}

/// `picbake bake … --shard I/N`: every stage, the links of one shard's caches.
int runBakeShardCommand(const std::string& scenePath, const std::string& outPath, const BakeOptions& options,
                        BakeShard shard) {
    using Clock = std::chrono::steady_clock;
    auto start = Clock::now();
    auto scene = loadScene(scenePath);
    if (!scene) return reportError(scene.error());
    BakeReport report;
    report.seconds.emplace_back("load", std::chrono::duration<double>(Clock::now() - start).count());
    auto part = runBakePart(*scene, options, shard, report);
    if (!part) return reportError(part.error());
    auto writeStart = Clock::now();
    if (auto written = writeBakePart(outPath, *part); !written) return reportError(written.error());
    report.seconds.emplace_back("write", std::chrono::duration<double>(Clock::now() - writeStart).count());
    const double total = writeTimings(report, outPath);
    std::error_code ec;
    fmt::print("pic bake part {}/{}: {} -> {}\n", shard.index, shard.count, scenePath, outPath);
    fmt::print("  caches          links of caches [{}, {}) of {}; join all {} parts with picbake merge\n",
               part->cacheBegin, part->cacheEnd, part->bake.caches.size(), shard.count);
    fmt::print("  surfels nS      {}, links nL {}, {}\n", part->bake.params.surfels, part->bake.params.linksPerCache,
               toString(part->bake.params.linkMode));
    fmt::print("  links           {:.1f} used per cache, {:.3g} M rays, {} caches that see no surface\n",
               report.links.meanLinksUsed, report.links.rays / 1e6,
               std::ranges::count(part->seesSurfel, uint8_t{0}));
    fmt::print("  bytes           {}\n", humanBytes(std::filesystem::file_size(outPath, ec)));
    fmt::print("  seconds         {} (total {:.2f}) on {} threads\n", stageList(report), total, workerCount());
    fmt::print("  peak memory     {}\n", humanBytes(report.peakMemoryBytes));
    return 0;
}

/// `picbake merge PART… -o OUT.pic`: the parts joined, byte-identical to the unsharded bake.
int runMergeCommand(const std::vector<std::string>& partPaths, const std::string& outPath) {
    using Clock = std::chrono::steady_clock;
    auto start = Clock::now();
    BakeJoiner joiner;
    Progress progress("parts", partPaths.size());
    for (const std::string& path : partPaths) {
        auto part = readBakePart(path);
        if (!part) return reportError(part.error());
        if (auto added = joiner.add(std::move(*part), path); !added) return reportError(added.error());
        progress.advance();
    }
    progress.finish();
    BakeReport report;
    auto bake = joiner.finish(report.blindCachesDropped);
    if (!bake) return reportError(bake.error());
    report.seconds.emplace_back("read", std::chrono::duration<double>(Clock::now() - start).count());
    auto writeStart = Clock::now();
    if (auto written = writeBakeFile(outPath, *bake); !written) return reportError(written.error());
    report.seconds.emplace_back("write", std::chrono::duration<double>(Clock::now() - writeStart).count());
    report.peakMemoryBytes = peakMemoryBytes();
    const double total = writeTimings(report, outPath);
    std::error_code ec;
    std::filesystem::remove(targetPath(outPath), ec);  // a stale prediction of another bake

    auto info = inspectBakeFile(outPath);
    if (!info) return reportError(info.error());
    fmt::print("pic merge: {} parts -> {}\n", partPaths.size(), outPath);
    fmt::print("  surfels nS      {}, nodes {}\n", info->surfels, info->nodes);
    fmt::print("  unique caches   {} ({} that see no surface were dropped), {} grid vertices, {} light-map texels\n",
               info->caches, report.blindCachesDropped, info->gridCaches, info->lightmapCaches);
    fmt::print("  links nL        {}, {}\n", info->linksPerCache, toString(info->params.linkMode));
    fmt::print("  bytes           {}\n", humanBytes(info->fileSize));
    fmt::print("  seconds         {} (total {:.2f})\n", stageList(report), total);
    fmt::print("  peak memory     {}\n", humanBytes(report.peakMemoryBytes));
    return 0;
}

int runInfoCommand(const std::string& bakePath, bool json) {
    auto info = inspectBakeFile(bakePath);
    if (!info) return reportError(info.error());
    Json seconds = Json::object();
    if (std::ifstream in(timingsPath(bakePath)); in) {
        Json timings = Json::parse(in, nullptr, false);
        if (!timings.is_discarded() && timings.contains("seconds")) seconds = timings["seconds"];
    }
    const BakeParams& p = info->params;
    Json out;
    out["format_version"] = info->formatVersion;
    out["scene_hash"] = fmt::format("{:016x}", info->sceneHash);
    out["surfels"] = info->surfels;
    out["nodes"] = info->nodes;
    out["caches"] = {{"grid", info->gridCaches}, {"lightmap", info->lightmapCaches}, {"unique", info->caches}};
    out["links_per_cache"] = info->linksPerCache;
    out["link_mode"] = toString(p.linkMode);
    out["bands"] = {{"y", p.bandsY}, {"c", p.bandsC}};
    out["bytes"] = Json::object();
    for (const auto& [name, bytes] : info->sectionBytes) out["bytes"][name] = bytes;
    out["file_bytes"] = info->fileSize;
    out["seconds"] = seconds;
    if (std::ifstream in(targetPath(bakePath)); in) {
        Json target = Json::parse(in, nullptr, false);
        if (!target.is_discarded()) out["target"] = target;
    }
    out["params"] = {{"grid_cell", p.gridCell},
                     {"grid_caches", gridCachesName(p.gridCaches)},
                     {"lightmap_texel", p.lightmapTexel},
                     {"hierarchy", hierarchyName(p.hierarchy)},
                     {"link_samples", p.linkSamples},
                     {"link_final_samples", p.linkFinalSamples},
                     {"exposure_rays", p.exposureRays},
                     {"sky_rays", p.skyRays},
                     {"link_reads", p.linkReads == LinkReads::Node ? "node" : "visible"},
                     {"link_cut", linkCutName(p.linkCut)},
                     {"relax_iterations", p.relaxIterations},
                     {"seed", p.seed}};
    out["defaults"] = Json::object();
    for (const auto& [key, how] : info->defaults) out["defaults"][key] = how;
    if (json) {
        std::cout << out.dump(2) << "\n";
        return 0;
    }
    fmt::print("{}: pic bake format {}, scene hash {}\n", bakePath, info->formatVersion,
               out["scene_hash"].get<std::string>());
    fmt::print("  surfels {}, nodes {}\n", info->surfels, info->nodes);
    fmt::print("  caches: {} unique, {} grid vertices, {} light-map texels\n", info->caches,
               info->gridCaches, info->lightmapCaches);
    fmt::print("  links: {} per cache, {}, bands y {} c {}\n", info->linksPerCache, toString(p.linkMode),
               p.bandsY, p.bandsC);
    fmt::print("  grid cell {:.4g} m (caches at {}), light-map texel {:.4g} m, hierarchy {}, seed {}\n",
               p.gridCell, gridCachesName(p.gridCaches), p.lightmapTexel, hierarchyName(p.hierarchy), p.seed);
    for (const auto& [name, bytes] : info->sectionBytes) fmt::print("  section {:<16} {}\n", name, humanBytes(bytes));
    fmt::print("  file {}\n", humanBytes(info->fileSize));
    for (const auto& [stage, s] : seconds.items()) fmt::print("  stage {:<14} {:.2f} s\n", stage, s.get<double>());
    return 0;
}

}  // namespace

int picbakeMain(int argc, char** argv) {
    CLI::App app{"picbake: precomputes surfels, hierarchy, caches and links of a glTF scene"};
    app.require_subcommand(1);
    addGlobalFlags(app);

    CLI::App* bakeCommand = app.add_subcommand("bake", "bake a glTF 2.0 scene (.gltf or .glb)");
    std::string scenePath, outPath;
    BakeOptionFlags bakeFlags;
    bakeCommand->add_option("scene", scenePath, "scene file (.gltf or .glb)")->required();
    bakeCommand->add_option("-o,--out", outPath, "bake file to write (.pic)")->required();
    bakeFlags.addTo(*bakeCommand);
    TargetErrorParams target;
    std::string pilotSize = "96x72", pilotCache = defaultCacheDir();
    std::vector<std::string> pilotCameras;
    CLI::Option* targetOption = bakeCommand->add_option(
        "--target-error", target.error,
        "the cheapest settings predicted to meet this relative RMSE of the indirect light (with "
        "emitting surfaces, their first reflection too: what the caches carry) against path "
        "tracing, from a pilot on the scene itself; bake flags given too set the pilot's base");
    CLI::Option* budgetOption = bakeCommand->add_option(
        "--budget-ms", "with --target-error: most CPU twin ms per update on this machine")
        ->check(CLI::Number);
    bakeCommand->add_option("--lights", target.lightsPath, "with --target-error: the light set the pilot relights with (default: the scene's)");
    bakeCommand->add_option("--pilot-size", pilotSize, "with --target-error: pilot image size (default 96x72)");
    bakeCommand->add_option("--pilot-camera", pilotCameras,
                            "with --target-error: a view the pilot measures, ex,ey,ez,tx,ty,tz,ux,uy,uz,fovy "
                            "(repeatable; default: the scene's first two cameras, else four from its middle)");
    bakeCommand->add_option("--pilot-cache", pilotCache,
                            "with --target-error: folder where the pilot keeps its measurements for the next "
                            "target on the same scene, or 'none' (default: " + defaultCacheDir() + ")");
    bakeCommand->add_option("--pilot-spp", target.spp, "with --target-error: pilot reference samples per pixel (default 256)")
        ->check(CLI::Range(2u, 1u << 20));
    std::string shardText;
    CLI::Option* shardOption = bakeCommand->add_option(
        "--shard", shardText,
        "I/N: write part I (0 to N-1) of a bake split N ways, the links of one N-th of the caches "
        "(every part runs the stages before the links); `picbake merge` joins the parts");

    CLI::App* mergeCommand = app.add_subcommand(
        "merge", "join the parts of a sharded bake into the bake file an unsharded bake writes");
    std::vector<std::string> partPaths;
    std::string mergeOut;
    mergeCommand->add_option("parts", partPaths, "every part (picbake bake --shard I/N), in any order")->required();
    mergeCommand->add_option("-o,--out", mergeOut, "bake file to write (.pic)")->required();

    CLI::App* infoCommand = app.add_subcommand("info", "describe a bake file");
    std::string infoPath;
    bool json = false;
    infoCommand->add_option("bake", infoPath, "bake file (.pic)")->required();
    infoCommand->add_flag("--json", json, "print one JSON object");

    if (auto exit = parseCommandLine(app, argc, argv)) return *exit;
    if (bakeCommand->parsed()) {
        std::optional<TargetErrorParams> targeted;
        if (*targetOption) {
            auto size = parseImageSize(pilotSize);
            if (!size) return reportError(size.error());
            target.size = *size;
            for (const std::string& text : pilotCameras) {
                auto camera = parseCamera(text);
                if (!camera) return reportError(Error{camera.error().code, "--pilot-camera: " + camera.error().message});
                target.cameras.push_back(*camera);
            }
            target.cacheDir = pilotCache == "none" ? "" : pilotCache;
            if (*budgetOption) target.budgetMs = budgetOption->as<double>();
            targeted = target;
        } else if (*budgetOption) {
            return reportError(Error{ErrorCode::InvalidInput, "--budget-ms needs --target-error"});
        }
        if (*shardOption) {
            if (targeted)
                return reportError(Error{ErrorCode::InvalidInput,
                                         "--shard cannot be combined with --target-error: the pilot "
                                         "chooses among whole bakes"});
            auto shard = parseBakeShard(shardText);
            if (!shard) return reportError(shard.error());
            return runBakeShardCommand(scenePath, outPath, bakeFlags.toOptions(), *shard);
        }
        return runBakeCommand(scenePath, outPath, bakeFlags.toOptions(), targeted);
    }
    if (mergeCommand->parsed()) return runMergeCommand(partPaths, mergeOut);
    return runInfoCommand(infoPath, json);
}

}  // namespace pic
