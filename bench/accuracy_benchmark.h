#pragma once
/// `picbench accuracy`: bakes a scene, runs the runtime's CPU twin, shades from the caches,
/// path-traces the same view as ground truth, and reports the error (relative RMSE, mean
/// luminance ratio) of the indirect component and of the full image, for the linked caches
/// and for the ideal (path-traced) caches, with the wall time of every step. Writes JSON and
/// side-by-side PNGs with an error heat map. Never asserts.

#include <string>
#include <vector>

#include "bake/bake.h"
#include "core/cli.h"

namespace pic {

struct AccuracyParams {
    std::string scenePath;
    std::string lightsPath;   ///< empty: the scene's own lights
    View view;                ///< image size and camera
    uint32_t spp = 256;           ///< path-traced reference samples per pixel
    uint32_t probeSamples = 1024; ///< path-traced directions per ideal cache
    uint32_t shadeSpp = 4;        ///< subsamples per pixel when shading from caches
    int bounces = -1;             ///< runtime and reference bounces (−1: converged / unlimited)
    BakeOptions bake;
    std::string outDir = "out/accuracy";
    std::string jsonPath;         ///< empty: <outDir>/<scene>_accuracy.json
    uint64_t seed = 1;
    /// Non-empty: the speed/accuracy trade-off instead of one comparison. One bake per nL,
    /// each timed (CPU twin update) and compared with one reference; JSON
    /// (<outDir>/<scene>_links_sweep.json unless jsonPath) and a PNG chart beside it.
    std::vector<uint32_t> linksSweep;
};

/// Runs the comparison; returns the process exit code.
int runAccuracyBenchmark(const AccuracyParams& params);

}  // namespace pic
