#include "bench/link_error_benchmark.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <numbers>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>
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
#include "render/node_spread.h"

namespace pic {

namespace {

using Json = nlohmann::ordered_json;
constexpr double kPi = std::numbers::pi;

/// The six band-0 RGB estimates of one cache (see the header), in W/(m²·sr) × y00.
struct Estimates {
    glm::dvec3 traced{0.0}, gather{0.0}, cut{0.0}, mean{0.0}, spread{0.0}, linked{0.0};
    /// Light-map caches: traced, gather, spread and linked as irradiance along the normal
    /// through the lY bands (W/m²), what an image shows of the cache; 0 for grid caches.
    glm::dvec3 tracedAlong{0.0}, gatherAlong{0.0}, spreadAlong{0.0}, linkedAlong{0.0};
    Estimates& operator+=(const Estimates& o) {
        traced += o.traced, gather += o.gather, cut += o.cut, mean += o.mean, spread += o.spread;
        linked += o.linked;
        tracedAlong += o.tracedAlong, gatherAlong += o.gatherAlong, spreadAlong += o.spreadAlong;
        linkedAlong += o.linkedAlong;
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

/// YCoCg luma of linear RGB (Y = R/4 + G/2 + B/4), in double.
double luma(const glm::dvec3& rgb) { return 0.25 * rgb.r + 0.5 * rgb.g + 0.25 * rgb.b; }

/// Luma ratio a/b, 0 where b holds no light.
double lumaRatio(const glm::dvec3& a, const glm::dvec3& b) {
    return luma(b) > 0.0 ? luma(a) / luma(b) : 0.0;
}

/// Per-channel ratios a/b, 0 for a channel where b holds no light.
Json channelRatios(const glm::dvec3& a, const glm::dvec3& b) {
    Json out = Json::array();
    for (int i = 0; i < 3; ++i) out.push_back(b[i] > 0.0 ? a[i] / b[i] : 0.0);
    return out;
}

/// How much the caches of `cache` disagree in one factor a/b beyond its ratio over them all:
/// the RMS over caches of (their luma ratio / the aggregate's − 1), each cache weighted by
/// the luma of b. A factor that is right on average but differs from cache to cache shows
/// here and as blotches, not in the ratio.
template <typename A, typename B>
double scatter(const std::vector<Estimates>& estimates, const std::vector<size_t>& cache, A a, B b) {
    glm::dvec3 sumA(0.0), sumB(0.0);
    for (size_t k : cache) sumA += a(estimates[k]), sumB += b(estimates[k]);
    const double overall = lumaRatio(sumA, sumB);
    if (!(overall > 0.0)) return 0.0;
    double weighted = 0.0, weight = 0.0;
    for (size_t k : cache) {
        const double w = luma(b(estimates[k]));
        if (!(w > 0.0)) continue;
        const double d = luma(a(estimates[k])) / w / overall - 1.0;
        weighted += w * d * d;
        weight += w;
    }
    return weight > 0.0 ? std::sqrt(weighted / weight) : 0.0;
}

/// The scatter of every factor over the caches `cache`.
Json scatterJson(const std::vector<Estimates>& e, const std::vector<size_t>& cache) {
    auto traced = [](const Estimates& x) { return x.traced; };
    auto gather = [](const Estimates& x) { return x.gather; };
    auto cut = [](const Estimates& x) { return x.cut; };
    auto mean = [](const Estimates& x) { return x.mean; };
    auto spread = [](const Estimates& x) { return x.spread; };
    auto linked = [](const Estimates& x) { return x.linked; };
    return {{"linked_over_traced", scatter(e, cache, linked, traced)},
            {"representation", scatter(e, cache, gather, traced)},
            {"cut_coverage", scatter(e, cache, cut, gather)},
            {"node_mean_radiance", scatter(e, cache, mean, cut)},
            {"node_spread_radiance", scatter(e, cache, spread, cut)},
            {"visibility_estimate", scatter(e, cache, linked, spread)}};
}

/// Light-map caches' irradiance along the normal: the same chain, its steps merged where band 0
/// shows them apart: representation, the cut with the node's spread model (cut coverage ×
/// spread), and the links' cones with their visibility estimate.
Json alongNormalJson(const Estimates& e) {
    return {{"linked_over_traced", lumaRatio(e.linkedAlong, e.tracedAlong)},
            {"representation", lumaRatio(e.gatherAlong, e.tracedAlong)},
            {"node_spread_radiance", lumaRatio(e.spreadAlong, e.gatherAlong)},
            {"cones_and_visibility", lumaRatio(e.linkedAlong, e.spreadAlong)}};
}

/// The scatter of the along-normal factors over the light-map caches `cache`.
Json alongNormalScatterJson(const std::vector<Estimates>& e, const std::vector<size_t>& cache) {
    auto traced = [](const Estimates& x) { return x.tracedAlong; };
    auto gather = [](const Estimates& x) { return x.gatherAlong; };
    auto spread = [](const Estimates& x) { return x.spreadAlong; };
    auto linked = [](const Estimates& x) { return x.linkedAlong; };
    return {{"linked_over_traced", scatter(e, cache, linked, traced)},
            {"representation", scatter(e, cache, gather, traced)},
            {"node_spread_radiance", scatter(e, cache, spread, gather)},
            {"cones_and_visibility", scatter(e, cache, linked, spread)}};
}

Json ratiosJson(const Estimates& e, uint32_t caches) {
    return {{"caches", caches},
            {"linked_over_traced", lumaRatio(e.linked, e.traced)},
            {"representation", lumaRatio(e.gather, e.traced)},
            {"cut_coverage", lumaRatio(e.cut, e.gather)},
            {"node_mean_radiance", lumaRatio(e.mean, e.cut)},
            {"node_spread_radiance", lumaRatio(e.spread, e.cut)},
            {"visibility_estimate", lumaRatio(e.linked, e.spread)},
            {"channels", {{"linked_over_traced", channelRatios(e.linked, e.traced)},
                          {"representation", channelRatios(e.gather, e.traced)},
                          {"cut_coverage", channelRatios(e.cut, e.gather)},
                          {"node_mean_radiance", channelRatios(e.mean, e.cut)},
                          {"node_spread_radiance", channelRatios(e.spread, e.cut)},
                          {"visibility_estimate", channelRatios(e.linked, e.spread)}}}};
}

}  // namespace

int runLinkErrorBenchmark(const LinkErrorParams& params) {
    if (!params.near.empty() &&
        (params.near.size() != 4 || !std::all_of(params.near.begin(), params.near.end(),
                                                 [](float v) { return std::isfinite(v); }) ||
         !(params.near[3] > 0.0f)))
        return reportError(Error{ErrorCode::InvalidInput,
                                 fmt::format("--near takes x,y,z,r with a radius r > 0 in metres, "
                                             "got {}",
                                             fmt::join(params.near, ","))});
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
    // the flux weights the bake linked with.
    const std::vector<float>& weights = bake->surfelWeights;
    const std::vector<double> weightedArea = weightedNodeArea(bake->surfels, bake->nodes, weights);
    std::vector<glm::dvec3> radiance(nS);
    for (size_t s = 0; s < nS; ++s) radiance[s] = glm::dvec3(flux[s]) / (kPi * bake->surfels[s].area);
    // With visible-part reads the flux spreads per channel as w·κ·a (surfel_exposure.h
    // fluxColour; the links' tints), except in a channel the node has no colour in.
    const bool coloured = bake->params.linkReads == LinkReads::Visible;
    std::vector<glm::dvec3> colouredArea(bake->nodes.size());
    for (size_t n = 0; n < colouredArea.size(); ++n) {
        const Node& node = bake->nodes[n];
        colouredArea[n] = node.left == kNoNode
                              ? glm::dvec3(fluxColour(bake->surfels[n])) * (double(weights[n]) * bake->surfels[n].area)
                              : colouredArea[node.left] + colouredArea[node.right];
    }
    auto modelled = [&](uint32_t node, uint32_t s) {
        glm::dvec3 read = glm::dvec3(flux[node]) * (weights[s] / (kPi * weightedArea[node]));
        if (!coloured) return read;
        const glm::dvec3 colour(fluxColour(bake->surfels[s]));
        for (int c = 0; c < 3; ++c)
            if (colouredArea[node][c] > 1e-6 * weightedArea[node])
                read[c] *= colour[c] * weightedArea[node] / colouredArea[node][c];
        return read;
    };
    // What a link reads with the node's flux spread (render/node_spread.h), relative to the
    // node's flux: the spread at the box point of the visible part's centroid (Σ w·Ω·x /
    // Σ w·Ω, as the bake's offset), with the part's spread share.
    const NodeSpread spread = nodeSpread(*bake);
    std::vector<glm::mat3> moment(bake->nodes.size()), slopes(bake->nodes.size());
    std::vector<glm::vec3> centreFlux(bake->nodes.size()), concentration(bake->nodes.size());
    std::vector<uint8_t> exponential(bake->nodes.size());
    pullFluxSpread(*bake, spread, flux, moment, centreFlux, slopes, concentration, exponential);
    auto spreadRead = [&](uint32_t node, const glm::vec3& centroid, float spreadShare) {
        glm::dvec3 ratio(1.0);
        if (node < nS) return ratio;
        const glm::vec3 u =
            decodeBoxPoint(encodeBoxPoint(spread, node, centroid - spread.centroid[node]));
        for (int c = 0; c < 3; ++c) {
            const float read =
                exponential[node]
                    ? centreFlux[node][c] * std::exp(glm::dot(slopes[node][c], u) -
                                                     (1.0f - spreadShare) * concentration[node][c])
                    : centreFlux[node][c] * (1.0f + glm::dot(slopes[node][c], u));
            ratio[c] = flux[node][c] > 0.0f ? read / flux[node][c] : 0.0;
        }
        return ratio;
    };

    // A part's spread share (bake/link_generation.cpp): the trace of its covariance over its
    // node's, from the part's centroid and mean |x|².
    auto spreadShare = [&](uint32_t n, const glm::dvec3& centroid, double meanSquare) {
        double node = 0.0;
        for (int k = 0; k < 3; ++k)
            if (spread.inverseVariance[n][k] > 0.0f) node += 1.0 / spread.inverseVariance[n][k];
        const double part = std::max(0.0, meanSquare - glm::dot(centroid, centroid));
        return float(node > 0.0 ? std::min(1.0, part / node) : 1.0);
    };
    const size_t nC = bake->caches.size();
    // The caches to examine: --caches of them, evenly over the bake's or over those near the
    // point --near names.
    std::vector<size_t> candidates;
    for (size_t c = 0; c < nC; ++c)
        if (params.near.empty() ||
            glm::distance(bake->caches[c].position,
                          glm::vec3(params.near[0], params.near[1], params.near[2])) <= params.near[3])
            candidates.push_back(c);
    if (candidates.empty())
        return reportError(Error{ErrorCode::InvalidInput,
                                 fmt::format("no cache lies within {} m of ({}, {}, {}) (--near)",
                                             params.near[3], params.near[0], params.near[1],
                                             params.near[2])});
    const size_t examined = std::min<size_t>(std::max(params.caches, 1u), candidates.size());
    std::vector<size_t> chosen(examined);
    for (size_t k = 0; k < examined; ++k) chosen[k] = candidates[k * candidates.size() / examined];
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
        if (!hit || (hit->backFace && params.oneSidedTruth)) return glm::vec3(0.0f);
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
    const SurfelCells cells = surfelCells(**rays, bake->surfels);
    const LinkReadWeight readWeight(bake->params.bandsY);
    std::vector<Estimates> estimates(examined);
    Progress progress("link error", examined);
    parallelFor(0, examined, [&](size_t k) {
        const size_t c = chosen[k];
        const Cache& cache = bake->caches[c];
        const bool hemisphere = cache.kind == gpu::kCacheKindLightmap;
        Estimates& e = estimates[k];
        const size_t strideC = size_t{values.bandsC} * values.bandsC;
        e.linked = glm::dvec3(yCoCgToRgb({values.y[c * strideY], values.co[c * strideC], values.cg[c * strideC]}));
        if (hemisphere) e.linkedAlong = glm::dvec3(values.irradiance[c]);
        // The irradiance kernel along the normal (the bake's weight of a direction in what a
        // link reads); grid caches have no normal and take 0.
        auto along = [&](const glm::vec3& w) { return hemisphere ? double(readWeight(cache, w)) : 0.0; };
        for (size_t s = 0; s < nS; ++s) {
            const SurfelView view = viewSurfel(**rays, cache, bake->surfels[s], cells.of(s));
            if (!view.visible) continue;
            e.gather += radiance[s] * (double(view.solidAngle) * y00);
            e.gatherAlong += radiance[s] * (double(view.solidAngle) * along(view.direction));
        }
        for (uint32_t j = 0; j < nL; ++j) {
            const uint32_t n = linkedNode(bake->links, c * nL + j);
            if (n == kNoNode) continue;
            const Node& node = bake->nodes[n];
            glm::dvec3 mean(0.0), meanAlong(0.0), centroid(0.0);
            double centroidWeight = 0.0, second = 0.0;
            for (uint32_t s = node.firstSurfel; s < node.firstSurfel + node.surfelCount; ++s) {
                const SurfelView view = viewSurfel(**rays, cache, bake->surfels[s], cells.of(s));
                if (!view.visible) continue;
                e.cut += radiance[s] * (double(view.solidAngle) * y00);
                mean += modelled(n, s) * (double(view.solidAngle) * y00);
                meanAlong += modelled(n, s) * (double(view.solidAngle) * along(view.direction));
                const double w = (weights.empty() ? 1.0 : double(weights[s])) *
                                 double(view.solidAngle) * readWeight(cache, view.direction);
                const glm::dvec3 x(bake->surfels[s].position);
                centroid += w * x;
                centroidWeight += w;
                second += w * glm::dot(x, x);
            }
            e.mean += mean;
            if (centroidWeight > 0.0) {
                const glm::dvec3 ratio = spreadRead(n, glm::vec3(centroid / centroidWeight),
                                                    spreadShare(n, centroid / centroidWeight,
                                                                second / centroidWeight));
                e.spread += mean * ratio;
                e.spreadAlong += meanAlong * ratio;
            }
        }
        // Uniform directions over the cache's sphere (hemisphere for light-map caches).
        Rng rng(params.seed, c);
        glm::dvec3 sum(0.0), sumAlong(0.0);
        for (uint32_t i = 0; i < params.directions; ++i) {
            glm::vec3 w = sampleUniformSphere(rng.uniform(), rng.uniform());
            if (hemisphere && glm::dot(w, cache.normal) < 0.0f) w = -w;
            const glm::dvec3 radiance(firstBounce(cache.position, w));
            sum += radiance;
            sumAlong += radiance * along(w);
        }
        e.traced = sum * ((hemisphere ? 2.0 : 4.0) * kPi * y00 / params.directions);
        e.tracedAlong = sumAlong * (2.0 * kPi / params.directions);
        progress.advance();
    }, 1);
    progress.finish();

    Estimates all, grid, lightmap;
    std::vector<size_t> allCaches, gridCaches, lightmapCaches;
    for (size_t k = 0; k < examined; ++k) {
        all += estimates[k];
        allCaches.push_back(k);
        if (bake->caches[chosen[k]].kind == gpu::kCacheKindLightmap) {
            lightmap += estimates[k];
            lightmapCaches.push_back(k);
        } else {
            grid += estimates[k];
            gridCaches.push_back(k);
        }
    }
    Json json;
    json["scene"] = params.scenePath;
    json["lights"] = params.lightsPath.empty() ? "scene" : params.lightsPath;
    json["bake"] = {{"surfels", bake->params.surfels}, {"links_per_cache", nL},
                    {"link_mode", bake->params.linkMode == LinkMode::Sh ? "sh" : "rtp"},
                    {"unique_caches", nC}};
    json["directions"] = params.directions;
    if (!params.near.empty())
        json["near"] = {{"point", {params.near[0], params.near[1], params.near[2]}},
                        {"radius", params.near[3]},
                        {"caches_within", candidates.size()}};
    json["one_sided_truth"] = params.oneSidedTruth;
    json["all"] = ratiosJson(all, uint32_t(examined));
    json["grid"] = ratiosJson(grid, uint32_t(gridCaches.size()));
    json["lightmap"] = ratiosJson(lightmap, uint32_t(lightmapCaches.size()));
    json["all"]["scatter"] = scatterJson(estimates, allCaches);
    json["grid"]["scatter"] = scatterJson(estimates, gridCaches);
    json["lightmap"]["scatter"] = scatterJson(estimates, lightmapCaches);
    json["lightmap"]["along_normal"] = alongNormalJson(lightmap);
    json["lightmap"]["along_normal"]["scatter"] = alongNormalScatterJson(estimates, lightmapCaches);
    // Each examined cache, to find where a factor scatters: its place, its kind, the traced
    // luma and its own ratios.
    Json perCache = Json::array();
    for (size_t k = 0; k < examined; ++k) {
        const Cache& cache = bake->caches[chosen[k]];
        const Estimates& e = estimates[k];
        perCache.push_back(
            {{"cache", chosen[k]},
             {"kind", cache.kind == gpu::kCacheKindLightmap ? "lightmap" : "grid"},
             {"position", {cache.position.x, cache.position.y, cache.position.z}},
             {"normal", {cache.normal.x, cache.normal.y, cache.normal.z}},
             {"traced_luma", luma(e.traced)},
             {"linked_over_traced", lumaRatio(e.linked, e.traced)},
             {"representation", lumaRatio(e.gather, e.traced)},
             {"cut_coverage", lumaRatio(e.cut, e.gather)},
             {"node_mean_radiance", lumaRatio(e.mean, e.cut)},
             {"node_spread_radiance", lumaRatio(e.spread, e.cut)},
             {"visibility_estimate", lumaRatio(e.linked, e.spread)},
             {"along_normal", cache.kind == gpu::kCacheKindLightmap ? alongNormalJson(e) : Json()}});
    }
    json["caches"] = std::move(perCache);

    std::printf("%s: one bounce, %zu of %zu caches%s, nL %u (%s)\n", params.scenePath.c_str(), examined,
                candidates.size(), params.near.empty() ? "" : " near the --near point", nL,
                bake->params.linkMode == LinkMode::Sh ? "sh" : "rtp");
    std::printf("  %-9s %7s %14s %15s %10s %11s %11s %11s\n", "caches", "count", "linked/traced",
                "representation", "coverage", "node mean", "node spread", "visibility");
    const char* factors[] = {"linked_over_traced", "representation",       "cut_coverage",
                             "node_mean_radiance", "node_spread_radiance", "visibility_estimate"};
    for (const char* kind : {"all", "grid", "lightmap"}) {
        const Json& r = json[kind];
        std::printf("  %-9s %7u %14.4f %15.4f %10.4f %11.4f %11.4f %11.4f\n", kind,
                    r["caches"].get<uint32_t>(), r[factors[0]].get<double>(), r[factors[1]].get<double>(),
                    r[factors[2]].get<double>(), r[factors[3]].get<double>(), r[factors[4]].get<double>(),
                    r[factors[5]].get<double>());
        // The same factors per channel, R G B, under their luma.
        std::printf("  %-9s %7s", "", "R G B");
        const int widths[] = {14, 15, 10, 11, 11, 11};
        for (int f = 0; f < 6; ++f) {
            const Json& c = r["channels"][factors[f]];
            char text[32];
            std::snprintf(text, sizeof text, "%.2f %.2f %.2f", c[0].get<double>(), c[1].get<double>(),
                          c[2].get<double>());
            std::printf(" %*s", widths[f], text);
        }
        std::printf("\n");
        const Json& scattered = r["scatter"];
        std::printf("  %-9s %7s", "", "scatter");
        for (int f = 0; f < 6; ++f) std::printf(" %*.4f", widths[f], scattered[factors[f]].get<double>());
        std::printf("\n");
    }
    // The light-map caches' irradiance along the normal: linked/traced, representation, the
    // cut with the spread model (under "node spread"), the cones and visibility.
    const Json& along = json["lightmap"]["along_normal"];
    for (const bool scattered : {false, true}) {
        const Json& r = scattered ? along["scatter"] : along;
        std::printf("  %-9s %7s %14.4f %15.4f %10s %11s %11.4f %11.4f\n", scattered ? "" : "along n",
                    scattered ? "scatter" : "", r["linked_over_traced"].get<double>(),
                    r["representation"].get<double>(), "", "", r["node_spread_radiance"].get<double>(),
                    r["cones_and_visibility"].get<double>());
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
