#pragma once
/// Grid cache placement (paper 000 §4.4, paper 001 §5): caches at the vertices of grid
/// cells that contain or touch geometry, dilated by one cell, never inside solid geometry —
/// the volume dynamic objects near surfaces are shaded from —, at every vertex in open space
/// (dynamic objects anywhere), or only at the vertices that grid-shaded surfaces read, where
/// nothing dynamic is shaded.

#include <cstdint>
#include <span>
#include <vector>

#include "core/bake_data.h"
#include "core/error.h"
#include "core/scene.h"
#include "rays/embree_scene.h"

namespace pic {

struct GridCacheParams {
    float cellSize = 0.0f;        ///< metres
    GridCaches mode = GridCaches::Volume;
    /// GridCaches::Surfaces: per scene triangle, 1 where it is shaded from the grid (not
    /// light-mapped). Only the caches its cells' corners read are kept.
    std::vector<uint8_t> gridShaded;
    uint32_t insideRays = 16;     ///< rays per vertex for the inside-solid test
    uint64_t maxVertices = 64ull << 20;  ///< refuse grids larger than this
};

/// The grid layout and its unique caches.
struct GridCacheSet {
    GridLayout layout;
    std::vector<Cache> caches;     ///< unique grid caches, kind = grid
    uint32_t insideSolid = 0;      ///< needed vertices found inside geometry
    uint32_t duplicates = 0;       ///< inside vertices that copy a neighbour's cache
    uint32_t unread = 0;           ///< GridCaches::Surfaces: volume caches no surface reads,
                                   ///< not kept
};

/// Unit directions spread evenly over the sphere (Fibonacci lattice).
std::vector<glm::vec3> sphereDirections(uint32_t n);

/// Whether point `p` is inside closed geometry (or behind single-sided walls): more than a
/// quarter of the rays along `directions` meet back faces of single-sided materials first, or
/// none meets a front face (e.g. outside a closed room: nothing to see from there).
bool insideSolid(const Scene& scene, const EmbreeScene& rays, const glm::vec3& p,
                 std::span<const glm::vec3> directions);

/// Places grid caches; their indices start at `firstCacheIndex`.
Result<GridCacheSet> placeGridCaches(const Scene& scene, const EmbreeScene& rays,
                                     uint32_t firstCacheIndex, const GridCacheParams& params);

}  // namespace pic
