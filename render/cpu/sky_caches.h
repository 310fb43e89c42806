#pragma once
/// Sky caches, CPU twin: the direct sky added to every cache after the last bounce's cache
/// lighting, c_i += Σ_k W_ik v_k per YCoCg channel (core/sky.h SkyCacheWeights), v the cache's
/// sky visibility (BakeData::cacheSky). The bounces read caches without it: the surfels'
/// direct flux already holds the sky they see, so caches lit again from it would count it twice.

#include "core/bake_data.h"
#include "core/cache_values.h"
#include "core/sky.h"

namespace pic {

/// Adds the sky of `weights` (made for the bake's lY, lC) to every cache of `values`.
/// CacheValues::irradiance is left as the bounces need it.
void addSkyToCaches(const BakeData& bake, const SkyCacheWeights& weights, CacheValues& values);

}  // namespace pic
