#include "render/cpu/lightmap_copy.h"

#include "core/error.h"
#include "core/parallel.h"

namespace pic {
namespace {

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
