#pragma once
/// Node spreads (paper 000 §4.1): how the flux of each hierarchy node spreads over its surfels,
/// the flux's first moment summed up the hierarchy from which each node's spread follows, and
/// the box points at which links read a node's spread. Shared by the GPU passes
/// (render/passes/pull_pass.h, cache_lighting_pass.h) and the CPU twin (render/cpu/pull.h,
/// cache_lighting.h), so that both backends spread and read the same light.

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "core/bake_data.h"
#include "shaders/shared/pull.h"

namespace pic {

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
/// x̄_n + d (LinkSet::offset) reads Φ_n + g_n·d: a far wall lit at one end sends more light to
/// a cache that sees that end. The visible part's centroid lies among the node's surfels, so
/// within the box [low, high], and links carry it in box coordinates (encodeBoxPoint).
///
/// Where the limiter keeps less than half the fitted gradient (gpu::kExponentialLimit), light
/// is concentrated in a part of the node (a sun patch, the corner next to a lamp) and a line
/// cannot follow it: a flat node's spread is exponential instead (exponentialSpread),
/// Φ_s = ω_s·Φ_n·e^{β·(x_s − x̄_n)} / Z(β), ≥ 0 everywhere and as peaked as the moment asks. Z is that of a model of the node: along each principal axis
/// k its surfels spread evenly over ±a_k, a_k = √3·σ_k (the same variance), so that
/// Z = Π_k sinh(β_k·a_k) / (β_k·a_k) and the moment fixes each β_k by the inverse Langevin
/// function, a_k·L(β_k·a_k) = M_k / Φ_n. A link reads the model's mean over the part it sees,
/// Φ_n·E_part[e^{β·y}] / E_node[e^{β·y}]: to second order in β (cumulants) that is
/// Φ_n·e^{β·ȳ + ½βᵀ(Σ_part − Σ_node)β}, ȳ and Σ_part the centroid and covariance of the part
/// (weights w·Ω·V, as the link's offset), and with ½βᵀΣ_node β ≈ ln Z and βᵀΣ_part β ≈
/// ρ·βᵀΣ_node β, ρ = tr Σ_part / tr Σ_node the link's spread share (LinkSet::spreadShare),
///   Φ_link = Φ_n·e^{β·ȳ − (1 − ρ)·ln Z}:
/// Φ_n for a link that sees the whole node evenly, the spread's value at ȳ for one that sees a
/// point. The exponent is capped, Σ_k |β_k|·halfExtent_k ≤ gpu::kExponentialSpreadCap, where
/// the box model stops holding. A node that is not flat (a corner, a piece of furniture) keeps
/// its limited line: its surfels fill no box, and exponential reads of the OpenArena level's
/// such nodes fell 6 % short of the path tracer's light.
struct NodeSpread {
    std::vector<glm::vec3> centroid;  ///< x̄_n per node, metres
    std::vector<glm::mat3> axes;      ///< principal axes of C_n (orthonormal columns)
    std::vector<glm::vec3>
        inverseVariance;          ///< 1 / (eigenvalue + λ_n) per axis, 1/m²; 0 for leaves
    std::vector<glm::vec3> low;   ///< extent of the surfels about x̄_n along the axes:
    std::vector<glm::vec3> high;  ///< low ≤ 0 ≤ high, metres
};

/// The spread of every node of `bake` from its surfels and flux weights (bake.surfelWeights;
/// uniform when empty). λ_n = 10⁻⁶·trace C_n keeps the inverse finite for flat or linear
/// nodes, whose moment has no component across them.
NodeSpread nodeSpread(const BakeData& bake);

/// A node's flux as its links read it, per channel: the limited linear spread's flux at the
/// centre of the node's box, and its relative slopes along the box's axes per half extent. A
/// point of the box at box coordinates u ∈ [−1, 1]³ (encodeBoxPoint) reads
/// centre·(1 + slopes·u). The limiter keeps the spread ≥ 0 over the box, which is exactly
/// Σ_k |slopes_k| ≤ 1 (the least corner reads centre·(1 − Σ_k |slopes_k|)).
struct ChannelSpread {
    float centre = 0.0f;     ///< W: Φ_n + g_n·c_n, c_n the box centre about x̄_n
    glm::vec3 slopes{0.0f};  ///< (g_n·axis_k)·halfExtent_k / centre
    bool limited = false;    ///< the limiter scaled g_n down
    bool concentrated = false;  ///< by more than gpu::kExponentialLimit: the line cannot hold it
};

/// An exponential spread of one channel (NodeSpread): a point of the box at box coordinates u
/// reads centre·e^{slopes·u − (1 − ρ)·concentration} for a part of spread share ρ.
struct ExponentialSpread {
    float centre = 0.0f;           ///< W: Φ_n·e^{β·c_n}, c_n the box centre about x̄_n
    glm::vec3 slopes{0.0f};        ///< β_k·halfExtent_k
    float concentration = 0.0f;    ///< ln Z(β) ≥ 0
};

/// The exponential spread of one channel of `node` from its flux Φ and moment M (the twin of
/// the GPU pull's): 0 where Φ ≤ 0; axes along which the node is flat (variance below 10⁻³ of
/// the total) take no slope.
ExponentialSpread exponentialSpread(const NodeSpread& spread, size_t node, float flux,
                                    const glm::vec3& moment);

/// Whether `node` is flat: its least variance is at most gpu::kFlatVariance of their sum (a
/// patch of one surface; a leaf, whose variances are all 0, too).
bool isFlat(const NodeSpread& spread, size_t node);

/// Whether the flux centroid of every channel of `node` (moment column c over flux c) lies
/// within gpu::kExponentialReach·√3·σ_k of the surfels' centroid along each axis the node is
/// not flat on: the box model its exponential spread is normalised over.
bool fitsBoxModel(const NodeSpread& spread, size_t node, const glm::vec3& flux,
                  const glm::mat3& moment);

/// x with L(x) = coth x − 1/x = r for |r| < 1 (the inverse Langevin function), by Jedynak's
/// rational approximation (within 1.5 %); r is clamped to ±0.99.
float inverseLangevin(float r);

/// The limited spread of one channel of `node` from its flux Φ and moment M (the twin of the
/// GPU pull's): g = axes·(axesᵀ·M ∘ inverseVariance), scaled so that Φ + g·y ≥ 0 over the
/// box [low, high] in the axes' frame, then evaluated about the box centre.
ChannelSpread limitedSpread(const NodeSpread& spread, size_t node, float flux,
                            const glm::vec3& moment);

/// From pulled `nodeFlux`: the first moments M_n (`moment`, column c = channel c, W·m; the
/// leaves' are 0) summed up the hierarchy like the flux, M_n = Σ_children M_k + Φ_k ⊗ (x̄_k −
/// x̄_n), and every node's spread: `centreFlux` (W per channel; a leaf's own flux) and
/// `slopes` (column c = channel c's slopes; 0 for leaves). A flat node (isFlat) whose flux is
/// concentrated (ChannelSpread::concentrated) in any channel and fits its box model
/// (fitsBoxModel) is exponential in all three (`exponential` 1, its ln Z per channel in
/// `concentration`); the others are linear (`exponential` 0, `concentration` 0).
void pullFluxSpread(const BakeData& bake, const NodeSpread& spread,
                    std::span<const glm::vec3> nodeFlux, std::span<glm::mat3> moment,
                    std::span<glm::vec3> centreFlux, std::span<glm::mat3> slopes,
                    std::span<glm::vec3> concentration, std::span<uint8_t> exponential);

/// Box coordinates of a point at `offset` from the flux centroid of `node` (a link's
/// LinkSet::offset): u_k = (axis_k·offset − centre_k) / halfExtent_k, clamped to [−1, 1], 0
/// along an axis the box is flat on; as three snorm8 in bits 0-23, the form the GPU's links
/// carry (shaders/shared/cache_lighting.h), so that both backends read the same points. One
/// step is 1/127 of a half extent, so a link reads its node's spread within 1/127 of its flux.
uint32_t encodeBoxPoint(const NodeSpread& spread, size_t node, const glm::vec3& offset);

/// The box coordinates of a code from encodeBoxPoint, each in [−1, 1] (GLSL unpackSnorm4x8).
glm::vec3 decodeBoxPoint(uint32_t code);

}  // namespace pic
