#pragma once
/// `picbench links`: where the linked caches' error comes from. Bakes a scene, lights the
/// surfels directly (one bounce, so that errors do not compound) and, for a sample of caches,
/// compares the band-0 luma of five estimates of the same incident radiance:
///   traced    path-traced one-bounce radiance (the truth),
///   gather    every surfel of the bake with exact visibility and its own radiance,
///   cut       the surfels of the cache's linked nodes, exact visibility, own radiance,
///   mean      the same surfels, each with its node's mean radiance Φ/(πA) (what a link
///             assumes), exact visibility,
///   linked    the runtime's cache (estimated visibility, node mean radiance).
/// Their ratios factor linked/traced into the surfel representation (gather/traced), the
/// coverage of the cut (cut/gather), the node-mean radiance (mean/cut) and the visibility
/// estimate (linked/mean). Writes JSON; never asserts.

#include <string>

#include "bake/bake.h"

namespace pic {

struct LinkErrorParams {
    std::string scenePath;
    std::string lightsPath;        ///< empty: the scene's own lights
    BakeOptions bake;
    uint32_t caches = 400;         ///< caches to examine, evenly spread over the cache list
    uint32_t directions = 1024;    ///< path-traced directions per examined cache
    std::string jsonPath;          ///< empty: print only
    uint64_t seed = 1;
};

/// Runs the decomposition; returns the process exit code.
int runLinkErrorBenchmark(const LinkErrorParams& params);

}  // namespace pic
