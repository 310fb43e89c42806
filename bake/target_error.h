#pragma once
/// `picbake bake --target-error E`: the cheapest bake predicted to meet an error target, found
/// by a pilot on the scene itself; nothing is looked up from other scenes.
///
/// The pilot path-traces the scene's views small, in two independent halves whose difference
/// gives the reference's own noise n, so that a bake's error against the truth is √(e² − n²)
/// with e its measured relative RMSE, and over the views the root mean square of theirs. It bakes the user's
/// settings (the base) and each setting alone up to three steps cheaper (nS, nL ×½, ×¼ and ×⅛;
/// lY − 1; each lC below the base; grid cell and light-map texel ×2 and ×4; 4 link samples)
/// and every setting at its cheapest at once (the corner) — and, where the base misses the
/// target, each setting a step dearer — relights each with the CPU twin, times its updates in
/// turns with the base's and measures its error.
///
/// Two models then rank every combination of those levels. Error: independent approximations
/// add their squared errors, view by view: e²(combination) = e²(base) + Σ (e²(setting alone) −
/// e²(base)). Cost: the update's CPU ms as a non-negative fit of link reads (caches · nL), link
/// reads times SH coefficients, surfels and a constant to the measured bakes. The cheapest
/// combination predicted within safety · E is baked and measured; if it misses, the error
/// model's sums are scaled up by what the miss shows, every combination no dearer on any
/// setting is struck out, and the next is tried. Measurements are kept in a cache keyed by the
/// scene, its base settings, lights, views and pilot, so a second target on the same scene
/// bakes only what it has not measured.

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "bake/bake.h"
#include "core/bake_data.h"
#include "core/error.h"
#include "core/image.h"
#include "core/light_set.h"
#include "core/scene.h"
#include "rays/embree_scene.h"

