#include "bake/bake.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "bake/grid_caches.h"
#include "bake/lightmap_caches.h"
#include "bake/lightmap_charts.h"
#include "bake/surfel_exposure.h"
#include "bake/surfel_hierarchy.h"
#include "bake/surfel_placement.h"
#include "core/sh.h"
#include "rays/embree_scene.h"

namespace pic {

namespace {

/// Wall-clock timer of one stage that appends to the report when stopped.
class StageTimer {
public:
    StageTimer(BakeReport& report, std::string name)
        : mReport(report), mName(std::move(name)), mStart(std::chrono::steady_clock::now()) {}
    void stop() {
        double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - mStart).count();
        mReport.seconds.emplace_back(mName, s);
    }

private:
    BakeReport& mReport;
    std::string mName;
    std::chrono::steady_clock::time_point mStart;
};

// Scene-relative defaults (documented in README): a 1 m box and a 100 m level both get
// a surfel spacing of 1/64 of their largest extent, 16 grid cells along it and about
// 8k light-map texels, within the ranges below.
constexpr double kSurfelSpacingDivisor = 64.0;
constexpr uint32_t kMinDefaultSurfels = 8192;
constexpr uint32_t kMaxDefaultSurfels = 131072;
constexpr float kGridCellsAlongExtent = 16.0f;
constexpr double kDefaultLightmapTexels = 8192.0;
constexpr uint32_t kDefaultLinks = 128;
constexpr uint32_t kDefaultBandsY = 3;
constexpr uint32_t kDefaultBandsC = 2;

}  // namespace

uint32_t dropBlindCaches(BakeData& bake, const std::vector<float>& visibleSolidAngle) {
    const uint32_t nL = bake.links.linksPerCache;
    const size_t nC = bake.caches.size();
    // Links of a cache are packed from its first slot, so a cache is blind when its first
    // link sees nothing.
    std::vector<uint32_t> remap(nC, kNoCache);
    uint32_t kept = 0;
    for (size_t c = 0; c < nC; ++c)
        if (visibleSolidAngle[c * nL] > 0.0f) remap[c] = kept++;
    const uint32_t dropped = static_cast<uint32_t>(nC - kept);
    if (dropped == 0) return 0;

    LinkSet& links = bake.links;
    const size_t coefficients = links.mode == LinkMode::Sh ? size_t{links.bands} * links.bands : 0;
    for (size_t c = 0; c < nC; ++c) {
        if (remap[c] == kNoCache) continue;
        const size_t to = remap[c];
        bake.caches[to] = bake.caches[c];
        std::copy_n(links.tint.begin() + c * nL, nL, links.tint.begin() + to * nL);
        std::copy_n(links.offset.begin() + c * nL * 3, nL * 3, links.offset.begin() + to * nL * 3);
        std::copy_n(links.spreadShare.begin() + c * nL, nL, links.spreadShare.begin() + to * nL);
        if (links.mode == LinkMode::Rtp) {
            std::copy_n(links.rtp.begin() + c * nL, nL, links.rtp.begin() + to * nL);
        } else {
            std::copy_n(links.shNodes.begin() + c * nL, nL, links.shNodes.begin() + to * nL);
            std::copy_n(links.shCoefficients.begin() + c * nL * coefficients, nL * coefficients,
                        links.shCoefficients.begin() + to * nL * coefficients);
        }
    }
    bake.caches.resize(kept);
    links.tint.resize(size_t{kept} * nL);
    links.offset.resize(size_t{kept} * nL * 3);
    links.spreadShare.resize(size_t{kept} * nL);
    if (links.mode == LinkMode::Rtp) {
        links.rtp.resize(size_t{kept} * nL);
    } else {
        links.shNodes.resize(size_t{kept} * nL);
        links.shCoefficients.resize(size_t{kept} * nL * coefficients);
    }
    for (std::vector<uint32_t>* index : {&bake.grid.cacheIndex, &bake.lightmap.cacheIndex})
        for (uint32_t& i : *index)
            if (i != kNoCache) i = remap[i];
    return dropped;
}

