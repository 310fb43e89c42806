#pragma once
/// Flux weights: how a node's flux is expected to spread over its surfels, so that a link can
/// read the radiance of the part a cache sees rather than the node's mean (issue 23).
///
/// A node is linked as one sender, but its flux is not uniform: surfels hidden under
/// furniture, behind an emitter panel or in a narrow gap receive almost no light, so the
/// exposed surfels that caches see radiate more than Φ_node / (π·A_node). The weights predict
/// the flux of each surfel without knowing the lights:
///  - a reflecting surfel's expected irradiance from a point light placed uniformly at random
///    in the free space within distance R of it is ∝ ∫ cosθ·min(t(ω), R) dω, with t(ω) the
///    free distance along ω (the light's 1/r² cancels the r² of the volume element), so its
///    expected flux is ∝ a·E_cos[min(t, R)]. R is the scene's mean chord, 4·V/S (Cauchy),
///    the distance light typically travels between two surfaces of it: surfels that see that
///    far in every direction weigh the same, those in gaps and under objects less;
///  - an emitting surfel's flux is π·L_e·a, fixed up to the light set's scale of its
///    material, which the hierarchy keeps apart from other materials (surfel_hierarchy.h).
/// Each kind is normalised to an area-weighted mean of 1, so nodes that mix them (near the
/// root) stay close to the uniform model.

#include <cstdint>
#include <vector>

#include "core/bake_data.h"
#include "core/error.h"
#include "core/scene.h"
#include "rays/embree_scene.h"

namespace pic {

struct ExposureParams {
    uint32_t rays = 64;  ///< cosine-distributed rays per surfel, stratified
    uint64_t seed = 1;
};

/// The reach R of the exposure rays: the mean chord 4·V/S of the scene's bounds (V) over its
/// surface area (S), m; the bounds' largest extent when the scene has no area.
float exposureReach(const Scene& scene);

/// E_cos[min(t, reach)], the cosine-weighted mean free distance (m) above each surfel, rays
/// that leave the scene bounds counting up to the bounds. 0 where every ray is blocked at once.
Result<std::vector<float>> surfelFreeDistance(const EmbreeScene& rays, const Aabb& bounds,
                                              float reach, const std::vector<Surfel>& surfels,
                                              const ExposureParams& params);

/// Whether a surfel emits: it belongs to its own hierarchy class and takes its emission as
/// weight.
inline bool isEmitter(const Surfel& s) { return s.emission.r > 0.0f || s.emission.g > 0.0f || s.emission.b > 0.0f; }

/// Least flux weight, against an area-weighted mean of 1.
inline constexpr float kMinFluxWeight = 1e-3f;

/// The flux weight w of every surfel (see above; reflectors take E_cos[min(t, R)] alone: their
/// albedo spreads the flux per channel, fluxColour below); Σ w·a over a node is the area its
/// flux is read over. Every weight is finite and ≥ kMinFluxWeight; a kind whose weights are all 0
/// gets 1.
std::vector<float> fluxWeights(const std::vector<Surfel>& surfels,
                               const std::vector<float>& freeDistance);

/// The colour κ in which a surfel's share of its node's flux is expected to come, per channel:
/// a reflector's flux is ρ·E·a with E ∝ w, so κ = ρ, its albedo; an emitter's is π·L_e·a with
/// w ∝ π·luminance(L_e), so κ = L_e / luminance(L_e). A node's flux spreads over its surfels as
/// w·κ·a per channel, and a link's tint is the colour of what its cache sees over the colour
/// of the node it reads (bake/link_generation.h).
glm::vec3 fluxColour(const Surfel& surfel);

/// Σ w·a per node (leaves first, children before parents), m².
std::vector<double> weightedNodeArea(const std::vector<Surfel>& surfels,
                                     const std::vector<Node>& nodes,
                                     const std::vector<float>& weights);

}  // namespace pic
