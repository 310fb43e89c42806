#include "bake/bake.h"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "bake/grid_caches.h"
#include "bake/lightmap_caches.h"
#include "bake/lightmap_charts.h"
#include "bake/sky_transfer.h"
#include "bake/surfel_exposure.h"
#include "bake/surfel_hierarchy.h"
#include "bake/surfel_placement.h"
#include "core/sh.h"
#include "core/sky.h"
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

uint32_t dropBlindCaches(BakeData& bake, const std::vector<uint8_t>& seesSurfel) {
    const uint32_t nL = bake.links.linksPerCache;
    const size_t nC = bake.caches.size();
    PIC_CHECK(seesSurfel.size() == nC);
    std::vector<uint32_t> remap(nC, kNoCache);
    uint32_t kept = 0;
    for (size_t c = 0; c < nC; ++c)
        if (seesSurfel[c]) remap[c] = kept++;
    const uint32_t dropped = static_cast<uint32_t>(nC - kept);
    if (dropped == 0) return 0;
    const size_t skyPerCache = skyValuesPerCache(bake.params);

    LinkSet& links = bake.links;
    const size_t coefficients = links.mode == LinkMode::Sh ? size_t{links.bands} * links.bands : 0;
    for (size_t c = 0; c < nC; ++c) {
        if (remap[c] == kNoCache) continue;
        const size_t to = remap[c];
        bake.caches[to] = bake.caches[c];
        std::copy_n(bake.cacheSky.begin() + c * skyPerCache, skyPerCache,
                    bake.cacheSky.begin() + to * skyPerCache);
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
    bake.cacheSky.resize(size_t{kept} * skyPerCache);
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
    p.skyRays = options.skyRays;
    if (p.skyRays > 4096)
        return fail(ErrorCode::InvalidInput, "--sky-rays must be in [0, 4096], got {}", p.skyRays);
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

std::pair<uint64_t, uint64_t> shardCaches(uint64_t nC, BakeShard shard) {
    // nC < 2³² and count ≤ kMaxShards: the products cannot overflow.
    return {nC * shard.index / shard.count, nC * (shard.index + 1) / shard.count};
}

Result<BakeShard> parseBakeShard(const std::string& text) {
    const auto fromText = [](std::string_view digits, uint32_t& value) {
        const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
        return !digits.empty() && ec == std::errc{} && end == digits.data() + digits.size();
    };
    const size_t slash = text.find('/');
    BakeShard shard;
    if (slash == std::string::npos || !fromText(std::string_view(text).substr(0, slash), shard.index) ||
        !fromText(std::string_view(text).substr(slash + 1), shard.count))
        return fail(ErrorCode::InvalidInput, "--shard {}: expected I/N, e.g. 0/4", text);
    if (shard.count == 0 || shard.count > kMaxShards)
        return fail(ErrorCode::InvalidInput, "--shard {}: the shard count must be 1 to {}", text,
                    kMaxShards);
    if (shard.index >= shard.count)
        return fail(ErrorCode::InvalidInput,
                    "--shard {}: shards are numbered 0 to {} (as a Kubernetes Indexed Job's "
                    "JOB_COMPLETION_INDEX)",
                    text, shard.count - 1);
    return shard;
}

Result<BakePart> runBakePart(const Scene& scene, const BakeOptions& options, BakeShard shard,
                             BakeReport& report) {
    PIC_CHECK(shard.count > 0 && shard.index < shard.count);
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

    BakePart part;
    part.index = shard.index;
    part.count = shard.count;
    std::tie(part.cacheBegin, part.cacheEnd) = shardCaches(bake.caches.size(), shard);

    if (p.skyRays > 0) {
        // Every shard computes the surfels' transfer (shared, compared when joining) and its own
        // caches' visibility.
        StageTimer skyTimer(report, "sky");
        bake.surfelSky = surfelSkyTransfer(*rays, bake.surfels, p.skyRays, p.seed);
        bake.cacheSky = cacheSkyVisibility(*rays, bake.caches, part.cacheBegin, part.cacheEnd,
                                           p.bandsY, p.skyRays, p.seed);
        skyTimer.stop();
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
    linkParams.cacheBegin = part.cacheBegin;
    linkParams.cacheEnd = part.cacheEnd;
    PIC_TRY_ASSIGN(LinkResult links, generateLinks(*rays, bake.surfels, bake.nodes, bake.caches, linkParams, weights));
    // Links of a cache are packed from its first slot, so a cache sees a surfel when its first
    // link does; it sees the sky when its visibility's band 0 (∫ V·y_0) is positive. A
    // light-map cache that sees either is kept: under a sky, a texel of an open floor that
    // sees no surface still receives light, and only its own surface reads it. A grid cache
    // must see a surfel: one outside a room's walls that sees only the sky would bring the sky
    // into the room to points inside that interpolate it.
    const size_t skyPerCache = skyValuesPerCache(p);
    part.seesSurfel.resize(part.cacheEnd - part.cacheBegin);
    for (size_t c = 0; c < part.seesSurfel.size(); ++c)
        part.seesSurfel[c] =
            links.visibleSolidAngle[c * p.linksPerCache] > 0.0f ||
            (skyPerCache && bake.caches[part.cacheBegin + c].kind == gpu::kCacheKindLightmap &&
             bake.cacheSky[c * skyPerCache] > 0.0f);
    bake.links = std::move(links.links);
    bake.surfelWeights = weights.empty() ? std::vector<float>(bake.surfels.size(), 1.0f) : weights;
    report.links = links.stats;
    linkTimer.stop();

    part.bake = std::move(bake);
    report.peakMemoryBytes = peakMemoryBytes();
    return part;
}

Result<BakeData> runBake(const Scene& scene, const BakeOptions& options, BakeReport& report) {
    PIC_TRY_ASSIGN(BakePart part, runBakePart(scene, options, BakeShard{}, report));
    BakeJoiner joiner;
    PIC_TRY(joiner.add(std::move(part), "the bake"));
    return joiner.finish(report.blindCachesDropped);
}

namespace {

template <class T>
bool sameBytes(const std::vector<T>& a, const std::vector<T>& b) {
    static_assert(std::is_trivially_copyable_v<T>);
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

/// What two parts' shared arrays first differ in, if anything.
std::optional<std::string_view> firstDifference(const BakeData& a, const BakeData& b) {
    if (a.sceneHash != b.sceneHash) return "scene hash";
    if (!(a.params == b.params) || a.defaults != b.defaults) return "parameters";
    if (!sameBytes(a.surfels, b.surfels)) return "surfels";
    if (!sameBytes(a.surfelWeights, b.surfelWeights)) return "surfel flux weights";
    if (!sameBytes(a.surfelSky, b.surfelSky)) return "surfel sky transfer";
    if (!sameBytes(a.nodes, b.nodes) || a.levelOffsets != b.levelOffsets) return "hierarchy";
    if (!sameBytes(a.caches, b.caches)) return "caches";
    const GridLayout &ga = a.grid, &gb = b.grid;
    if (ga.origin != gb.origin || ga.cellSize != gb.cellSize || ga.dims != gb.dims ||
        ga.cacheIndex != gb.cacheIndex)
        return "grid";
    const LightmapLayout &la = a.lightmap, &lb = b.lightmap;
    if (la.width != lb.width || la.height != lb.height || la.texelSize != lb.texelSize ||
        la.chartCount != lb.chartCount || la.cacheIndex != lb.cacheIndex ||
        !sameBytes(la.triangleUvs, lb.triangleUvs))
        return "light map";
    if (a.links.mode != b.links.mode || a.links.linksPerCache != b.links.linksPerCache ||
        a.links.bands != b.links.bands)
        return "link layout";
    return std::nullopt;
}

/// Copies `from`, the links of caches [first, first + n), into `to`, which holds every cache's.
void placeLinks(LinkSet& to, const LinkSet& from, uint64_t first) {
    const size_t nL = to.linksPerCache;
    const size_t coefficients = size_t{to.bands} * to.bands;
    std::ranges::copy(from.rtp, to.rtp.begin() + first * nL);
    std::ranges::copy(from.shNodes, to.shNodes.begin() + first * nL);
    std::ranges::copy(from.shCoefficients, to.shCoefficients.begin() + first * nL * coefficients);
    std::ranges::copy(from.tint, to.tint.begin() + first * nL);
    std::ranges::copy(from.offset, to.offset.begin() + first * nL * 3);
    std::ranges::copy(from.spreadShare, to.spreadShare.begin() + first * nL);
}

}  // namespace

Result<void> BakeJoiner::add(BakePart part, const std::string& name) {
    const uint64_t nC = part.bake.caches.size();
    if (mBake) {
        const std::string& first = *std::ranges::find_if(mNames, [](const auto& n) { return !n.empty(); });
        if (part.count != mNames.size())
            return fail(ErrorCode::InvalidInput, "{} is shard {} of {}, {} one of {}", name, part.index,
                        part.count, first, mNames.size());
        if (const auto difference = firstDifference(*mBake, part.bake))
            return fail(ErrorCode::InvalidInput,
                        "{} and {} differ in their {}: they are parts of different bakes (scene, "
                        "options, seed or picbake build); bake every shard with the same command",
                        first, name, *difference);
    } else {
        mNames.resize(part.count);
    }
    if (!mNames[part.index].empty())
        return fail(ErrorCode::InvalidInput, "{} and {} are both shard {} of {}", mNames[part.index],
                    name, part.index, part.count);
    const auto [begin, end] = shardCaches(nC, BakeShard{part.index, part.count});
    if (part.cacheBegin != begin || part.cacheEnd != end)
        return fail(ErrorCode::InvalidInput, "{} links caches [{}, {}); shard {} of {} links [{}, {})",
                    name, part.cacheBegin, part.cacheEnd, part.index, part.count, begin, end);
    mNames[part.index] = name;

    if (!mBake) {
        mSees.assign(nC, 0);
        mSkyPerCache = skyValuesPerCache(part.bake.params);
        mBake = std::move(part.bake);
        if (part.count > 1) {
            // Room for every cache's links; this part's go in their place below.
            LinkSet own = std::move(mBake->links);
            mBake->links = paddingLinks(own.mode, own.linksPerCache, own.bands, nC);
            placeLinks(mBake->links, own, begin);
            // Likewise the caches' sky visibility.
            std::vector<float> ownSky = std::move(mBake->cacheSky);
            mBake->cacheSky.assign(nC * mSkyPerCache, 0.0f);
            std::ranges::copy(ownSky, mBake->cacheSky.begin() + begin * mSkyPerCache);
        }
    } else {
        placeLinks(mBake->links, part.bake.links, begin);
        if (part.bake.cacheSky.size() != (end - begin) * mSkyPerCache)
            return fail(ErrorCode::InvalidInput, "{} holds {} cache sky values for {} caches, the "
                        "other parts {} per cache", name, part.bake.cacheSky.size(), end - begin,
                        mSkyPerCache);
        std::ranges::copy(part.bake.cacheSky, mBake->cacheSky.begin() + begin * mSkyPerCache);
    }
    std::ranges::copy(part.seesSurfel, mSees.begin() + begin);
    return {};
}

Result<BakeData> BakeJoiner::finish(uint32_t& dropped) {
    if (!mBake) return fail(ErrorCode::InvalidInput, "no part of a sharded bake was given");
    std::vector<size_t> missing;
    for (size_t i = 0; i < mNames.size(); ++i)
        if (mNames[i].empty()) missing.push_back(i);
    if (!missing.empty())
        return fail(ErrorCode::InvalidInput, "{} of {} missing: the merge needs every part",
                    fmt::format("shard{} {}", missing.size() > 1 ? "s" : "", fmt::join(missing, ", ")),
                    mNames.size());
    BakeData bake = std::move(*mBake);
    mBake.reset();
    dropped = dropBlindCaches(bake, mSees);
    return bake;
}

}  // namespace pic
