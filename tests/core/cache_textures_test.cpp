// The cache textures' layout: sizes from the index maps and band counts, coefficients zero
// until a copy, coverage 1 exactly where a map names a cache. The light-map copy
// (copyCachesToTextures) on a 2×1×2 grid and a 3×1 light map: texels take their caches'
// coefficients layer by layer, and coverage-renormalised trilinear interpolation of the
// textures equals the grid lookup.

#include <gtest/gtest.h>

#include <vector>

#include "core/bake_data.h"
#include "core/cache_textures.h"
#include "core/cache_values.h"

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

TEST(LightmapCopy, TexelsTakeTheirCacheCoefficientsLayerByLayer) {
    BakeData bake;
    bake.params.bandsY = 2;
    bake.params.bandsC = 1;
    bake.caches.resize(2);
    bake.grid.origin = {0.0f, 0.0f, 0.0f};
    bake.grid.cellSize = 1.0f;
    bake.grid.dims = {2, 1, 2};
    bake.grid.cacheIndex = {0, kNoCache, 1, 0};
    bake.lightmap.width = 3;
    bake.lightmap.height = 1;
    bake.lightmap.cacheIndex = {1, kNoCache, 0};
    CacheValues values = CacheValues::zeros(2, 2, 1);
    for (int i = 0; i < 8; ++i) values.y[i] = float(10 + i);  // cache 0: 10..13, cache 1: 14..17
    values.co = {-1.0f, -2.0f};
    values.cg = {0.5f, 0.25f};

    CacheTextures textures = makeCacheTextures(bake);
    copyCachesToTextures(bake, values, textures);
    EXPECT_EQ(textures.layers(0), 4u);
    EXPECT_EQ(textures.layers(1), 1u);
    EXPECT_EQ(textures.gridCoverage, (std::vector<float>{1, 0, 1, 1}));
    EXPECT_EQ(textures.lightmapCoverage, (std::vector<float>{1, 0, 1}));
    // Grid Y: layer k holds coefficient k of each vertex's cache, 0 where there is none.
    EXPECT_EQ(textures.grid[0], (std::vector<float>{10, 0, 14, 10, 11, 0, 15, 11,  //
                                                    12, 0, 16, 12, 13, 0, 17, 13}));
    EXPECT_EQ(textures.grid[1], (std::vector<float>{-1, 0, -2, -1}));
    EXPECT_EQ(textures.grid[2], (std::vector<float>{0.5f, 0, 0.25f, 0.5f}));
    EXPECT_EQ(textures.lightmap[0],
              (std::vector<float>{14, 0, 10, 15, 0, 11, 16, 0, 12, 17, 0, 13}));
    EXPECT_EQ(textures.lightmap[1], (std::vector<float>{-2, 0, -1}));
    EXPECT_EQ(textures.lightmap[2], (std::vector<float>{0.25f, 0, 0.5f}));
}

TEST(LightmapCopy, CoverageRenormalisedTrilinearEqualsTheGridLookup) {
    // A renderer interpolating the textures and dividing by interpolated coverage must see
    // what core/cache_values.h computes.
    BakeData bake;
    bake.params.bandsY = 1;
    bake.params.bandsC = 1;
    bake.caches.resize(3);
    bake.grid.origin = {-1.0f, 0.0f, 2.0f};
    bake.grid.cellSize = 0.5f;
    bake.grid.dims = {2, 2, 2};
    bake.grid.cacheIndex = {0, 1, kNoCache, 2, kNoCache, 0, 1, kNoCache};
    bake.lightmap.width = bake.lightmap.height = 0;
    CacheValues values = CacheValues::zeros(3, 1, 1);
    values.y = {1.0f, 3.0f, 8.0f};
    CacheTextures textures = makeCacheTextures(bake);
    copyCachesToTextures(bake, values, textures);

    const glm::vec3 p(-0.8f, 0.35f, 2.1f);
    const glm::vec3 f = (p - bake.grid.origin) / bake.grid.cellSize;
    double value = 0.0, coverage = 0.0;
    for (int corner = 0; corner < 8; ++corner) {
        const int x = corner & 1, y = (corner >> 1) & 1, z = corner >> 2;
        const double w = (x ? f.x : 1 - f.x) * (y ? f.y : 1 - f.y) * (z ? f.z : 1 - f.z);
        const int index = x + 2 * (y + 2 * z);
        value += w * textures.grid[0][index];
        coverage += w * textures.gridCoverage[index];
    }
    const RadianceSh lookup = lookupGridRadiance(bake, values, p);
    EXPECT_NEAR(lookup.rgb[1][0], value / coverage, 1e-5);
}

}  // namespace
}  // namespace pic
