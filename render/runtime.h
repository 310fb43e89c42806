#pragma once
/// The runtime of paper 000 Figure 2 behind one API with two backends (GPU, CPU twin):
/// a light change in, cache radiance out.

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/bake_data.h"
#include "core/cache_textures.h"
#include "core/cache_values.h"
#include "core/error.h"
#include "core/light_set.h"
#include "core/scene.h"

namespace pic {

/// How many bounces the runtime computes.
struct BounceParams {
    int bounces = -1;                 ///< ≥ 0: exactly this many cache passes; −1: progressive
    float convergence = 0.005f;       ///< progressive: stop when a bounce adds less than this fraction of flux
    int maxBounces = 8;               ///< progressive: at most this many
};

/// What follows a bounce's cache pass (BounceSchedule::afterBounce).
struct BounceStep {
    bool another = false;     ///< the surfels take the next bounce's flux
    bool last = false;        ///< and that bounce's cache pass is the last
    glm::vec3 tail{0.0f};     ///< per channel: its surfel pass adds tail·max(ΔS, 0)
};

/// The bounce loop both backends run. Bounce b's surfel flux is S_b = S_direct + ρ·A·E(C_{b−1}),
/// its caches C_b. Progressive updates converge the series: its increments ΔS_b = S_b − S_{b−1}
/// shrink by the ratio q of the transport's leading eigenvalue (per channel, at most the largest
/// albedo), so all the light after the last bounce computed is ΔS·q/(1 − q). The last surfel
/// pass adds it (the geometric tail, as the ambient term of progressive radiosity does) instead
/// of stopping short of the converged light: white rooms keep 5–10 % of their indirect light
/// in the bounces after the eighth. Fixed bounce counts add no tail: they are what they say.
class BounceSchedule {
public:
    /// `ratioBound`: the largest surfel albedo per channel (bounceRatioBound).
    BounceSchedule(const BounceParams& params, glm::vec3 ratioBound);
    /// Cache passes at most.
    int maxPasses() const { return mPasses; }
    /// Records the summed surfel flux (W, RGB) of the next bounce, the direct flux first.
    /// Returns whether that bounce's cache pass runs: always for the first bounce, one planned
    /// as the last and fixed counts; progressive, only while it adds more than `convergence`
    /// of the flux.
    bool record(const glm::dvec3& total);
    /// After bounce b's cache pass (b ≥ 2 needs the totals of bounces 1…b recorded; b = 1 none):
    /// whether bounce b + 1 follows, whether it is the last and its tail. Progressive, bounce
    /// b + 1 is the last at the cap, or from b = 3 on when the bounce after it would add less
    /// than `convergence` of the flux at the ratio of the last two increments (q² ΔS_b), so
    /// the loop runs as many passes as stopping on that bounce would. (The first ratio, bounced
    /// over direct light, does not predict the later ones.)
    BounceStep afterBounce(int bounce);

private:
    BounceParams mParams;
    glm::dvec3 mRatioBound;
    int mPasses = 0;
    bool mLastPlanned = false;
    std::vector<glm::dvec3> mTotals;  ///< per bounce recorded
};

/// The largest surfel albedo per channel, at most 0.95: no bounce returns more of the light
/// than that (energy conservation); the cap keeps the tail of a room of perfect white finite.
glm::vec3 bounceRatioBound(const BakeData& bake);

/// Timings and counts of one update.
struct UpdateStats {
    int bounces = 0;                          ///< cache passes run
    std::map<std::string, double> passMs;     ///< milliseconds per pass, summed over bounces
    double totalMs = 0.0;
    double surfelFlux = 0.0;                  ///< W, luminance of the last bounce's surfel flux
    int shadowMapsRendered = 0;               ///< lights whose shadow maps were re-rendered (GPU)
    uint64_t shadowTriangles = 0;             ///< triangles rasterised into them, after culling (GPU)
    uint64_t shadowTexels = 0;                ///< texels of the layers rendered (GPU)
    int lightsTraced = 0;  ///< lights whose visibility rays were traced (GPU, rays)
};

/// Called after each bounce's cache pass with that bounce's caches (before the direct sky,
/// which follows the last bounce) and whether the runtime knows it is the last: what a
/// budgeted server streams before the update ends (server/progressive.h). Both backends have
/// the caches on the host then anyway (the GPU reads them back after every submission).
using BounceObserver = std::function<void(int bounce, const CacheValues& caches, bool last)>;

/// A runtime backend over one bake of one scene.
class Runtime {
public:
    virtual ~Runtime() = default;
    /// Relights the scene with `lights` and returns the caches' incident radiance; `observer`,
    /// when set, sees every bounce's caches as they are computed.
    virtual Result<const CacheValues*> setLights(const LightSet& lights, UpdateStats* stats = nullptr,
                                                 const BounceObserver& observer = {}) = 0;
    /// The last update's caches as the grid and light-map textures renderers sample
    /// (core/cache_textures.h layout), made on demand: `picref shade` shades from them;
    /// picserver streams the caches themselves and never asks.
    virtual Result<const CacheTextures*> textures() = 0;
    /// Backend name for logs ("cpu", "gpu").
    virtual const char* name() const = 0;
};

/// What every backend relies on beyond the bake file's own validation: the bake belongs to
/// this scene, its band counts and link counts agree, and the hierarchy is ordered so that a
/// level-by-level pull reads only finished nodes. InvalidInput naming the mismatch.
Result<void> checkRuntimeBake(const Scene& scene, const BakeData& bake);

/// BounceParams in range (InvalidInput naming the field).
Result<void> checkBounceParams(const BounceParams& params);

/// A light set fits the scene (checkLightSet) and holds only finite, non-negative numbers.
Result<void> checkRuntimeLights(const LightSet& lights, const Scene& scene);

}  // namespace pic
