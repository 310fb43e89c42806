#pragma once
/// A baseline that users run instead of pic: irradiance probes ray-traced at runtime (DDGI
/// style), no links and no precomputed transport. The probes are the bake's unique caches;
/// each update traces K rays per cache, shades every hit with direct light (shadow rays) plus
/// the irradiance the previous update's caches give there, so that bounces accumulate over
/// successive updates, projects the radiance to the bake's SH exactly as the ideal caches do
/// (bake/ref/probes.h) and blends it into the stored values with a hysteresis.

#include <cstdint>
#include <memory>
#include <vector>

#include "core/bake_data.h"
#include "core/cache_values.h"
#include "core/error.h"
#include "core/light_set.h"
#include "core/scene.h"
#include "rays/embree_scene.h"

namespace pic {

/// How the ray-traced probes update.
struct TracedProbeParams {
    uint32_t raysPerCache = 64;  ///< K: rays traced per cache per update
    float hysteresis = 0.0f;  ///< h in [0, 1): new = h·old + (1 − h)·traced (DDGI's temporal blend)
    uint32_t subsets = 1;  ///< 1: every cache each update; 4: a quarter of the caches per
                           ///< update, in a randomised order (paper 003 §5.3)
    uint64_t seed = 1;
};

/// Ray-traced probes over the unique caches of a bake: grid caches over the full sphere,
/// light-map caches over the hemisphere above Cache::normal, as pathTraceProbes estimates
/// them. With K → ∞, h = 0 and enough updates for the bounces to converge, the values are
/// pathTraceProbes' (indirectOnly) values up to the error of reading bounces from the caches.
/// Subsets: a random permutation of the caches, made once, cut into `subsets` parts of sizes
/// differing by at most one; update u traces part u mod subsets, so every cache is traced
/// once every `subsets` updates. Directions are stratified and turned by a random rotation per
/// cache and update, deterministic per (seed, update index, cache) for any thread count.
class TracedProbes {
public:
    /// InvalidInput naming the value for K = 0, h outside [0, 1), subsets 0 or > 64, a bake of
    /// another scene (or an Embree scene of another one), band counts outside 1 ≤ lC ≤ lY ≤ 8.
    /// The scene, Embree scene and bake must outlive the probes.
    static Result<std::unique_ptr<TracedProbes>> create(const Scene& scene, const EmbreeScene& rays,
                                                        const BakeData& bake,
                                                        const TracedProbeParams& params);

    /// One update under `lights`: the caches of this update's subset trace K rays each and
    /// blend; returns all caches' values (CacheValues::irradiance stays empty), valid until
    /// the next update. InvalidInput when the light set does not fit the scene.
    Result<const CacheValues*> update(const LightSet& lights);

    /// Bytes this baseline holds at runtime: its current and previous CacheValues and the
    /// cache order of its subsets.
    uint64_t memoryBytes() const;

private:
    TracedProbes(const Scene& scene, const EmbreeScene& rays, const BakeData& bake,
                 const TracedProbeParams& params);

    /// Radiance arriving at `origin` from unit `direction`: emission and direct light reflected
    /// at the first hit, plus (when `bounce`) the irradiance mPrevious gives there; 0 on a miss.
    glm::vec3 tracedRadiance(const glm::vec3& origin, const glm::vec3& direction,
                             const LightSet& lights, bool bounce) const;

    const Scene* mScene;
    const EmbreeScene* mRays;
    const BakeData* mBake;
    TracedProbeParams mParams;
    CacheValues mValues;                 ///< what update() returns
    CacheValues mPrevious;               ///< the values before the running update
    std::vector<uint32_t> mOrder;        ///< nC cache indices in random order
    std::vector<uint32_t> mSubsetBegin;  ///< subsets + 1 offsets into mOrder
    std::vector<float> mEmissiveScale;   ///< per material, of the running update's light set
    uint64_t mUpdates = 0;               ///< updates done
};

}  // namespace pic
