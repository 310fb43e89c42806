#pragma once
/// `picbench sweep`: what each setting of pic costs and buys on one scene. Bakes the scene over
/// a grid of settings (nS, nL, lY, lC, link form, grid cell, light-map texel, link samples, the
/// GPU backend's visibility source), relights every bake with the scene's lights and measures
/// it against a path-traced reference at the same views: indirect and full relative RMSE, mean
/// luminance ratio, blotch index against the ideal caches of the same layout; bake seconds,
/// peak memory and file bytes; update ms on the CPU twin and on the GPU backend, run in turn;
/// runtime memory; stream bytes of a key and a delta frame. The methods a user would run
/// instead go through the same measurement on the default bake's caches: the ideal caches
/// (path-traced, the representation's floor), ray-traced probes updated at runtime
/// (bench/traced_probes.h) and a light propagation volume (bench/light_propagation_volume.h).
/// Writes CSV, JSON and PNG charts (error against update ms, memory and stream bytes, the
/// Pareto front drawn and labelled). References, ideal images and finished points are kept
/// in the output folder: a killed sweep resumes where it stopped.

#include <cstdint>
#include <string>
#include <vector>

#include "bake/bake.h"
#include "core/cli.h"
#include "core/error.h"

namespace pic {

struct SweepParams {
    std::string scenePath;
    std::string lightsPath;           ///< empty: the scene's own lights
    View view;                        ///< image size, and --camera when given
    std::vector<int> sceneCameras;    ///< views: these scene cameras (ignored with --camera)
    std::string grid = "coarse";      ///< "coarse" (the default grid) or "fine"
    /// picbake flags every bake of the sweep starts from (its "default" point); a setting's own
    /// flags replace those of the same name.
    std::vector<std::string> baseBakeArgs;
    std::vector<std::string> baselines{"ideal", "traced", "lpv"};
    uint32_t spp = 256;               ///< reference samples per pixel (two halves, seeds 1, 2)
    uint32_t probeSamples = 256;      ///< directions per ideal cache
    uint32_t shadeSpp = 2;            ///< subsamples per pixel shading from caches
    int repeat = 5;                   ///< timed updates per backend; medians
    bool gpu = true;                  ///< also time the GPU backend (Vulkan; lavapipe here)
    std::string device;               ///< Vulkan device name substring
    std::string outDir;               ///< empty: out/sweep/<scene>
    std::string picbake;              ///< empty: the build tree's picbake
    uint32_t maxPoints = 0;           ///< > 0: only the first N settings (tests, trials)
    bool keepBakes = false;           ///< keep each setting's .pic file
    /// Targets E to bake with `picbake --target-error E` after the grid (`picbench autotune`):
    /// each bake measured as a point and checked against the grid: its error against the
    /// truth at most E, its update at most 1.1 × the cheapest grid point's that meets E.
    std::vector<double> targetErrors;
};

/// One setting of the sweep: the bake flags it passes to picbake and the GPU backend's
/// visibility source.
struct SweepSetting {
    std::string name;                 ///< what differs from the default ("default", "nL 32", …)
    std::string axis;                 ///< the parameter it varies ("default", "nL", "diagonal", …)
    std::vector<std::string> bakeArgs;  ///< picbake flags; empty values are the scene's defaults
    std::string visibility = "rays";  ///< "rays" or "shadow-maps"

    /// A file-name-safe key that identifies the setting (its flags and visibility).
    std::string key() const;
};

/// The scene's default bake parameters that the grid scales.
struct SweepDefaults {
    uint32_t surfels = 0;
    uint32_t links = 0;
    uint32_t bandsY = 0, bandsC = 0;
    float gridCell = 0.0f;
    float lightmapTexel = 0.0f;
    uint32_t linkSamples = 0;
};

/// `base` with the flags of `overrides` put in: a flag in both takes the value of `overrides`
/// (flags with one value each, as picbake's bake flags are).
std::vector<std::string> mergeFlags(const std::vector<std::string>& base,
                                    const std::vector<std::string>& overrides);

/// The settings of grid `grid` ("coarse" or "fine") around `defaults`: the default, each
/// parameter alone at each of its levels, and a diagonal where all of them move together
/// towards the cheap and the expensive end. InvalidInput naming an unknown grid.
Result<std::vector<SweepSetting>> sweepGrid(const std::string& grid, const SweepDefaults& defaults);

/// Runs the sweep; returns the process exit code.
int runSweepBenchmark(const SweepParams& params);

}  // namespace pic
