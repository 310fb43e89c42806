#pragma once
/// What the picbench benchmarks share: medians, paper 000 Table 2's settings, the light
/// changes they time, loading a scene with its lights and rays, and their JSON output.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bake/bake.h"
#include "bench/chart.h"
#include "core/error.h"
#include "core/image.h"
#include "core/light_set.h"
#include "core/scene.h"
#include "rays/embree_scene.h"

namespace pic {

/// Median of `values` (0 when empty).
double median(std::vector<double> values);

/// Paper 000 Table 2's settings as bake options: "moderate" (nS 32k, nL 128, lY 3) or
/// "high" (nS 128k, nL 254, lY 4), with "rtp" or "sh" links and `chromaBands` lC (2 in the
/// paper's settings; the bake refuses lC > lY), grid caches in the whole volume as the
/// paper's.
BakeOptions settingOptions(const std::string& setting, const std::string& linkMode,
                           uint32_t chromaBands = 2);

/// The light set of update `k` under a kind of change: "move-all" (every light moves by a
/// small step: point and spot lights along x, directional lights tilt), "move-one" (the
/// first point or spot light moves, else the first light) or "recolour" (intensities
/// change by a few per cent). `step` is in metres.
LightSet changedLights(const LightSet& base, int k, float step, const std::string& change);

/// A scene with its light set and rays (over the scene: it stays where it was loaded).
struct BenchInputs {
    Scene scene;
    LightSet lights;
    std::unique_ptr<EmbreeScene> rays;
};

/// Loads the scene, its light set (`lightsPath` empty: the scene's own) and its rays;
/// prints the error and returns null on failure.
std::unique_ptr<BenchInputs> loadBenchInputs(const std::string& scenePath, const std::string& lightsPath);

/// Prints `error` on stderr and returns its exit code.
int reportError(const Error& error);

/// The chart written beside a benchmark's JSON: "x.json" → "x.png".
std::string chartPathFor(const std::string& jsonPath);

/// Writes `chart` to `path` (creating its folder) and says so; returns the exit code.
int writeChartFile(const Chart& chart, const std::string& path);

/// The images placed left to right, top-aligned, on black (for side-by-side PNGs).
Image imagesSideBySide(const std::vector<const Image*>& images);

/// Writes `json` to `path` (creating its folder) and says so; returns the exit code.
int writeJson(const nlohmann::ordered_json& json, const std::string& path);

}  // namespace pic
