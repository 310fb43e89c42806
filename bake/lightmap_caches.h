#pragma once
/// Light-map cache placement (paper 000 §4.4 and §4.7, buffers 6 and 9): one unique cache
/// per texel centre on a triangle, none behind other geometry (000 Fig. 9a), and seam
/// dilation that points empty texels around charts at a neighbour's cache.

#include <cstdint>
#include <vector>

#include "bake/lightmap_charts.h"
#include "core/bake_data.h"
#include "core/error.h"
#include "core/scene.h"
#include "rays/embree_scene.h"

namespace pic {

/// Light-map cache parameters.
struct LightmapCacheParams {
    float texelSize = 0.0f;  ///< metres per texel; must be the size the charts were built for
};

/// The light map's unique caches and the texel → cache index map.
struct LightmapCacheSet {
    LightmapLayout layout;         ///< cacheIndex per texel (firstCacheIndex + i, or kNoCache)
    std::vector<Cache> caches;     ///< unique caches, kind kCacheKindLightmap, texel = own texel
    uint32_t duplicateTexels = 0;  ///< texels filled by dilation with a neighbour's cache
    uint32_t relocated = 0;        ///< caches moved off an enclosed texel centre
    uint32_t rejected = 0;         ///< texels whose every candidate point was enclosed
    uint32_t gridShadedTriangles = 0;  ///< triangles of charts without caches (UVs kNotLightmapped)
};

/// Places the light-map caches of `charts` (moved into the layout).
///
/// Every texel whose centre lies inside a triangle gets a unique cache at that point (the
/// first triangle in scene order wins a shared centre); a triangle covering no centre gets
/// one at its centroid's texel if that texel is free, unless no triangle of its chart covers
/// a centre: such charts get no cache and their triangles' UVs are set to kNotLightmapped
/// (shaded from the grid). A point inside or under other
/// geometry (its rays mostly see back faces, or its normal ray hits something within
/// 10·epsilon) moves to another point of the triangle inside the texel, or is dropped.
/// Cache positions are lifted 2·rays.epsilon() along the triangle's geometric normal so
/// visibility rays start in front of the surface. Then every texel a bilinear lookup on a
/// chart can read (centre within `padding` texels of one of its triangles) that is still
/// empty takes the cache of the nearest filled texel of the same chart. Caches are ordered
/// by chart, then by texel row-major; the result does not depend on the thread count.
Result<LightmapCacheSet> placeLightmapCaches(const Scene& scene, const EmbreeScene& rays,
                                             LightmapCharts charts, uint32_t firstCacheIndex,
                                             const LightmapCacheParams& params);

}  // namespace pic
