#pragma once
/// Pull, CPU twin (paper 000 Figure 2 step 3, §4.1): surfel flux summed up the hierarchy. The
/// flux's first moment, summed up with it, and each node's spread are render/node_spread.h
/// (pullFluxSpread), which the GPU passes share.

#include <span>

#include <glm/glm.hpp>

#include "core/bake_data.h"

namespace pic {

/// Fills the inner nodes of `nodeFlux` (2nS − 1 entries, W per RGB channel) with the sum of
/// their children, level by level along bake.levelOffsets so that every child is final before
/// its parent reads it. The leaves [0, nS) must already hold the surfel flux; the root (last
/// node) ends up with the total. Each inner node is exactly the float sum of its two children.
void pullFlux(const BakeData& bake, std::span<glm::vec3> nodeFlux);

}  // namespace pic
