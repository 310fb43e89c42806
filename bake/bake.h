#pragma once
/// The whole precomputation (paper 000 §4): surfels, hierarchy, caches, links.

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "bake/link_generation.h"
#include "core/bake_data.h"
#include "core/bake_file.h"
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
    uint32_t skyRays = 256;
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

/// Which caches one process links in a sharded bake: shard `index` of `count` (from 0, as a
/// Kubernetes Indexed Job numbers its pods) links caches [nC·index/count, nC·(index+1)/count).
/// Every shard runs the stages before the links in full; they are deterministic.
struct BakeShard {
    uint32_t index = 0;
    uint32_t count = 1;
};

/// The caches [first, second) that `shard` links of nC.
std::pair<uint64_t, uint64_t> shardCaches(uint64_t nC, BakeShard shard);

/// Parses "I/N" (0 ≤ I < N ≤ kMaxShards), naming the value when it is not one.
Result<BakeShard> parseBakeShard(const std::string& text);
inline constexpr uint32_t kMaxShards = 4096;

/// Runs every bake stage, linking the caches of `shard` only (BakePart, core/bake_file.h).
Result<BakePart> runBakePart(const Scene& scene, const BakeOptions& options, BakeShard shard,
                             BakeReport& report);

/// Joins the parts of a sharded bake, given one at a time in any order, into the bake runBake
/// makes of the same scene and options, byte for byte. Refuses a part of another bake (scene,
/// options, seed or build), a shard given twice, and finishing with a shard missing. Holds
/// one part's arrays and the links of all, not every part at once.
class BakeJoiner {
public:
    /// `name` names the part in messages (its path).
    Result<void> add(BakePart part, const std::string& name);
    /// The whole bake, its blind caches dropped (dropBlindCaches; how many in `dropped`).
    Result<BakeData> finish(uint32_t& dropped);

private:
    std::optional<BakeData> mBake;   ///< the first part's, its links grown to every cache
    std::vector<uint8_t> mSees;      ///< per cache: its links see a surfel
    size_t mSkyPerCache = 0;         ///< cache sky visibility values per cache
    std::vector<std::string> mNames; ///< per shard: the part given for it, empty while missing
};

/// Removes caches whose links see no surfel, but light-map caches that see the sky (e.g. grid
/// caches on the outside of a room's walls): their radiance is zero whatever the lights, so their grid vertices and
/// light-map texels become kNoCache, which the runtime reads as zero. `seesSurfel` holds one
/// flag per cache, 1 for the caches to keep. Returns how many were dropped.
uint32_t dropBlindCaches(BakeData& bake, const std::vector<uint8_t>& seesSurfel);

/// Peak resident memory of this process so far, in bytes (0 if unknown).
uint64_t peakMemoryBytes();

}  // namespace pic
