#pragma once
/// `picbench links`: where the linked caches' error comes from. Bakes a scene, lights the
/// surfels directly (one bounce, so that errors do not compound) and, for a sample of caches,
/// compares the band-0 luma (and each RGB channel) of six estimates of the same incident
/// radiance:
///   traced    ray-traced radiance of what the first runtime bounce holds (the truth):
///             emitters seen directly and punctual light reflected once, with shadow rays,
///   gather    every surfel of the bake with exact visibility and its own radiance,
///   cut       the surfels of the cache's linked nodes, exact visibility, own radiance,
///   mean      the same surfels with the radiance a link reads for them: the node's flux
///             spread by the bake's flux weights, Φ·w/(π·Σ w·a) (Φ/(πA) with uniform
///             weights), per channel in the surfels' colours κ, Φ·w·κ/(π·Σ w·κ·a), with
///             visible-part reads (the links' tints), exact visibility,
///   spread    the same with the node's flux spread (render/node_spread.h) read as the runtime
///             reads it, at the centroid of the part the cache sees (Σ w·Ω·k·x / Σ w·Ω·k) with
///             that part's spread share: what the runtime's links read, exact visibility,
///   linked    the runtime's cache (estimated visibility, the spread read at each link's box
///             point).
/// Their ratios factor linked/traced into the surfel representation (gather/traced), the
/// coverage of the cut (cut/gather), the node radiance model with the spread (spread/cut) and
/// the visibility estimate (linked/spread); mean/cut, the model without the spread, is printed
/// beside them. Under each ratio, its scatter: the RMS over the caches of their own ratio's
/// relative deviation from it (weighted by the denominator's luma), how much neighbouring
/// caches disagree in that factor, which shows as blotches rather than bias. The traced
/// estimate's Monte Carlo noise adds to the scatter of the first two (about 0.2 at 1,024
/// directions in a sunlit room; use ≥ 16,384 to read them). For light-map caches, which an
/// image shows as their irradiance along the normal through the lY bands, the same chain
/// along the normal (`along_normal`): representation, the cut with the spread model, the
/// links' cones and visibility; the spread is read at the part's centroid as the bake
/// weighs it (bake/link_generation.h LinkReadWeight). Writes JSON, with every examined
/// cache's place, kind and ratios under `caches`; never asserts.

#include <string>
#include <vector>

#include "bake/bake.h"

namespace pic {

struct LinkErrorParams {
    std::string scenePath;
    std::string lightsPath;        ///< empty: the scene's own lights
    BakeOptions bake;
    uint32_t caches = 400;         ///< caches to examine, evenly spread over the cache list
    /// Empty, or x, y, z, r: examine only the caches within r metres of (x, y, z) (a region
    /// an image shows, whose caches a sample of the whole bake may miss)
    std::vector<float> near;
    uint32_t directions = 1024;    ///< path-traced directions per examined cache
    bool oneSidedTruth = false;    ///< the traced bounce takes no light off a surface's back,
                                   ///< as the surfels (front faces only) do
    std::string jsonPath;          ///< empty: print only
    uint64_t seed = 1;
};

/// Runs the decomposition; returns the process exit code.
int runLinkErrorBenchmark(const LinkErrorParams& params);

}  // namespace pic
