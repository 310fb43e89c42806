#include "render/sh_tables.h"

#include "core/sh.h"

namespace pic::gpu {

ShTables makeShTables() {
    const ShRecurrence recurrence = shRecurrence();
    ShTables tables{};
    // Element k of each array is component k % 4 of vec4 k / 4.
    const auto at = [](glm::vec4* array, int k) -> float& { return array[k / 4][k % 4]; };
    for (int l = 0; l < kMaxShBands; ++l) {
        at(tables.diagonal, l) = recurrence.diagonal[l];
        at(tables.clampedCosine, l) = clampedCosineZonal(l);
        for (int m = 0; m < kMaxShBands; ++m) {
            at(tables.a, l * kMaxShBands + m) = recurrence.a[l][m];
            at(tables.b, l * kMaxShBands + m) = recurrence.b[l][m];
        }
    }
    return tables;
}

}  // namespace pic::gpu
