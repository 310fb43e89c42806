// The cache textures' layout: sizes from the index maps and band counts, coefficients zero
// until a copy, coverage 1 exactly where a map names a cache.

#include <gtest/gtest.h>

#include <vector>

#include "core/cache_textures.h"

namespace pic {
namespace {

TEST(CacheTextures, LayersAndCoverageFollowTheIndexMaps) {
    // A 2×2×2 grid with caches at two vertices, a 3×1 light map with one.
    const std::vector<uint32_t> grid = {0, kNoCache, kNoCache, 1, kNoCache, kNoCache, kNoCache, 1};
    const std::vector<uint32_t> lightmap = {kNoCache, 2, kNoCache};
    const CacheIndexMaps maps{glm::uvec3(2), grid, 3, 1, lightmap};

    const CacheTextures textures = makeCacheTextures(maps, 3, 2);
    EXPECT_EQ(textures.bandsY, 3u);
    EXPECT_EQ(textures.bandsC, 2u);
    EXPECT_EQ(textures.layers(0), 9u);
    EXPECT_EQ(textures.layers(1), 4u);
    EXPECT_EQ(textures.layers(2), 4u);
    EXPECT_EQ(textures.gridDims, glm::uvec3(2));
    EXPECT_EQ(textures.lightmapWidth, 3u);
    EXPECT_EQ(textures.lightmapHeight, 1u);
    for (int ch = 0; ch < 3; ++ch) {
        ASSERT_EQ(textures.grid[ch].size(), 8u * textures.layers(ch)) << ch;
        ASSERT_EQ(textures.lightmap[ch].size(), 3u * textures.layers(ch)) << ch;
        for (float v : textures.grid[ch]) EXPECT_EQ(v, 0.0f);
        for (float v : textures.lightmap[ch]) EXPECT_EQ(v, 0.0f);
    }
    EXPECT_EQ(textures.gridCoverage, (std::vector<float>{1, 0, 0, 1, 0, 0, 0, 1}));
    EXPECT_EQ(textures.lightmapCoverage, (std::vector<float>{0, 1, 0}));
}

TEST(CacheTextures, IndexMapsOfABakeViewItsLayouts) {
    BakeData bake;
    bake.grid.dims = glm::uvec3(1, 2, 1);
    bake.grid.cacheIndex = {kNoCache, 0};
    bake.lightmap.width = 1;
    bake.lightmap.height = 1;
    bake.lightmap.cacheIndex = {1};
    const CacheIndexMaps maps = cacheIndexMapsOf(bake);
    EXPECT_EQ(maps.gridDims, bake.grid.dims);
    EXPECT_EQ(maps.grid.data(), bake.grid.cacheIndex.data());
    EXPECT_EQ(maps.grid.size(), 2u);
    EXPECT_EQ(maps.lightmap.data(), bake.lightmap.cacheIndex.data());
    EXPECT_EQ(maps.lightmapWidth, 1u);
    EXPECT_EQ(maps.lightmapHeight, 1u);
}

}  // namespace
}  // namespace pic
