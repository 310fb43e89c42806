#include "bake/target_error.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "bake/ref/path_tracer.h"
#include "core/image.h"
#include "render/cpu/cache_shading.h"
#include "render/cpu_runtime.h"

namespace pic {

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

double median3(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

/// A pilot reference: the mean of two halves and its own noise.
struct PilotReference {
    Camera camera;
    Image image;
    double noise = 0.0;
};

}  // namespace

bool surfacesEmit(const Scene& scene) {
    for (const Material& m : scene.materials)
        if (glm::any(glm::greaterThan(m.emission, glm::vec3(0.0f)))) return true;
    return false;
}

double halvesNoise(const Image& a, const Image& b) {
    PIC_CHECK(a.pixels.size() == b.pixels.size());
    double sum = 0.0, level = 0.0;
    for (size_t i = 0; i < a.pixels.size(); ++i) {
        const glm::dvec3 d = glm::dvec3(a.pixels[i]) - glm::dvec3(b.pixels[i]);
        sum += glm::dot(d, d);
        level += 0.5 * double(a.pixels[i].r + a.pixels[i].g + a.pixels[i].b + b.pixels[i].r +
                              b.pixels[i].g + b.pixels[i].b);
    }
    const double n = 3.0 * double(a.pixels.size());
    return level > 0.0 ? std::sqrt(sum / n) / 2.0 / (level / n) : 0.0;
}

std::vector<std::pair<std::string, BakeOptions>> targetLadder(const Scene& scene, const BakeOptions& base) {
    std::map<std::string, std::string> unused;
    auto resolved = resolveBakeParams(scene, base, unused);
    std::vector<std::pair<std::string, BakeOptions>> ladder;
    if (!resolved) return ladder;
    const BakeParams& d = *resolved;
    // scale: nS and nL; coarse: grid cell and texel; lC and link samples at the rung.
    auto rung = [&](const std::string& name, double scale, double coarse, uint32_t bandsC, uint32_t samples) {
        BakeOptions o = base;
        o.surfels = std::max<uint32_t>(256, uint32_t(std::lround(d.surfels * scale)));
        o.links = std::clamp<uint32_t>(uint32_t(std::lround(d.linksPerCache * scale)), 8, 4096);
        o.bandsY = d.bandsY;
        o.bandsC = std::min(bandsC, d.bandsY);
        o.gridCell = float(d.gridCell * coarse);
        o.lightmapTexel = float(d.lightmapTexel * coarse);
        o.linkSamples = samples;
        ladder.emplace_back(name, o);
    };
    rung("cheapest", 0.25, 2.0, 1, 4);
    rung("cheaper", 0.25, std::sqrt(2.0), 1, 8);
    rung("cheap", 0.5, std::sqrt(2.0), std::min(2u, d.bandsC), 8);
    rung("lean", 0.5, 1.0, d.bandsC, d.linkSamples);
    ladder.emplace_back("default", base);
    rung("dearer", 2.0, 1.0 / std::sqrt(2.0), d.bandsC + 1, d.linkSamples);
    return ladder;
}

std::vector<Camera> pilotViews(const Scene& scene, std::vector<std::string>& how) {
    std::vector<Camera> views;
    for (size_t i = 0; i < scene.cameras.size() && views.size() < 2; ++i) {
        views.push_back(scene.cameras[i]);
        how.push_back(fmt::format("scene camera {}{}", i, scene.cameras[i].name.empty() ? "" : " (" + scene.cameras[i].name + ")"));
    }
    if (!views.empty()) return views;
    // No camera: from the middle of the bounds, a little above, along the longest horizontal
    // side, where a person standing in the scene would look.
    const glm::vec3 centre = scene.bounds.center(), extent = scene.bounds.extent();
    Camera camera;
    camera.eye = centre;
    const glm::vec3 along = extent.x >= extent.z ? glm::vec3(1.0f, 0.0f, 0.0f) : glm::vec3(0.0f, 0.0f, 1.0f);
    camera.target = centre + along * std::max(extent.x, extent.z) * 0.5f - glm::vec3(0.0f, 0.1f * extent.y, 0.0f);
    camera.fovyDegrees = 70.0f;
    views.push_back(camera);
    how.push_back(fmt::format("from the centre of the bounds along {} (the scene has no camera)",
                              extent.x >= extent.z ? "+x" : "+z"));
    return views;
}

Result<TargetChoice> chooseBakeForTarget(const Scene& scene, const BakeOptions& base,
                                         const TargetErrorParams& params) {
    if (!(params.error > 0.0 && params.error <= 10.0))
        return fail(ErrorCode::InvalidInput, "--target-error must be a relative RMSE in (0, 10], got {}", params.error);
    if (params.budgetMs && !(*params.budgetMs > 0.0))
        return fail(ErrorCode::InvalidInput, "--budget-ms must be a positive number of milliseconds, got {}",
                    *params.budgetMs);
    const Clock::time_point pilotStart = Clock::now();
    PIC_TRY_ASSIGN(LightSet lights, loadLightSet(params.lightsPath, scene));
    PIC_TRY_ASSIGN(std::unique_ptr<EmbreeScene> rays, EmbreeScene::create(scene));
    TargetChoice choice;
    const bool full = surfacesEmit(scene);
    choice.component = full ? "full" : "indirect";

    // The pilot's references, each traced in two independent halves.
    std::vector<PilotReference> references;
    for (const Camera& camera : pilotViews(scene, choice.views)) {
        PathTraceParams trace;
        trace.width = params.size.x;
        trace.height = params.size.y;
        trace.spp = std::max(params.spp / 2, 1u);
        trace.component = full ? PathTraceParams::Component::Full : PathTraceParams::Component::Indirect;
        std::fprintf(stderr, "picbake: target: path tracing the pilot reference of %s (%ux%u, %u spp) …\n",
                     choice.views[references.size()].c_str(), params.size.x, params.size.y, params.spp);
        trace.seed = 1;
        PIC_TRY_ASSIGN(Image a, pathTrace(scene, *rays, lights, camera, trace));
        trace.seed = 2;
        PIC_TRY_ASSIGN(Image b, pathTrace(scene, *rays, lights, camera, trace));
        PilotReference reference{camera, Image(a.width, a.height), halvesNoise(a, b)};
        for (size_t i = 0; i < a.pixels.size(); ++i) reference.image.pixels[i] = 0.5f * (a.pixels[i] + b.pixels[i]);
        choice.noise += reference.noise;
        references.push_back(std::move(reference));
    }
    choice.noise /= double(references.size());

    ShadeParams shade;
    shade.width = params.size.x;
    shade.height = params.size.y;
    shade.samplesPerPixel = params.shadeSpp;
    shade.component = full ? ShadeComponent::Full : ShadeComponent::Indirect;
    std::optional<size_t> bestInBudget;
    std::optional<BakeData> bestBake;
    std::optional<BakeReport> bestReport;
    for (auto& [name, options] : targetLadder(scene, base)) {
        TargetRung rung;
        rung.name = name;
        rung.options = options;
        std::fprintf(stderr, "picbake: target: baking rung '%s' …\n", name.c_str());
        BakeReport report;
        const Clock::time_point start = Clock::now();
        PIC_TRY_ASSIGN(BakeData bake, runBake(scene, options, report));
        rung.bakeSeconds = secondsSince(start);
        rung.params = bake.params;
        rung.caches = bake.caches.size();
        PIC_TRY_ASSIGN(auto runtime, createCpuRuntime(scene, *rays, bake, BounceParams{}));
        std::vector<double> ms;
        const CacheValues* values = nullptr;
        for (int k = 0; k < 3; ++k) {
            const Clock::time_point update = Clock::now();
            PIC_TRY_ASSIGN(values, runtime->setLights(lights));
            ms.push_back(1e3 * secondsSince(update));
        }
        rung.updateMs = median3(ms);
        for (const PilotReference& reference : references) {
            PIC_TRY_ASSIGN(Image image, shadeFromCaches(scene, *rays, bake, *values, lights, reference.camera, shade));
            PIC_TRY_ASSIGN(ImageError e, compareImages(image, reference.image));
            rung.measured += e.relativeRmse / double(references.size());
            rung.error += std::sqrt(std::max(e.relativeRmse * e.relativeRmse - reference.noise * reference.noise, 0.0)) /
                          double(references.size());
        }
        const bool inBudget = !params.budgetMs || rung.updateMs <= *params.budgetMs;
        rung.meets = inBudget && rung.error <= params.safety * params.error;
        std::fprintf(stderr, "picbake: target:   %s: %zu caches, error %.4f against the truth (measured %.4f), "
                     "%.1f ms per update%s\n", name.c_str(), rung.caches, rung.error, rung.measured, rung.updateMs,
                     rung.meets ? ": meets the target" : inBudget ? "" : ": over the budget");
        choice.rungs.push_back(rung);
        const size_t index = choice.rungs.size() - 1;
        // The first rung that meets the target wins. Failing that, the most accurate rung
        // within the budget; failing that, the cheapest rung.
        bool take = rung.meets || index == 0;
        if (inBudget && (!bestInBudget || rung.error < choice.rungs[*bestInBudget].error)) {
            bestInBudget = index;
            take = true;
        }
        if (take) {
            bestBake = std::move(bake);
            bestReport = std::move(report);
            choice.chosen = index;
        }
        if (rung.meets) {
            choice.met = true;
            break;
        }
        // Costs rise up the ladder: past the budget, the rungs above cost more still.
        if (!inBudget) break;
    }
    if (!bestBake) return fail(ErrorCode::Internal, "the target ladder of scene '{}' is empty", scene.sourcePath);
    choice.bake = std::move(*bestBake);
    choice.report = std::move(*bestReport);
    choice.pilotSeconds = secondsSince(pilotStart);
    return choice;
}

nlohmann::ordered_json targetJson(const TargetChoice& choice, const TargetErrorParams& params) {
    nlohmann::ordered_json rungs = nlohmann::ordered_json::array();
    for (const TargetRung& r : choice.rungs)
        rungs.push_back({{"name", r.name},
                         {"surfels", r.params.surfels},
                         {"links", r.params.linksPerCache},
                         {"bands", {{"y", r.params.bandsY}, {"c", r.params.bandsC}}},
                         {"grid_cell", r.params.gridCell},
                         {"lightmap_texel", r.params.lightmapTexel},
                         {"link_samples", r.params.linkSamples},
                         {"caches", r.caches},
                         {"bake_seconds", r.bakeSeconds},
                         {"update_ms", r.updateMs},
                         {"measured_rmse", r.measured},
                         {"predicted_error", r.error},
                         {"meets", r.meets}});
    const TargetRung& chosen = choice.rungs[choice.chosen];
    return {{"error", params.error},
            {"budget_ms", params.budgetMs ? nlohmann::ordered_json(*params.budgetMs) : nlohmann::ordered_json(nullptr)},
            {"component", choice.component},
            {"met", choice.met},
            {"chosen", chosen.name},
            {"predicted_error", chosen.error},
            {"predicted_update_ms", chosen.updateMs},
            {"safety", params.safety},
            {"pilot", {{"size", fmt::format("{}x{}", params.size.x, params.size.y)},
                       {"reference_spp", params.spp},
                       {"reference_noise", choice.noise},
                       {"views", choice.views},
                       {"lights", params.lightsPath.empty() ? "scene" : params.lightsPath},
                       {"seconds", choice.pilotSeconds}}},
            {"rungs", rungs}};
}

}  // namespace pic
