#pragma once
/// `picref probes`: the ideal caches of a bake. Path-traced incident radiance at every unique
/// cache, projected to SH with the bake's band counts (Y with lY bands, Co and Cg with lC),
/// i.e. what the runtime's caches would hold with exact transport: their error is the floor
/// of the SH representation itself (ARCHITECTURE.md §7).

#include <cstdint>

#include "bake/ref/path_tracer.h"
#include "core/bake_data.h"
#include "core/cache_values.h"
#include "core/error.h"
#include "core/light_set.h"
#include "core/scene.h"
#include "rays/embree_scene.h"

namespace pic {

/// How the ideal caches are estimated.
struct ProbeParams {
    uint32_t samples = 1024;  ///< stratified directions (one path each) per cache
    int bounces = -1;         ///< B ≥ 0: light that reflected off at most B surfaces before
                              ///< reaching the cache (0: emitters and the sky only); −1:
                              ///< unlimited
    uint64_t seed = 1;
    /// true: radiance from surfaces and the sky only, what the runtime's caches hold
    /// (reflected light of every order, emitted radiance and the sky where no geometry blocks
    /// it); false: plus the punctual lights' unoccluded direct light, each a delta of radiance
    /// I/d² (times colour and spot falloff) projected to SH.
    bool indirectOnly = true;
};

/// Estimates the incident radiance SH of every unique cache of `bake`: grid caches over the
/// full sphere, light-map caches over the hemisphere above Cache::normal (the lower one is
/// zero). Deterministic per seed for any thread count. InvalidInput when the bake's scene
/// hash differs from the scene's, its band counts are outside 1 ≤ lC ≤ lY ≤ 8, samples is 0
/// or bounces < −1; the sky's errors (PathTracer::create). `stats` (if given) receives the
/// path counts.
Result<CacheValues> pathTraceProbes(const Scene& scene, const EmbreeScene& rays,
                                    const BakeData& bake, const LightSet& lights,
                                    const ProbeParams& params, PathTraceStats* stats = nullptr);

}  // namespace pic
