#pragma once
/// The runtime of paper 000 Figure 2 behind one API with two backends (GPU, CPU twin):
/// a light change in, cache radiance out.

#include <map>
#include <memory>
#include <string>

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

/// A runtime backend over one bake of one scene.
class Runtime {
public:
    virtual ~Runtime() = default;
    /// Relights the scene with `lights` and returns the caches' incident radiance.
    virtual Result<const CacheValues*> setLights(const LightSet& lights, UpdateStats* stats = nullptr) = 0;
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
