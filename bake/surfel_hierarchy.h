#pragma once
/// The surfel hierarchy (paper 000 §4.3): a binary tree over the leaf surfels whose
/// nodes are the sender patches that caches link to and that the pull pass sums up.

#include <cstdint>
#include <vector>

#include "core/bake_data.h"
#include "core/error.h"
#include "rays/embree_scene.h"

namespace pic {

/// How buildHierarchy clusters surfels; distances are normalised by the scene extent.
struct HierarchyParams {
    HierarchyMethod method = HierarchyMethod::Agglomerative;
    float normalWeight = 0.1f;    ///< C_n, weight of 1 − ⟨m_a, m_b⟩ in the metric
    float balanceWeight = 0.02f;  ///< C_b, weight of |A_a − A_b| / max(A_a, A_b) in the metric
    float sceneExtent = 1.0f;     ///< ‖x_max − x_min‖ of the scene in metres, > 0
    /// The scene's rays, which HierarchyMethod::Visible needs: clusters that cannot see each
    /// other (the two faces of a wall, a room's floor and the next room's, a cabinet's back and
    /// the wall behind it) merge only when no cluster they see is in reach, so that a node does
    /// not spread the light of one side of a wall over the other (paper 000 §5.2 (c)).
    const EmbreeScene* rays = nullptr;
};

/// Surfels in leaf order and the 2·nS − 1 nodes over them, laid out as documented in
/// shaders/shared/bake_layout.h: leaves first, inner nodes by ascending level, root last.
struct SurfelHierarchy {
    std::vector<Surfel> surfels;         ///< the input surfels in depth-first leaf order
    std::vector<Node> nodes;             ///< node i < nS is the leaf of surfel i
    std::vector<uint32_t> levelOffsets;  ///< [0] = nS, level k > 0 is [offsets[k−1], offsets[k])
};

/// Builds the hierarchy over `surfels` with `params.method`; deterministic for a given
/// input whatever the thread count. Fails on empty input or invalid surfels or params.
Result<SurfelHierarchy> buildHierarchy(std::vector<Surfel> surfels, const HierarchyParams& params);

}  // namespace pic
