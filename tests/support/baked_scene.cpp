// The shared baked test scene (tests/support/baked_scene.h): scenes loaded, baked and written
// once per (scene, options) for the test process.

#include "tests/support/baked_scene.h"

#include <map>
#include <tuple>
#include <utility>

#include <gtest/gtest.h>

#include "core/bake_file.h"
#include "core/gltf_loader.h"
#include "tests/support/command.h"

namespace pic::test {
namespace {

/// Every field of BakeOptions, and the sizes per diagonal where given: what makes two bakes
/// the same bake.
using BakeKey =
    std::tuple<std::string, std::optional<uint32_t>, std::optional<uint32_t>,
               std::optional<uint32_t>, std::optional<uint32_t>, std::optional<float>,
               std::optional<float>, GridCaches, LinkMode, HierarchyMethod, uint32_t, uint32_t, uint32_t, uint32_t,
               LinkReads, LinkCut, uint32_t, uint64_t, std::optional<std::pair<float, float>>>;

BakeKey keyOf(const std::string& name, const BakeOptions& o,
              std::optional<std::pair<float, float>> perDiagonal) {
    return {name,
            o.surfels,
            o.links,
            o.bandsY,
            o.bandsC,
            o.gridCell,
            o.lightmapTexel,
            o.gridCaches,
            o.linkMode,
            o.hierarchy,
            o.linkSamples,
            o.linkFinalSamples,
            o.exposureRays,
            o.skyRays,
            o.linkReads,
            o.linkCut,
            o.relaxIterations,
            o.seed,
            perDiagonal};
}

/// bakedScene for both sizings: `perDiagonal` (grid cell, light-map texel) replaces the
/// options' sizes once the scene's diagonal is known.
const BakedScene& bake(const std::string& name, const BakeOptions& options,
                       std::optional<std::pair<float, float>> perDiagonal) {
    static std::map<BakeKey, std::unique_ptr<BakedScene>> cache;
    auto& slot = cache[keyOf(name, options, perDiagonal)];
    if (slot) return *slot;
    slot = std::make_unique<BakedScene>();
    auto scene = loadScene(testScenePath(name));
    EXPECT_TRUE(scene) << name << ": " << (scene ? "" : scene.error().message);
    if (!scene) return *slot;
    slot->scene = std::move(*scene);
    auto rays = EmbreeScene::create(slot->scene);
    EXPECT_TRUE(rays) << name << ": " << (rays ? "" : rays.error().message);
    if (!rays) return *slot;
    slot->rays = std::move(*rays);
    BakeOptions sized = options;
    if (perDiagonal) {
        const float extent = slot->scene.bounds.diagonal();
        sized.gridCell = perDiagonal->first * extent;
        sized.lightmapTexel = perDiagonal->second * extent;
    }
    BakeReport report;
    auto baked = runBake(slot->scene, sized, report);
    EXPECT_TRUE(baked) << name << ": " << (baked ? "" : baked.error().message);
    if (!baked) return *slot;
    slot->bake = std::move(*baked);
    slot->ok = true;
    return *slot;
}

}  // namespace

std::string testScenePath(const std::string& name) {
    return std::string(PIC_TEST_SCENE_DIR) + "/" + name + ".gltf";
}

Scene loadTestScene(const std::string& name) {
    auto scene = loadScene(testScenePath(name));
    EXPECT_TRUE(scene) << name << ": " << (scene ? "" : scene.error().message);
    return scene ? std::move(*scene) : Scene{};
}

BakeOptions smallBakeOptions(uint32_t surfels, uint32_t links, std::optional<float> gridCell,
                             std::optional<float> lightmapTexel) {
    BakeOptions options;
    options.surfels = surfels;
    options.links = links;
    options.gridCell = gridCell;
    options.lightmapTexel = lightmapTexel;
    options.gridCaches = GridCaches::Volume;
    return options;
}

const BakedScene& bakedScene(const std::string& name, const BakeOptions& options) {
    return bake(name, options, std::nullopt);
}

const BakedScene& bakedScene(const std::string& name, const BakeOptions& options,
                             float gridCellPerDiagonal, float lightmapTexelPerDiagonal) {
    return bake(name, options, std::pair(gridCellPerDiagonal, lightmapTexelPerDiagonal));
}

const std::string& bakeFile(const std::string& name, const BakeOptions& options) {
    // Made in the first test that asks; removed when the process exits.
    static const ScratchDir dir("pic_test_bakes");
    static std::map<BakeKey, std::string> files;
    const BakeKey key = keyOf(name, options, std::nullopt);
    if (auto found = files.find(key); found != files.end()) return found->second;
    std::string& path = files[key];
    const BakedScene& baked = bakedScene(name, options);
    if (!baked.ok) return path;
    const std::string out = (dir / (name + "_" + std::to_string(files.size()) + ".pic")).string();
    auto written = writeBakeFile(out, baked.bake);
    EXPECT_TRUE(written) << out << ": " << (written ? "" : written.error().message);
    if (written) path = out;
    return path;
}

}  // namespace pic::test
