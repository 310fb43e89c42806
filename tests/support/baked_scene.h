#pragma once
/// The baked test scene that tests share: a generated scene (tests/scenes/) loaded, its Embree
/// scene and a small bake of it, made once per (scene, options) for the test process; and the
/// same bake written once to a file for the tests that run the command-line tools on it.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "bake/bake.h"
#include "core/bake_data.h"
#include "core/scene.h"
#include "rays/embree_scene.h"

namespace pic::test {

/// The path of generated test scene `name` ("cornell" → <PIC_TEST_SCENE_DIR>/cornell.gltf).
std::string testScenePath(const std::string& name);

/// Generated test scene `name`, loaded afresh; an empty Scene, with a test failure, when it
/// does not load.
Scene loadTestScene(const std::string& name);

/// Bake options small enough for a test: `surfels` surfels, `links` links per cache, the grid
/// cell and light-map texel in metres (unset: the bake's defaults for the scene), grid caches
/// in the whole volume (the tests examine them), everything else at BakeOptions' defaults.
BakeOptions smallBakeOptions(uint32_t surfels, uint32_t links,
                             std::optional<float> gridCell = std::nullopt,
                             std::optional<float> lightmapTexel = std::nullopt);

/// A test scene, its Embree scene and its bake.
struct BakedScene {
    Scene scene;
    std::unique_ptr<EmbreeScene> rays;
    BakeData bake;
    bool ok = false;  ///< all three made; otherwise the failure was reported to the test
};

/// Test scene `name` baked with `options`, made once per (name, options) and kept for the
/// process.
const BakedScene& bakedScene(const std::string& name, const BakeOptions& options);

/// The same with the grid cell and light-map texel of `options` set to these fractions of the
/// scene's diagonal (the runtime tests size them so, whatever the scene).
const BakedScene& bakedScene(const std::string& name, const BakeOptions& options,
                             float gridCellPerDiagonal, float lightmapTexelPerDiagonal);

/// A bake file of test scene `name` with `options`, written once per (name, options) into a
/// scratch directory that lasts as long as the process; "" (with a test failure) when baking
/// or writing failed.
const std::string& bakeFile(const std::string& name, const BakeOptions& options);

}  // namespace pic::test
