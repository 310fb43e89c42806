#include "render/cpu/pull.h"

#include "core/error.h"
#include "core/parallel.h"

namespace pic {

void pullFlux(const BakeData& bake, std::span<glm::vec3> nodeFlux) {
    PIC_CHECK_EQ(nodeFlux.size(), bake.nodes.size());
    PIC_CHECK(!bake.levelOffsets.empty());
    PIC_CHECK_EQ(size_t{bake.levelOffsets.back()}, bake.nodes.size());
    // Level k ≥ 1 is [levelOffsets[k − 1], levelOffsets[k]); its children lie on lower levels,
    // so one parallel loop per level, in order, is a complete pull (one dispatch per level on
    // the GPU).
    for (size_t level = 1; level < bake.levelOffsets.size(); ++level) {
        parallelFor(
            bake.levelOffsets[level - 1], bake.levelOffsets[level],
            [&](size_t n) {
                const Node& node = bake.nodes[n];
                PIC_DCHECK(node.left < n && node.right < n);
                nodeFlux[n] = nodeFlux[node.left] + nodeFlux[node.right];
            },
            1024);
    }
}

}  // namespace pic
