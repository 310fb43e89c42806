#include "bench/link_error_benchmark.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <limits>
#include <numbers>
#include <vector>

#include <nlohmann/json.hpp>

#include "bake/link_generation.h"
#include "bake/surfel_exposure.h"
#include "bench/bench_common.h"
#include "core/color.h"
#include "core/gltf_loader.h"
#include "core/light_set.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "core/sampling.h"
#include "core/sh.h"
#include "rays/embree_scene.h"
#include "render/cpu/cache_lighting.h"
#include "render/cpu/pull.h"
#include "render/cpu/surfel_lighting.h"

namespace pic {

namespace {

using Json = nlohmann::ordered_json;
constexpr double kPi = std::numbers::pi;

/// The five band-0 luma estimates of one cache (see the header), in W/(m²·sr) × y00.
struct Estimates {
    double traced = 0.0, gather = 0.0, cut = 0.0, mean = 0.0, linked = 0.0;
    Estimates& operator+=(const Estimates& o) {
        traced += o.traced, gather += o.gather, cut += o.cut, mean += o.mean, linked += o.linked;
        return *this;
    }
};

/// The node linked in slot `slot` of the bake's links, or kNoNode for padding.
uint32_t linkedNode(const LinkSet& links, size_t slot) {
    if (links.mode == LinkMode::Rtp)
        return links.rtp[slot].factor > 0.0f ? links.rtp[slot].node : kNoNode;
    const size_t coefficients = size_t{links.bands} * links.bands;
    return links.shCoefficients[slot * coefficients] != 0 ? links.shNodes[slot] : kNoNode;
}

Json ratiosJson(const Estimates& e, uint32_t caches) {
    auto ratio = [](double a, double b) { return b > 0.0 ? a / b : 0.0; };
    return {{"caches", caches},
            {"linked_over_traced", ratio(e.linked, e.traced)},
            {"representation", ratio(e.gather, e.traced)},
            {"cut_coverage", ratio(e.cut, e.gather)},
            {"node_mean_radiance", ratio(e.mean, e.cut)},
            {"visibility_estimate", ratio(e.linked, e.mean)}};
}

}  // namespace

int runLinkErrorBenchmark(const LinkErrorParams& params) {
    auto scene = loadScene(params.scenePath);
    if (!scene) return reportError(scene.error());
    auto loaded = loadLightSet(params.lightsPath, *scene);
    if (!loaded) return reportError(loaded.error());
    const LightSet& lights = *loaded;
    BakeReport report;
    auto bake = runBake(*scene, params.bake, report);
    if (!bake) return reportError(bake.error());
    auto rays = EmbreeScene::create(*scene);
    if (!rays) return reportError(rays.error());

    // One bounce of the runtime: direct surfel flux, pulled, gathered through the links.
    const size_t nS = bake->surfels.size();
    std::vector<glm::vec3> flux(bake->nodes.size());
    directSurfelFlux(*scene, **rays, *bake, lights, std::span(flux.data(), nS));
    pullFlux(*bake, flux);
    CacheValues values = CacheValues::zeros(bake->caches.size(), bake->params.bandsY, bake->params.bandsC);
    lightCaches(*bake, flux, values);

    // Luma radiance of every surfel, and what a link reads for it: its node's flux spread by
    // the flux weights the bake linked with (recomputed: the bake file does not keep them).
    std::vector<float> weights(nS, 1.0f);
    if (bake->params.exposureRays > 0) {
        auto free = surfelFreeDistance(**rays, scene->bounds, exposureReach(*scene), bake->surfels,
                                       ExposureParams{bake->params.exposureRays, bake->params.seed});
        if (!free) return reportError(free.error());
        weights = fluxWeights(bake->surfels, *free);
    }
    const std::vector<double> weightedArea = weightedNodeArea(bake->surfels, bake->nodes, weights);
    std::vector<double> radiance(nS), fluxY(bake->nodes.size());
    for (size_t n = 0; n < fluxY.size(); ++n) fluxY[n] = rgbToYCoCg(flux[n]).x;
    for (size_t s = 0; s < nS; ++s) radiance[s] = fluxY[s] / (kPi * bake->surfels[s].area);
    auto modelled = [&](uint32_t node, uint32_t s) {
        return fluxY[node] * weights[s] / (kPi * weightedArea[node]);
    };

    const size_t nC = bake->caches.size();
    const size_t examined = std::min<size_t>(std::max(params.caches, 1u), nC);
    const uint32_t nL = bake->links.linksPerCache;
    const size_t strideY = size_t{values.bandsY} * values.bandsY;
    const double y00 = 0.5 / std::sqrt(kPi);
    // The first runtime bounce: emission seen directly, punctual light reflected once.
    std::vector<float> emissiveScale(scene->materials.size());
    for (size_t m = 0; m < scene->materials.size(); ++m)
        emissiveScale[m] = lights.emissiveScaleOf(scene->materials[m].name);
    const float epsilon = (*rays)->epsilon();
    auto firstBounce = [&](const glm::vec3& origin, const glm::vec3& direction) {
        const auto hit = (*rays)->intersect(origin, direction, 0.0f, std::numeric_limits<float>::infinity());
        if (!hit) return glm::vec3(0.0f);
        const uint32_t t = hit->triangle;
        glm::vec3 radiance(0.0f);
        if (!hit->backFace)
            radiance += emissiveScale[scene->triangles[t].material] * scene->emissionAt(t, hit->b1, hit->b2);
        const glm::vec3 normal = hit->backFace ? -hit->geometricNormal : hit->geometricNormal;
        const glm::vec3 position = origin + hit->t * direction + epsilon * normal;
        glm::vec3 irradiance(0.0f);
        for (const Light& light : lights.lights) {
            glm::vec3 toLight;
            float distance = 0.0f;
            const glm::vec3 e = lightIrradiance(light, position, normal, toLight, distance);
            if (!(e.r > 0.0f || e.g > 0.0f || e.b > 0.0f)) continue;
            if (!(*rays)->occluded(position, toLight, 0.0f, distance - epsilon)) irradiance += e;
        }
        return radiance + scene->albedoAt(t, hit->b1, hit->b2) * irradiance / float(kPi);
    };
    std::vector<Estimates> estimates(examined);
    Progress progress("link error", examined);
    parallelFor(0, examined, [&](size_t k) {
        const size_t c = k * nC / examined;
        const Cache& cache = bake->caches[c];
        const bool hemisphere = cache.kind == gpu::kCacheKindLightmap;
        Estimates& e = estimates[k];
        e.linked = values.y[c * strideY];
        for (size_t s = 0; s < nS; ++s) {
            const SurfelView view = viewSurfel(**rays, cache, bake->surfels[s]);
            if (view.visible) e.gather += radiance[s] * view.solidAngle * y00;
        }
        for (uint32_t j = 0; j < nL; ++j) {
            const uint32_t n = linkedNode(bake->links, c * nL + j);
            if (n == kNoNode) continue;
            const Node& node = bake->nodes[n];
            for (uint32_t s = node.firstSurfel; s < node.firstSurfel + node.surfelCount; ++s) {
                const SurfelView view = viewSurfel(**rays, cache, bake->surfels[s]);
                if (!view.visible) continue;
                e.cut += radiance[s] * view.solidAngle * y00;
                e.mean += modelled(n, s) * view.solidAngle * y00;
            }
        }
        // Uniform directions over the cache's sphere (hemisphere for light-map caches).
        Rng rng(params.seed, c);
        double sum = 0.0;
        for (uint32_t i = 0; i < params.directions; ++i) {
            glm::vec3 w = sampleUniformSphere(rng.uniform(), rng.uniform());
            if (hemisphere && glm::dot(w, cache.normal) < 0.0f) w = -w;
            sum += rgbToYCoCg(firstBounce(cache.position, w)).x;
        }
        e.traced = sum / params.directions * (hemisphere ? 2.0 : 4.0) * kPi * y00;
        progress.advance();
    }, 1);
    progress.finish();

    Estimates all, grid, lightmap;
    uint32_t gridCount = 0, lightmapCount = 0;
    for (size_t k = 0; k < examined; ++k) {
        all += estimates[k];
        if (bake->caches[k * nC / examined].kind == gpu::kCacheKindLightmap) {
            lightmap += estimates[k];
            ++lightmapCount;
        } else {
            grid += estimates[k];
            ++gridCount;
        }
    }
    Json json;
    json["scene"] = params.scenePath;
    json["lights"] = params.lightsPath.empty() ? "scene" : params.lightsPath;
    json["bake"] = {{"surfels", bake->params.surfels}, {"links_per_cache", nL},
                    {"link_mode", bake->params.linkMode == LinkMode::Sh ? "sh" : "rtp"},
                    {"unique_caches", nC}};
    json["directions"] = params.directions;
    json["all"] = ratiosJson(all, uint32_t(examined));
    json["grid"] = ratiosJson(grid, gridCount);
    json["lightmap"] = ratiosJson(lightmap, lightmapCount);

    std::printf("%s: one bounce, %zu of %zu caches, nL %u (%s)\n", params.scenePath.c_str(), examined,
                nC, nL, bake->params.linkMode == LinkMode::Sh ? "sh" : "rtp");
    std::printf("  %-9s %7s %14s %15s %10s %11s %11s\n", "caches", "count", "linked/traced",
                "representation", "coverage", "node mean", "visibility");
    for (const char* kind : {"all", "grid", "lightmap"}) {
        const Json& r = json[kind];
        std::printf("  %-9s %7u %14.4f %15.4f %10.4f %11.4f %11.4f\n", kind, r["caches"].get<uint32_t>(),
                    r["linked_over_traced"].get<double>(), r["representation"].get<double>(),
                    r["cut_coverage"].get<double>(), r["node_mean_radiance"].get<double>(),
                    r["visibility_estimate"].get<double>());
    }
    if (!params.jsonPath.empty()) {
        std::ofstream out(params.jsonPath);
        out << json.dump(2) << "\n";
        if (!out) return reportError(Error{ErrorCode::Io, "cannot write " + params.jsonPath});
        std::printf("  wrote %s\n", params.jsonPath.c_str());
    }
    return 0;
}

}  // namespace pic
