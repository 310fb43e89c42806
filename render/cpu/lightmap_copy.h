#pragma once
/// Light-map copy, CPU twin (paper 000 Figure 2 step 5, §4.7, buffers 6 and 9): the unique
/// caches' SH written into the textures renderers interpolate (core/cache_textures.h), through
/// the bake's index maps.

#include "core/bake_data.h"
#include "core/cache_textures.h"
#include "core/cache_values.h"

namespace pic {

/// Copies every cache's coefficients into each grid vertex and light-map texel that holds it;
/// texels without a cache stay 0. `textures` comes from makeCacheTextures for the same maps
/// and `values` has the band counts of `textures` and every cache the maps name.
void copyCachesToTextures(const CacheIndexMaps& maps, const CacheValues& values,
                          CacheTextures& textures);
/// The same through `bake`'s maps; `values` has exactly the bake's caches.
void copyCachesToTextures(const BakeData& bake, const CacheValues& values, CacheTextures& textures);

}  // namespace pic
