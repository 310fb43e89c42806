#include "bake/surfel_grid.h"

#include <algorithm>
#include <utility>

#include <tbb/parallel_sort.h>

#include "core/sampling.h"

namespace pic {

SurfelGrid::SurfelGrid(const std::vector<Surfel>& surfels, float cellSize, float halo) : mCell(cellSize) {
    std::vector<std::pair<uint64_t, uint32_t>> keyed;
    keyed.reserve(surfels.size());
    for (uint32_t i = 0; i < surfels.size(); ++i) {
        const glm::ivec3 lo = cellOf(surfels[i].position - halo), hi = cellOf(surfels[i].position + halo);
        for (int z = lo.z; z <= hi.z; ++z)
            for (int y = lo.y; y <= hi.y; ++y)
                for (int x = lo.x; x <= hi.x; ++x) keyed.emplace_back(key({x, y, z}), i);
    }
    tbb::parallel_sort(keyed.begin(), keyed.end());
    size_t cells = 0;
    for (size_t i = 0; i < keyed.size(); ++i) cells += i == 0 || keyed[i].first != keyed[i - 1].first;
    size_t capacity = 16;
    while (capacity < 2 * cells) capacity *= 2;
    mSlots.assign(capacity, Slot{});
    mEntries.resize(keyed.size());
    for (size_t i = 0; i < keyed.size(); ++i) {
        const Surfel& s = surfels[keyed[i].second];
        mEntries[i] = Entry{s.position, keyed[i].second, s.normal};
        Slot& slot = mSlots[slotOf(keyed[i].first)];
        if (slot.begin == slot.end) {
            slot.key = keyed[i].first;
            slot.begin = static_cast<uint32_t>(i);
        }
        slot.end = static_cast<uint32_t>(i + 1);
    }
}

size_t SurfelGrid::slotOf(uint64_t k) const {
    const size_t mask = mSlots.size() - 1;
    for (size_t s = mixBits(k) & mask;; s = (s + 1) & mask)
        if (mSlots[s].key == k || mSlots[s].begin == mSlots[s].end) return s;
}

}  // namespace pic