uint64_t peakMemoryBytes() {
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line)) {
        if (line.rfind("VmHWM:", 0) == 0) return std::stoull(line.substr(6)) * 1024ull;
    }
    return 0;
}

Result<BakeParams> resolveBakeParams(const Scene& scene, const BakeOptions& options,
                                     std::map<std::string, std::string>& defaults) {
    const glm::vec3 extent = scene.bounds.extent();
    const float largest = std::max({extent.x, extent.y, extent.z});
    if (!(largest > 0.0f) || !(scene.totalArea > 0.0))
        return fail(ErrorCode::InvalidInput, "scene '{}' has no extent or area to bake", scene.sourcePath);
    BakeParams p;

    if (options.surfels) {
        p.surfels = *options.surfels;
    } else {
        double spacing = largest / kSurfelSpacingDivisor;
        double wanted = scene.totalArea / (spacing * spacing);
        p.surfels = static_cast<uint32_t>(std::clamp(std::round(wanted / 1024.0) * 1024.0,
                                                     double(kMinDefaultSurfels), double(kMaxDefaultSurfels)));
        defaults["surfels"] = fmt::format("{:.4g} m² at {:.3g} m spacing (extent/{}), clamped to [{}, {}]",
                                          scene.totalArea, spacing, kSurfelSpacingDivisor,
                                          kMinDefaultSurfels, kMaxDefaultSurfels);
    }
    if (p.surfels < 2 || p.surfels > (1u << 24))
        return fail(ErrorCode::InvalidInput, "--surfels must be in [2, 16777216], got {}", p.surfels);

    p.linksPerCache = options.links.value_or(kDefaultLinks);
    if (!options.links) defaults["links"] = fmt::format("{} (paper 000 moderate setting)", kDefaultLinks);
    if (p.linksPerCache < 1 || p.linksPerCache > 4096)
        return fail(ErrorCode::InvalidInput, "--links must be in [1, 4096], got {}", p.linksPerCache);

    p.bandsY = options.bandsY.value_or(kDefaultBandsY);
    if (!options.bandsY) defaults["bands"] = fmt::format("{}", kDefaultBandsY);
    if (p.bandsY < 1 || p.bandsY > static_cast<uint32_t>(kMaxShBands))
        return fail(ErrorCode::InvalidInput, "--bands must be in [1, {}], got {}", kMaxShBands, p.bandsY);
    p.bandsC = options.bandsC.value_or(std::min(kDefaultBandsC, p.bandsY));
    if (!options.bandsC) defaults["chroma_bands"] = fmt::format("{} (≤ bands)", p.bandsC);
    if (p.bandsC < 1 || p.bandsC > p.bandsY)
        return fail(ErrorCode::InvalidInput, "--chroma-bands must be in [1, --bands = {}], got {}", p.bandsY, p.bandsC);

    if (options.gridCell) {
        p.gridCell = *options.gridCell;
    } else {
        p.gridCell = largest / kGridCellsAlongExtent;
        defaults["grid_cell"] = fmt::format("{:.3g} m = largest extent {:.3g} m / {}", p.gridCell,
                                            largest, kGridCellsAlongExtent);
    }
    if (!(p.gridCell > 0.0f) || !std::isfinite(p.gridCell))
        return fail(ErrorCode::InvalidInput, "--grid-cell must be a positive number of metres, got {}", p.gridCell);

    p.gridCaches = options.gridCaches;

    if (options.lightmapTexel) {
        p.lightmapTexel = *options.lightmapTexel;
    } else {
        p.lightmapTexel = static_cast<float>(std::sqrt(scene.totalArea / kDefaultLightmapTexels));
        defaults["lightmap_texel"] = fmt::format("{:.3g} m = sqrt({:.4g} m² / {} texels)", p.lightmapTexel,
                                                 scene.totalArea, kDefaultLightmapTexels);
    }
    if (!(p.lightmapTexel > 0.0f) || !std::isfinite(p.lightmapTexel))
        return fail(ErrorCode::InvalidInput, "--lightmap-texel must be a positive number of metres, got {}",
                    p.lightmapTexel);

    p.linkMode = options.linkMode;
    p.hierarchy = options.hierarchy;
    p.linkSamples = options.linkSamples;
    if (p.linkSamples < 1 || p.linkSamples > 1024)
        return fail(ErrorCode::InvalidInput, "--link-samples must be in [1, 1024], got {}", p.linkSamples);
    p.linkFinalSamples = options.linkFinalSamples;
    if (p.linkFinalSamples < 1 || p.linkFinalSamples > 1024)
        return fail(ErrorCode::InvalidInput, "--link-final-samples must be in [1, 1024], got {}",
                    p.linkFinalSamples);
    p.exposureRays = options.exposureRays;
    if (p.exposureRays > 1024)
        return fail(ErrorCode::InvalidInput, "--exposure-rays must be in [0, 1024], got {}", p.exposureRays);
    p.linkReads = options.linkReads;
    p.linkCut = options.linkCut;
    p.relaxIterations = options.relaxIterations;
    p.seed = options.seed;
    return p;
}

