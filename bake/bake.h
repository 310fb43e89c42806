#pragma once
/// The whole precomputation (paper 000 §4): surfels, hierarchy, caches, links.

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "bake/link_generation.h"
#include "core/bake_data.h"
#include "core/error.h"
#include "core/scene.h"

namespace pic {

/// What the user asked for; unset values get scene-dependent defaults.
struct BakeOptions {
    std::optional<uint32_t> surfels;
    std::optional<uint32_t> links;
    std::optional<uint32_t> bandsY;
    std::optional<uint32_t> bandsC;
    std::optional<float> gridCell;
    GridCaches gridCaches = GridCaches::Surfaces;
    std::optional<float> lightmapTexel;
    LinkMode linkMode = LinkMode::Rtp;
    HierarchyMethod hierarchy = HierarchyMethod::Visible;
    uint32_t linkSamples = 16;
    uint32_t linkFinalSamples = 64;
    uint32_t exposureRays = 64;
    LinkReads linkReads = LinkReads::Visible;
    LinkCut linkCut = LinkCut::ErrorBound;
    uint32_t relaxIterations = 4;
    uint64_t seed = 1;
};

/// Timings and counts of one bake, for the summary and benchmarks.
struct BakeReport {
    std::vector<std::pair<std::string, double>> seconds;  ///< per stage, in order
    LinkStats links;
    uint32_t gridInsideSolid = 0;
    uint32_t gridDuplicates = 0;
    uint32_t gridUnread = 0;          ///< GridCaches::Surfaces: volume caches no surface reads
    uint32_t lightmapDuplicates = 0;
    uint32_t lightmapRelocated = 0;
    uint32_t lightmapRejected = 0;
    uint32_t lightmapGridShaded = 0;  ///< triangles too small for the light map (grid-shaded)
    uint32_t blindCachesDropped = 0;  ///< caches that saw no surfel, removed after linking
    double discShareOnSurface = 0.0;  ///< of the surfels' disc area (link_generation.h)
    uint64_t peakMemoryBytes = 0;
};

/// Resolves unset options from the scene's extent and area; `defaults` says how.
Result<BakeParams> resolveBakeParams(const Scene& scene, const BakeOptions& options,
                                     std::map<std::string, std::string>& defaults);

/// The least share of the surfels' disc area on their own surfaces (discShareOnSurface) that
/// a default surfel count keeps: open rooms hold 0.86–0.98 at a spacing of 1/64 of their
/// extent, the OpenArena level 0.75, where caches found a quarter of the light short within
/// four surfel radii of them.
inline constexpr double kMinDiscShareOnSurface = 0.85;

/// Places `params.surfels` surfels. With `raise` (the count is a default) the count doubles
/// until the share of their discs on their surfaces reaches kMinDiscShareOnSurface or the
/// next would pass the default's ceiling, 131,072: surfaces narrower than a disc (a level's
/// steps, ledges and bars) are otherwise drawn by discs that overhang them, and caches near
/// them find part of their light missing. Says so in `defaults`; the share placed is in
/// `report`.
Result<std::vector<Surfel>> placeBakeSurfels(const Scene& scene, const EmbreeScene& rays,
                                             BakeParams& params, bool raise,
                                             std::map<std::string, std::string>& defaults,
                                             BakeReport& report);

/// Runs every bake stage on a loaded scene.
Result<BakeData> runBake(const Scene& scene, const BakeOptions& options, BakeReport& report);

/// Removes caches whose links see no surfel (e.g. on the outside of a room's walls): their
/// radiance is zero whatever the lights, so their grid vertices and light-map texels become
/// kNoCache, which the runtime reads as zero. Returns how many were dropped.
uint32_t dropBlindCaches(BakeData& bake, const std::vector<float>& visibleSolidAngle);

/// Peak resident memory of this process so far, in bytes (0 if unknown).
uint64_t peakMemoryBytes();

}  // namespace pic
