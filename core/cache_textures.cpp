#include "core/cache_textures.h"

#include "core/error.h"
#include "core/parallel.h"

namespace pic {
namespace {

/// 1 where an index map has a cache, 0 where it has none.
std::vector<float> coverageOf(std::span<const uint32_t> cacheIndex) {
    std::vector<float> coverage(cacheIndex.size());
    for (size_t t = 0; t < cacheIndex.size(); ++t)
        coverage[t] = cacheIndex[t] == kNoCache ? 0.0f : 1.0f;
    return coverage;
}

/// Gathers `count` coefficients per texel from cache-major `values` into coefficient-major
/// layers: one thread per texel reads its cache's contiguous coefficients (buffer 9) and
/// writes them one layer apart.
void copyChannel(std::span<const uint32_t> cacheIndex, const std::vector<float>& values,
                 size_t count, std::vector<float>& layers) {
    const size_t texels = cacheIndex.size();
    PIC_CHECK_EQ(layers.size(), texels * count);
    parallelFor(0, texels, [&](size_t t) {
        const uint32_t c = cacheIndex[t];
        if (c == kNoCache) {
            for (size_t k = 0; k < count; ++k) layers[k * texels + t] = 0.0f;
            return;
        }
        PIC_DCHECK((size_t{c} + 1) * count <= values.size());
        const float* src = values.data() + c * count;
        for (size_t k = 0; k < count; ++k) layers[k * texels + t] = src[k];
    }, 4096);
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

void copyCachesToTextures(const CacheIndexMaps& maps, const CacheValues& values,
                          CacheTextures& textures) {
    PIC_CHECK_EQ(values.bandsY, textures.bandsY);
    PIC_CHECK_EQ(values.bandsC, textures.bandsC);
    const std::array<const std::vector<float>*, 3> channels = {&values.y, &values.co, &values.cg};
    for (int ch = 0; ch < 3; ++ch) {
        copyChannel(maps.grid, *channels[ch], textures.layers(ch), textures.grid[ch]);
        copyChannel(maps.lightmap, *channels[ch], textures.layers(ch), textures.lightmap[ch]);
    }
}

void copyCachesToTextures(const BakeData& bake, const CacheValues& values,
                          CacheTextures& textures) {
    PIC_CHECK_EQ(values.cacheCount(), bake.caches.size());
    copyCachesToTextures(cacheIndexMapsOf(bake), values, textures);
}

}  // namespace pic
