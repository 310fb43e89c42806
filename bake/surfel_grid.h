#pragma once
/// A uniform hash grid over surfel positions, for neighbour queries: surfel relaxation
/// (bake/surfel_placement.cpp) and the surfel a ray hit (bake/surfel_exposure.cpp).

#include <cstdint>
#include <unordered_map>
#include <vector>

#include <glm/glm.hpp>

#include "core/bake_data.h"

namespace pic {

class SurfelGrid {
public:
    /// Buckets every surfel by its position; `cellSize` (metres, > 0) bounds the reach of a
    /// query.
    SurfelGrid(const std::vector<Surfel>& surfels, float cellSize) : mCell(cellSize) {
        mCells.reserve(surfels.size());
        for (uint32_t i = 0; i < surfels.size(); ++i) mCells[key(cellOf(surfels[i].position))].push_back(i);
    }

    /// Calls fn(j) for every surfel j in the 3×3×3 cells around `p`: every surfel within one
    /// cell size of `p`, and some farther.
    template <class Fn>
    void forNeighbours(const glm::vec3& p, Fn&& fn) const {
        const glm::ivec3 c = cellOf(p);
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    auto it = mCells.find(key(c + glm::ivec3(dx, dy, dz)));
                    if (it == mCells.end()) continue;
                    for (uint32_t j : it->second) fn(j);
                }
    }

private:
    glm::ivec3 cellOf(const glm::vec3& p) const { return glm::ivec3(glm::floor(p / mCell)); }
    static uint64_t key(const glm::ivec3& c) {
        return (static_cast<uint64_t>(static_cast<uint32_t>(c.x) & 0x1FFFFF) << 42) |
               (static_cast<uint64_t>(static_cast<uint32_t>(c.y) & 0x1FFFFF) << 21) |
               (static_cast<uint64_t>(static_cast<uint32_t>(c.z) & 0x1FFFFF));
    }

    float mCell;
    std::unordered_map<uint64_t, std::vector<uint32_t>> mCells;
};

}  // namespace pic
