#pragma once
/// A uniform grid over surfel positions, hashed, for neighbour queries: surfel relaxation
/// (bake/surfel_placement.cpp) and the surfel a ray hit (bake/surfel_exposure.cpp). Surfels'
/// positions and normals are copied once in cell order; a query finds each cell it needs with
/// one probe of an open-addressing table and reads its surfels from one contiguous run.

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "core/bake_data.h"

namespace pic {

class SurfelGrid {
public:
    /// A surfel as queries see it.
    struct Entry {
        glm::vec3 position;  ///< metres
        uint32_t index;      ///< into the surfels the grid was built over
        glm::vec3 normal;    ///< unit
    };

    /// Buckets every surfel into the cubes of `cellSize` metres (> 0) that its position lies in
    /// or within `halo` metres (≥ 0) of.
    SurfelGrid(const std::vector<Surfel>& surfels, float cellSize, float halo = 0.0f);

    /// Calls fn(entry) for every surfel of the 3×3×3 cells around `p`: with no halo, every
    /// surfel within one cell size of `p`, and some farther; cell by cell, each in ascending
    /// surfel index.
    template <class Fn>
    void forNeighbours(const glm::vec3& p, Fn&& fn) const {
        const glm::ivec3 c = cellOf(p);
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) forCell(c + glm::ivec3(dx, dy, dz), fn);
    }

    /// The surfels of the cell `p` lies in: every surfel within the halo of `p`, and some
    /// farther, in ascending surfel index.
    std::span<const Entry> halo(const glm::vec3& p) const {
        const Slot& slot = mSlots[slotOf(key(cellOf(p)))];
        return {mEntries.data() + slot.begin, mEntries.data() + slot.end};
    }

private:
    glm::ivec3 cellOf(const glm::vec3& p) const { return glm::ivec3(glm::floor(p / mCell)); }
    static uint64_t key(const glm::ivec3& c) {
        return (static_cast<uint64_t>(static_cast<uint32_t>(c.x) & 0x1FFFFF) << 42) |
               (static_cast<uint64_t>(static_cast<uint32_t>(c.y) & 0x1FFFFF) << 21) |
               (static_cast<uint64_t>(static_cast<uint32_t>(c.z) & 0x1FFFFF));
    }
    /// Slot of `k` in the table: where it is, or the empty slot where it would go.
    size_t slotOf(uint64_t k) const;

    template <class Fn>
    void forCell(const glm::ivec3& c, Fn&& fn) const {
        const Slot& slot = mSlots[slotOf(key(c))];
        for (uint32_t i = slot.begin; i < slot.end; ++i) fn(mEntries[i]);
    }

    /// One cell: its key and its surfels, mEntries[begin, end); begin == end when empty.
    struct Slot {
        uint64_t key = ~uint64_t(0);
        uint32_t begin = 0;
        uint32_t end = 0;
    };

    float mCell;
    std::vector<Entry> mEntries;  ///< by cell key, then surfel index
    std::vector<Slot> mSlots;     ///< open addressing, a power of two at most half full
};

}  // namespace pic
