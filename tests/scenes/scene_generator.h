#pragma once
/// Procedural glTF 2.0 test scenes (Cornell boxes, stacked rooms, a Sponza-like atrium, error
/// cases), written deterministically as NAME.gltf plus NAME.bin in metres, Y up, right-handed.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/error.h"

namespace pic::testscenes {

/// Knobs of the generated scenes; the defaults give the scenes the test suites expect.
struct SceneOptions {
    uint32_t atriumTriangles = 250000;  ///< target triangle count of `atrium`, met within ±5 %
};

/// `textured_quad`'s base-colour texture: a kCheckerSize² checkerboard whose texel in column i,
/// row j (row 0 at v = 0) is kCheckerSrgbA when i + j is even and kCheckerSrgbB otherwise (8-bit
/// sRGB).
inline constexpr int kCheckerSize = 8;
inline constexpr std::array<uint8_t, 3> kCheckerSrgbA{230, 40, 40};
inline constexpr std::array<uint8_t, 3> kCheckerSrgbB{40, 40, 230};

/// What writing one scene produced.
struct WrittenScene {
    std::vector<std::string> files;  ///< paths written, the .gltf first
    uint64_t triangleCount = 0;      ///< triangles over all TRIANGLES primitives
};

/// Names of every scene writeTestScene knows, in a fixed order.
std::vector<std::string> testSceneNames();

/// Writes scene `name` into `outDir` (created if missing) and reports the files and triangles.
Result<WrittenScene> generateTestScene(const std::string& name, const std::string& outDir,
                                       const SceneOptions& options);

/// Writes scene `name` into `outDir` (created if missing) as NAME.gltf and, if it has geometry,
/// NAME.bin.
Result<void> writeTestScene(const std::string& name, const std::string& outDir,
                            const SceneOptions& options);

}  // namespace pic::testscenes
