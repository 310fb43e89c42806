#pragma once
/// Solids: the closed, consistently wound surfaces of a scene. A ray that starts outside a
/// solid meets it first on a face that looks back along the ray (it enters there), so a depth
/// map rendered from a point outside a solid may skip that solid's faces that look away from
/// the point without changing a texel. Open surfaces (a single-sided wall, a curtain, a leaf)
/// have no inside and keep both faces.

#include <cstdint>
#include <vector>

#include "core/scene.h"

namespace pic {

struct Solids {
    static constexpr uint32_t kOpen = UINT32_MAX;

    std::vector<uint32_t> solidOf;  ///< per triangle: the solid it belongs to, or kOpen
    /// Per solid: its triangles wind clockwise seen from outside (negative enclosed volume),
    /// the opposite of glTF's counter-clockwise front faces.
    std::vector<bool> inverted;
    std::vector<Aabb> bounds;  ///< per solid, metres

    uint32_t count() const { return uint32_t(bounds.size()); }
};

/// Finds the solids: connected sets of triangles (connected through shared edges, vertices
/// matched by exact position) in which every edge is shared by exactly two triangles that
/// traverse it in opposite directions. Anything else (a border edge, an edge of three or more
/// triangles, two triangles winding the same way along an edge) leaves the whole set open,
/// which is always safe: open triangles are drawn from both sides. Triangles with two equal
/// corners join no solid.
Solids findSolids(const Scene& scene);

}  // namespace pic
