#pragma once
/// The cache textures renderers sample (paper 000 §4.7, buffers 6 and 9): the unique caches'
/// SH written into every grid vertex and light-map texel that holds one, through the bake's
/// index maps. The server's runtime, `picref shade` and the thin client share this layout;
/// copyCachesToTextures fills it on the CPU (the light-map copy, paper 000 Figure 2 step 5),
/// render/passes/lightmap_copy_pass.h on a GPU.
///
/// Layout. Each channel of YCoCg is a monochrome texture array so that luma and chroma keep
/// different coefficient counts; layer k holds SH coefficient k (core/sh.h order) of that
/// channel:
///   grid[ch]      shCount(bands) layers of V = dims.x·dims.y·dims.z floats; vertex (x, y, z)
///                 of layer k at k·V + x + dims.x·(y + dims.y·z), the GridLayout vertex index.
///   lightmap[ch]  shCount(bands) layers of T = width·height floats; texel (x, y) of layer k
///                 at k·T + x + width·y, the LightmapLayout texel index (row 0 at v = 0).
/// with ch = 0, 1, 2 for Y (lY bands), Co and Cg (lC bands), radiance in W/(m²·sr).
/// Vertices and texels without a cache (kNoCache) hold 0 in every layer, and the coverage
/// layers hold 1 where there is a cache and 0 where there is none. A renderer that
/// interpolates coefficients and coverage with the same weights (grid: trilinear, clamped to
/// the edge; light map: bilinear, zero outside the atlas) and divides by the interpolated
/// coverage gets exactly the renormalised interpolation of core/cache_values.h, with no
/// dilation pass.

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "core/bake_data.h"
#include "core/cache_values.h"

namespace pic {

/// The grid volume and light-map texture of every YCoCg channel, plus coverage (see above).
struct CacheTextures {
    uint32_t bandsY = 0;                         ///< lY: layers of channel Y = lY²
    uint32_t bandsC = 0;                         ///< lC: layers of channels Co, Cg = lC²
    glm::uvec3 gridDims{0u};                     ///< grid vertices per axis
    uint32_t lightmapWidth = 0;                  ///< texels
    uint32_t lightmapHeight = 0;                 ///< texels
    std::array<std::vector<float>, 3> grid;      ///< Y, Co, Cg: coefficient-major layers
    std::array<std::vector<float>, 3> lightmap;  ///< Y, Co, Cg: coefficient-major layers
    std::vector<float> gridCoverage;             ///< V floats, 1 = cache, 0 = none
    std::vector<float> lightmapCoverage;         ///< T floats, 1 = cache, 0 = none

    /// Coefficient layers of channel ch (0 = Y, 1 = Co, 2 = Cg).
    uint32_t layers(int ch) const { return ch == 0 ? bandsY * bandsY : bandsC * bandsC; }
};

/// Where the caches go in the textures: the bake's index maps (GridLayout::cacheIndex,
/// LightmapLayout::cacheIndex), kNoCache where a vertex or texel holds none. The server has
/// them in its bake; a thin client downloads them with the scene.
struct CacheIndexMaps {
    glm::uvec3 gridDims{0u};
    std::span<const uint32_t> grid;  ///< dims.x·dims.y·dims.z, GridLayout vertex order
    uint32_t lightmapWidth = 0;
    uint32_t lightmapHeight = 0;
    std::span<const uint32_t> lightmap;  ///< width·height, LightmapLayout texel order
};

/// The index maps of `bake` (views into it).
CacheIndexMaps cacheIndexMapsOf(const BakeData& bake);

/// Textures for `maps` with lY and lC bands, coefficients zero, coverage written (it depends
/// on the maps only, so it is uploaded once).
CacheTextures makeCacheTextures(const CacheIndexMaps& maps, uint32_t bandsY, uint32_t bandsC);
/// The same for `bake`'s maps and band counts.
CacheTextures makeCacheTextures(const BakeData& bake);

/// Copies every cache's coefficients into each grid vertex and light-map texel that holds it;
/// texels without a cache stay 0. `textures` comes from makeCacheTextures for the same maps
/// and `values` has the band counts of `textures` and every cache the maps name.
void copyCachesToTextures(const CacheIndexMaps& maps, const CacheValues& values,
                          CacheTextures& textures);
/// The same through `bake`'s maps; `values` has exactly the bake's caches.
void copyCachesToTextures(const BakeData& bake, const CacheValues& values, CacheTextures& textures);

}  // namespace pic
