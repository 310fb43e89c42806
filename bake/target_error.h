#pragma once
/// `picbake bake --target-error E`: the cheapest bake predicted to meet an error target, found
/// by a pilot on the scene itself. The pilot path-traces the scene's views small (two
/// independent halves, whose difference gives the reference's own noise n), then bakes a
/// ladder of settings from the cheapest up, relights each with the CPU twin, shades it at the
/// same views and takes its error against the truth as √(e² − n²), e the measured relative
/// RMSE. The first rung whose error is at most the target times a safety factor (and whose
/// update fits the budget) is the choice; nothing is looked up from other scenes.

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

namespace pic {

/// What the pilot aims for and how it measures.
struct TargetErrorParams {
    double error = 0.0;             ///< E: relative RMSE against path tracing (indirect light;
                                    ///< the full image where surfaces emit)
    std::optional<double> budgetMs; ///< M: most CPU twin ms per update on this machine
    std::string lightsPath;         ///< the light set the pilot relights with ("": the scene's)
    glm::uvec2 size{64, 48};        ///< pilot image size
    uint32_t spp = 256;             ///< reference samples per pixel (two halves)
    uint32_t shadeSpp = 2;          ///< subsamples per pixel shading from the caches
    /// The choice's predicted error must be at most safety × E: the pilot's images are
    /// small and its views are not every view a user will look from.
    double safety = 0.85;
};

/// One rung of the ladder as the pilot measured it.
struct TargetRung {
    std::string name;
    BakeOptions options;
    BakeParams params;       ///< as resolved by the bake
    size_t caches = 0;
    double bakeSeconds = 0.0;
    double updateMs = 0.0;   ///< CPU twin, median of 3 updates
    double measured = 0.0;   ///< relative RMSE against the pilot reference (mean over views)
    double error = 0.0;      ///< against the truth: √max(e² − n², 0), mean over views
    bool meets = false;      ///< error ≤ safety × E and within the budget
};

/// The pilot's outcome: the chosen bake and what led to it.
struct TargetChoice {
    BakeData bake;           ///< the chosen rung's bake, ready to write
    BakeReport report;       ///< its bake report
    std::vector<TargetRung> rungs;  ///< every rung measured, cheapest first
    size_t chosen = 0;       ///< index into rungs
    bool met = false;        ///< a rung met the target; otherwise the most accurate one within
                             ///< the budget (or the cheapest, if none fits it) was chosen
    std::string component;   ///< "indirect" or "full"
    double noise = 0.0;      ///< the pilot reference's own relative RMSE (mean over views)
    std::vector<std::string> views;  ///< how each view was found
    double pilotSeconds = 0.0;
};

/// Whether any material emits: then the caches carry the emitters' light, whose first
/// reflection the path tracer counts as direct (PathTraceParams::Component), so only full
/// images compare with a reference; otherwise the indirect light does.
bool surfacesEmit(const Scene& scene);

/// The relative RMSE against the truth of the mean of two independent estimates `a` and `b`
/// of the same image: RMS(a − b)/2 over the mean's level (their difference has twice the
/// variance of either, their mean half of it). Same sizes required.
double halvesNoise(const Image& a, const Image& b);

/// The ladder of settings the pilot climbs, cheapest first, around `base` (the user's bake
/// flags; unset values are the scene's defaults): each rung scales nS and nL, coarsens the
/// grid cell and the light-map texel, and lowers lC and the link samples less the higher it
/// stands; the top rungs are `base` itself and one dearer than it.
std::vector<std::pair<std::string, BakeOptions>> targetLadder(const Scene& scene, const BakeOptions& base);

/// The views the pilot measures: the scene's cameras (at most 2), else one from the centre of
/// the bounds along their longest horizontal side. `how` receives a description of each.
std::vector<Camera> pilotViews(const Scene& scene, std::vector<std::string>& how);

/// Runs the pilot, one line per step on stderr. InvalidInput for E not in (0, 10], a budget
/// ≤ 0 or a bad light set.
Result<TargetChoice> chooseBakeForTarget(const Scene& scene, const BakeOptions& base,
                                         const TargetErrorParams& params);

/// The choice as JSON (`picbake info --json` shows it under "target").
nlohmann::ordered_json targetJson(const TargetChoice& choice, const TargetErrorParams& params);

}  // namespace pic
