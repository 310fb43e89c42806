#include "core/cache_textures.h"

#include "core/error.h"

namespace pic {
namespace {

/// 1 where an index map has a cache, 0 where it has none.
std::vector<float> coverageOf(std::span<const uint32_t> cacheIndex) {
    std::vector<float> coverage(cacheIndex.size());
    for (size_t t = 0; t < cacheIndex.size(); ++t)
        coverage[t] = cacheIndex[t] == kNoCache ? 0.0f : 1.0f;
    return coverage;
}

}  // namespace

CacheIndexMaps cacheIndexMapsOf(const BakeData& bake) {
    return CacheIndexMaps{bake.grid.dims, bake.grid.cacheIndex, bake.lightmap.width,
                          bake.lightmap.height, bake.lightmap.cacheIndex};
}

CacheTextures makeCacheTextures(const CacheIndexMaps& maps, uint32_t bandsY, uint32_t bandsC) {
    CacheTextures textures;
    textures.bandsY = bandsY;
    textures.bandsC = bandsC;
    textures.gridDims = maps.gridDims;
    textures.lightmapWidth = maps.lightmapWidth;
    textures.lightmapHeight = maps.lightmapHeight;
    const size_t vertices = maps.grid.size();
    const size_t texels = maps.lightmap.size();
    PIC_CHECK_EQ(vertices, size_t{textures.gridDims.x} * textures.gridDims.y * textures.gridDims.z);
    PIC_CHECK_EQ(texels, size_t{textures.lightmapWidth} * textures.lightmapHeight);
    for (int ch = 0; ch < 3; ++ch) {
        textures.grid[ch].assign(vertices * textures.layers(ch), 0.0f);
        textures.lightmap[ch].assign(texels * textures.layers(ch), 0.0f);
    }
    textures.gridCoverage = coverageOf(maps.grid);
    textures.lightmapCoverage = coverageOf(maps.lightmap);
    return textures;
}

CacheTextures makeCacheTextures(const BakeData& bake) {
    return makeCacheTextures(cacheIndexMapsOf(bake), bake.params.bandsY, bake.params.bandsC);
}

}  // namespace pic
