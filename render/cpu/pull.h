#pragma once
/// Pull, CPU twin (paper 000 Figure 2 step 3, §4.1): surfel flux summed up the hierarchy, and
/// the flux's first moment with it, from which each node's flux gets a linear spread.

#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "core/bake_data.h"

namespace pic {

/// Fills the inner nodes of `nodeFlux` (2nS − 1 entries, W per RGB channel) with the sum of
/// their children, level by level along bake.levelOffsets so that every child is final before
/// its parent reads it. The leaves [0, nS) must already hold the surfel flux; the root (last
/// node) ends up with the total. Each inner node is exactly the float sum of its two children.
void pullFlux(const BakeData& bake, std::span<glm::vec3> nodeFlux);

/// How a node's flux spreads over its surfels. Paper 000 §4.1 spreads it evenly; the bake's
/// flux weights w (bake/surfel_exposure.h) give the prior ω_s = w_s·a_s / Σ_n w·a. On top of
/// it the runtime fits a linear spread to the flux's first moment about the node's flux
/// centroid x̄_n = Σ_n ω·x,
///   Φ_s = ω_s·(Φ_n + g_n·(x_s − x̄_n)),   g_n = C_n⁻¹·M_n,
///   M_n = Σ_n Φ_s·(x_s − x̄_n),            C_n = Σ_n ω·(x − x̄_n)(x − x̄_n)ᵀ,
/// per channel. The fit keeps the node's flux and its moment: Σ_n Φ_s = Φ_n since
/// Σ ω·(x − x̄) = 0, and Σ_n Φ_s·(x_s − x̄_n) = C_n·g_n = M_n. Where the fitted spread would
/// turn negative inside the node's extent, g_n is scaled down until it does not (a slope
/// limiter): every part of the node then reads a flux ≥ 0 and the parts still sum to Φ_n, where
/// clamping negative parts to 0 would make light (one sunlit corner of a floor node made the
/// living room's caches 18 % too bright). A link whose visible part has its centroid at
/// x̄_n + d (LinkSet::offset) reads Φ_n·(1 + r_n·d), r_n = g_n / Φ_n: a far wall lit at one
/// end sends more light to a cache that sees that end.
struct NodeSpread {
    std::vector<glm::vec3> centroid;         ///< x̄_n per node, metres
    std::vector<glm::mat3> axes;             ///< principal axes of C_n (orthonormal columns)
    std::vector<glm::vec3> inverseVariance;  ///< 1 / (eigenvalue + λ_n) per axis, 1/m²; 0 for leaves
    std::vector<glm::vec3> low;              ///< extent of the surfels about x̄_n along the axes:
    std::vector<glm::vec3> high;             ///< low ≤ 0 ≤ high, metres
};

/// The spread of every node of `bake` from its surfels and flux weights (bake.surfelWeights;
/// uniform when empty). λ_n = 10⁻⁶·trace C_n keeps the inverse finite for flat or linear
/// nodes, whose moment has no component across them.
NodeSpread nodeSpread(const BakeData& bake);

/// From pulled `nodeFlux`: the first moments M_n (`moment`, column c = channel c, W·m; the
/// leaves' are 0) summed up the hierarchy like the flux, M_n = Σ_children M_k + Φ_k ⊗ (x̄_k −
/// x̄_n), and every node's limited relative gradient r_n (`gradient`, column c = g_n,c / Φ_n,c,
/// 1/m; 0 where Φ_n,c = 0 and for leaves).
void pullFluxGradients(const BakeData& bake, const NodeSpread& spread,
                       std::span<const glm::vec3> nodeFlux, std::span<glm::mat3> moment,
                       std::span<glm::mat3> gradient);

/// The limited relative gradient of one channel from its flux Φ and moment M (the twin of the
/// GPU pull's): g = axes·(axesᵀ·M ∘ inverseVariance), scaled so that Φ + g·y ≥ 0 over the box
/// [low, high] in the axes' frame, over Φ.
glm::vec3 limitedGradient(const NodeSpread& spread, size_t node, float flux, const glm::vec3& moment);

}  // namespace pic
