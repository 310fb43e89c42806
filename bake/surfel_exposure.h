#pragma once
/// Flux weights: how a node's flux is expected to spread over its surfels, so that a link can
/// read the radiance of the part a cache sees rather than the node's mean (issue 23).
///
/// A node is linked as one sender, but its flux is not uniform: surfels hidden under
/// furniture, behind an emitter panel or in a narrow gap receive almost no light, so the
/// exposed surfels that caches see radiate more than Φ_node / (π·A_node). The weights predict
/// the flux of each surfel without knowing the lights:
///  - direct light: a reflecting surfel's expected irradiance from a point light of power P
///    placed with density n in the free space within distance R of it is
///    E₀ = P·n/(4π) ∫ cosθ·min(t(ω), R) dω = c·E_cos[min(t, R)], c = P·n/4, t(ω) the free
///    distance along ω (the light's 1/r² cancels the r² of the volume element). R is the
///    scene's mean chord, 4·V/S (Cauchy), the distance light typically travels between two
///    surfaces of it: surfels that see that far in every direction weigh the same, those in
///    gaps and under objects less;
///  - its bounces: the surface a ray from the surfel hits radiates ρ·E/π, so bounce b + 1
///    gives E_{b+1}(s) = π·E_cos[ρ_h·E_b(h)/π] = E_cos[ρ_h·E_b(h)], h the surfel each ray hits
///    (the runtime's flux is direct light plus every bounce, render/cpu/surfel_lighting.h). The
///    same c carries through every bounce, so a reflector's weight is
///    E / c = Σ_b E_b / c, the expected total irradiance: a corner, which sees lit walls
///    all round, gains against an open wall; the floor under a sofa, which sees the sofa's
///    dark underside, stays low;
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

/// What a surfel's exposure rays see: a ray's end in `SurfelExposure::seen`.
inline constexpr uint32_t kRayEscaped = 0xFFFFFFFFu;     ///< left the scene's bounds: no bounce
inline constexpr uint32_t kRayUnresolved = 0xFFFFFFFEu;  ///< hit a surface with no surfel near
                                                          ///< the hit facing the ray

/// What the exposure rays of every surfel found.
struct SurfelExposure {
    uint32_t raysPerSurfel = 0;
    std::vector<float> freeDistance;  ///< E_cos[min(t, reach)] per surfel, m: rays that leave
                                      ///< the scene bounds count up to the bounds; 0 where every
                                      ///< ray is blocked at once
    std::vector<uint32_t> seen;       ///< raysPerSurfel per surfel: the surfel nearest each ray's
                                      ///< hit that faces the ray, kRayEscaped or kRayUnresolved
};

/// Casts `params.rays` cosine-distributed rays from every surfel.
Result<SurfelExposure> surfelExposure(const EmbreeScene& rays, const Aabb& bounds, float reach,
                                      const std::vector<Surfel>& surfels,
                                      const ExposureParams& params);

/// E / c of every surfel (see above): its free distance plus the bounces Σ_b≥1 E_b / c, each
/// the mean over its rays of ρ_h·E_{b−1}(h)/c, ρ_h the albedo luminance of the surfel h the ray
/// saw (0 for an escaped ray; an unresolved ray is left out of the mean). Bounces are added
/// until one adds less than 1e-4 of the sum, then their geometric tail. m, finite, ≥ 0.
std::vector<float> bouncedExposure(const std::vector<Surfel>& surfels,
                                   const SurfelExposure& exposure);

/// Whether a surfel emits: it belongs to its own hierarchy class and takes its emission as
/// weight.
inline bool isEmitter(const Surfel& s) { return s.emission.r > 0.0f || s.emission.g > 0.0f || s.emission.b > 0.0f; }

/// Least flux weight, against an area-weighted mean of 1.
inline constexpr float kMinFluxWeight = 1e-3f;

/// The flux weight w of every surfel (see above; reflectors take their `exposure`, E / c from
/// bouncedExposure, alone: their albedo spreads the flux per channel, fluxColour below); Σ w·a
/// over a node is the area its flux is read over. Every weight is finite and ≥ kMinFluxWeight;
/// a kind whose weights are all 0 gets 1.
std::vector<float> fluxWeights(const std::vector<Surfel>& surfels,
                               const std::vector<float>& exposure);

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