Result<std::vector<Surfel>> placeBakeSurfels(const Scene& scene, const EmbreeScene& rays,
                                             BakeParams& params, bool raise,
                                             std::map<std::string, std::string>& defaults,
                                             BakeReport& report) {
    const uint32_t first = params.surfels;
    for (;;) {
        PIC_TRY_ASSIGN(std::vector<Surfel> surfels,
                       placeSurfels(scene, SurfelParams{params.surfels, params.relaxIterations, 16, params.seed}));
        report.discShareOnSurface = discShareOnSurface(rays, surfels);
        if (!raise || report.discShareOnSurface >= kMinDiscShareOnSurface ||
            params.surfels > kMaxDefaultSurfels / 2) {
            if (params.surfels != first)
                defaults["surfels"] += fmt::format("; raised from {} until at least {} of the discs' area "
                                                   "lay on their surfaces ({:.3f})",
                                                   first, kMinDiscShareOnSurface, report.discShareOnSurface);
            return surfels;
        }
        params.surfels *= 2;
    }
}

Result<BakeData> runBake(const Scene& scene, const BakeOptions& options, BakeReport& report) {
    BakeData bake;
    PIC_TRY_ASSIGN(bake.params, resolveBakeParams(scene, options, bake.defaults));
    BakeParams& p = bake.params;
    bake.sceneHash = scene.hash;

    StageTimer raysTimer(report, "rays");
    PIC_TRY_ASSIGN(std::unique_ptr<EmbreeScene> rays, EmbreeScene::create(scene));
    raysTimer.stop();

    StageTimer surfelTimer(report, "surfels");
    PIC_TRY_ASSIGN(std::vector<Surfel> surfels,
                   placeBakeSurfels(scene, *rays, p, !options.surfels, bake.defaults, report));
    surfelTimer.stop();

    StageTimer hierarchyTimer(report, "hierarchy");
    HierarchyParams hierarchyParams;
    hierarchyParams.method = p.hierarchy;
    hierarchyParams.sceneExtent = scene.bounds.diagonal();
    hierarchyParams.rays = rays.get();
    PIC_TRY_ASSIGN(SurfelHierarchy hierarchy, buildHierarchy(std::move(surfels), hierarchyParams));
    bake.surfels = std::move(hierarchy.surfels);
    bake.nodes = std::move(hierarchy.nodes);
    bake.levelOffsets = std::move(hierarchy.levelOffsets);
    hierarchyTimer.stop();

    // The light map first: its charts decide which triangles are shaded from the grid. The
    // grid's caches still come first in the cache list.
    StageTimer lightmapTimer(report, "lightmap");
    LightmapChartParams chartParams;
    chartParams.texelSize = p.lightmapTexel;
    PIC_TRY_ASSIGN(LightmapCharts charts, buildLightmapCharts(scene, chartParams));
    LightmapCacheParams lightmapParams;
    lightmapParams.texelSize = p.lightmapTexel;
    PIC_TRY_ASSIGN(LightmapCacheSet lightmap, placeLightmapCaches(scene, *rays, std::move(charts), 0, lightmapParams));
    report.lightmapDuplicates = lightmap.duplicateTexels;
    report.lightmapRelocated = lightmap.relocated;
    report.lightmapRejected = lightmap.rejected;
    report.lightmapGridShaded = lightmap.gridShadedTriangles;
    lightmapTimer.stop();

    StageTimer gridTimer(report, "grid_caches");
    GridCacheParams gridParams;
    gridParams.cellSize = p.gridCell;
    gridParams.mode = p.gridCaches;
    if (p.gridCaches == GridCaches::Surfaces) {
        gridParams.gridShaded.resize(scene.triangles.size());
        for (size_t t = 0; t < scene.triangles.size(); ++t)
            gridParams.gridShaded[t] = lightmap.layout.triangleUvs[3 * t].x == kNotLightmapped;
    }
    PIC_TRY_ASSIGN(GridCacheSet grid, placeGridCaches(scene, *rays, 0, gridParams));
    bake.grid = std::move(grid.layout);
    bake.caches = std::move(grid.caches);
    report.gridInsideSolid = grid.insideSolid;
    report.gridDuplicates = grid.duplicates;
    report.gridUnread = grid.unread;
    gridTimer.stop();

    const auto gridCount = static_cast<uint32_t>(bake.caches.size());
    if (uint64_t{gridCount} + lightmap.caches.size() >= kNoCache)
        return fail(ErrorCode::InvalidInput, "{} grid and {} light-map caches are too many", gridCount,
                    lightmap.caches.size());
    bake.lightmap = std::move(lightmap.layout);
    for (uint32_t& index : bake.lightmap.cacheIndex)
        if (index != kNoCache) index += gridCount;
    bake.caches.insert(bake.caches.end(), lightmap.caches.begin(), lightmap.caches.end());

    // The links' flux weights (bake/surfel_exposure.h), surfels in leaf order.
    std::vector<float> weights;
    if (p.exposureRays > 0) {
        StageTimer exposureTimer(report, "exposure");
        PIC_TRY_ASSIGN(const SurfelExposure exposure,
                       surfelExposure(*rays, scene.bounds, exposureReach(scene), bake.surfels,
                                      ExposureParams{p.exposureRays, p.seed}));
        weights = fluxWeights(bake.surfels, bouncedExposure(bake.surfels, exposure));
        exposureTimer.stop();
    }

    StageTimer linkTimer(report, "links");
    LinkParams linkParams;
    linkParams.linksPerCache = p.linksPerCache;
    linkParams.mode = p.linkMode;
    linkParams.bands = p.bandsY;
    linkParams.samplesPerNode = p.linkSamples;
    linkParams.finalSamplesPerNode = p.linkFinalSamples;
    linkParams.seed = p.seed;
    linkParams.reads = p.linkReads;
    linkParams.cut = p.linkCut;
    PIC_TRY_ASSIGN(LinkResult links, generateLinks(*rays, bake.surfels, bake.nodes, bake.caches, linkParams, weights));
    bake.links = std::move(links.links);
    bake.surfelWeights = weights.empty() ? std::vector<float>(bake.surfels.size(), 1.0f) : weights;
    report.links = links.stats;
    report.blindCachesDropped = dropBlindCaches(bake, links.visibleSolidAngle);
    linkTimer.stop();

    report.peakMemoryBytes = peakMemoryBytes();
    return bake;
}

}  // namespace pic