namespace pic {

/// What the pilot aims for and how it measures.
struct TargetErrorParams {
    double error = 0.0;             ///< E: relative RMSE of the indirect light against path tracing
                                    ///< (what the caches carry: PathTraceParams::Component::Cached)
    std::optional<double> budgetMs; ///< M: most CPU twin ms per update on this machine
    std::string lightsPath;         ///< the light set the pilot relights with ("": the scene's)
    std::vector<Camera> cameras;    ///< the pilot's views (empty: pilotViews)
    glm::uvec2 size{96, 72};        ///< pilot image size
    uint32_t spp = 256;             ///< reference samples per pixel (two halves)
    uint32_t shadeSpp = 2;          ///< subsamples per pixel shading from the caches
    /// The choice's measured error must be at most safety × E: the pilot's estimate of the
    /// error against the truth scatters by 1–2 % (its reference's own noise), its images are
    /// small and its views are not every view a user will look from.
    double safety = 0.95;
    uint32_t maxChecks = 4;         ///< combinations baked to check the models, at most
    std::string cacheDir;           ///< where measurements are kept ("": nowhere)
};

/// The settings the pilot varies, each over a few levels ordered from cheapest to dearest.
enum class TargetAxis { Surfels, Links, BandsY, BandsC, GridCell, Texel, LinkSamples };
inline constexpr size_t kTargetAxes = 7;

/// The levels of one setting: values (counts, bands or metres), cheapest first, and the base's.
struct TargetAxisLevels {
    TargetAxis axis;
    std::vector<double> values;
    size_t base = 0;
};

/// A combination of levels: one index per axis into TargetAxisLevels::values.
using TargetLevels = std::array<uint8_t, kTargetAxes>;

/// The axes and levels around `base` (the user's bake flags; unset values are the scene's
/// defaults); empty when the base does not resolve.
std::vector<TargetAxisLevels> targetAxes(const Scene& scene, const BakeOptions& base);

/// `base` with the values of `levels` put in.
BakeOptions targetOptions(const BakeOptions& base, const std::vector<TargetAxisLevels>& axes,
                          const TargetLevels& levels);

/// What differs from the base, as the sweep names settings ("nL 32, grid cell x2"), or "base".
std::string targetLevelsName(const std::vector<TargetAxisLevels>& axes, const TargetLevels& levels);

/// One bake the pilot measured.
struct TargetRung {
    std::string name;
    std::string kind;        ///< "base", "single" (one setting moved), "corner" (every setting at its
                             ///< cheapest) or "check" (a combination the models chose)
    TargetLevels levels{};
    BakeParams params;       ///< as resolved by the bake
    size_t caches = 0;
    size_t gridCaches = 0;   ///< of `caches`, those of the grid
    double bakeSeconds = 0.0;
    double updateMs = 0.0;   ///< CPU twin: the base's median of 5 updates; another rung's, the
                             ///< median ratio of 5 updates timed in turns with the base's, times it
    std::vector<double> viewErrors;  ///< per view, against the truth: √max(e² − n², 0)
    double error = 0.0;      ///< against the truth over the views: √(mean of their squares)
    double measured = 0.0;   ///< relative RMSE against the pilot reference, likewise
    std::optional<double> predictedError;  ///< checks: what the models predicted before baking
    double predictedMs = 0.0;  ///< the cost model's update ms
    bool meets = false;      ///< error ≤ safety × E and within the budget
    bool cached = false;     ///< measured by an earlier pilot (kept in the cache)
};

/// The fitted cost: ms ≈ Σ coefficient · feature (link reads, link reads · SH coefficients,
/// surfels, 1).
struct TargetCostModel {
    std::array<double, 4> coefficients{};
    double predict(double caches, double links, double coefficientsPerCache, double surfels) const;
};

/// The pilot's outcome: the chosen bake and what led to it.
struct TargetChoice {
    BakeData bake;           ///< the chosen rung's bake, ready to write
    BakeReport report;       ///< its bake report
    std::vector<TargetRung> rungs;  ///< every bake measured, in the order measured
    size_t chosen = 0;       ///< index into rungs
    bool met = false;        ///< a rung met the target; otherwise the most accurate one within
                             ///< the budget (or the cheapest, if none fits it) was chosen
    double noise = 0.0;      ///< the pilot reference's own relative RMSE (mean over views)
    std::vector<std::string> views;  ///< how each view was found
    TargetCostModel cost;
    double errorScale = 1.0; ///< the error model's sum as the checks corrected it
    size_t combinations = 0; ///< combinations the models ranked
    std::string cachePath;   ///< the cache file ("" without one)
    double pilotSeconds = 0.0;
};

/// The mean of two independent estimates `a` and `b` of the same image (same sizes required).
Image meanOfHalves(const Image& a, const Image& b);

/// The relative RMSE against the truth of the mean of two independent estimates `a` and `b`
/// of the same image: RMS(a − b)/2 over the mean's level (their difference has twice the
/// variance of either, their mean half of it). Same sizes required.
double halvesNoise(const Image& a, const Image& b);

/// The views the pilot measures: the scene's cameras (at most 2) that see indirect light under
/// `lights`; without any, the first four that do of: the middle of the bounds, each lamp, the
/// lower and the upper half of the bounds, each looking along +x, −x, +z and −z (a person
/// turning round). A view sees indirect light when its eye is not inside a solid and a small
/// path-traced image of the cached component is not black (a relative error needs light).
/// `how` receives a description of each. InvalidInput when no view sees any.
Result<std::vector<Camera>> pilotViews(const Scene& scene, const EmbreeScene& rays, const LightSet& lights,
                                       std::vector<std::string>& how);

/// Runs the pilot, one line per step on stderr. InvalidInput for E not in (0, 10], a budget
/// ≤ 0 or a bad light set.
Result<TargetChoice> chooseBakeForTarget(const Scene& scene, const BakeOptions& base,
                                         const TargetErrorParams& params);

/// The choice as JSON (`picbake info --json` shows it under "target").
nlohmann::ordered_json targetJson(const TargetChoice& choice, const TargetErrorParams& params);

}  // namespace pic
