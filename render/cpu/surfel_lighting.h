#pragma once
/// Surfel lighting, CPU twin (paper 000 Figure 2 step 2, §3 and §4.1): the outgoing flux of
/// every leaf surfel, Φ = ρ·A·(E_direct + E_indirect) + π·L_e·A·emissiveScale, in W per RGB
/// channel, written in leaf order (index i = surfel i = hierarchy node i).
///
/// The pass is split in two so that bounces do not recast shadow rays: the direct part depends
/// on the light set only, the bounce part adds ρ·A·E_indirect read from the previous bounce's
/// caches. The rays it shares with the GPU backend (visibleIrradiance, surfelVisibility,
/// surfelStencils) are render/surfel_visibility.h.

#include <array>
#include <span>

#include <glm/glm.hpp>

#include "core/bake_data.h"
#include "core/cache_values.h"
#include "core/light_set.h"
#include "core/scene.h"
#include "core/sky.h"
#include "rays/embree_scene.h"

namespace pic {

/// Direct flux of every surfel: ρ·A·(Σ_lights E_light·V + E_sky) + π·L_e·A·emissiveScale(material),
/// with V the Embree visibility from the surfel (offset by rays.epsilon() along its normal) to
/// the light and E_sky = max(0, Σ_k s_k T_k) per channel, s the sky's radiance SH (`skySh`,
/// null: no sky) and T the surfel's sky transfer (BakeData::surfelSky). `directFlux` must hold
/// nS entries.
void directSurfelFlux(const Scene& scene, const EmbreeScene& rays, const BakeData& bake,
                      const LightSet& lights, std::span<glm::vec3> directFlux,
                      const std::array<glm::vec3, kSkyCoefficients>* skySh = nullptr);

/// Flux of every surfel for one more bounce: directFlux + ρ·A·E_indirect, E_indirect the
/// irradiance that the caches of `previousBounce` deliver at the surfel through its stencil
/// (surfelStencils): the marked light-map caches' irradiance along their normal
/// (CacheValues::irradiance, when `previousBounce` has it), the others' SH convolved with the
/// clamped cosine about the surfel's normal, per channel cut at zero where SH ringing makes it
/// negative. Through the SH alone the chroma's lC = 2 bands bent the colour of light that
/// arrives from another direction than most of the light (opposite_colors: the far lamp's
/// colour 5–10 % too strong on the walls two bounces on). `surfelFlux` holds the previous bounce's
/// flux S on entry; with a `tail` (BounceSchedule: the light of the bounces not computed) each
/// surfel's new flux S' becomes S' + tail·max(S' − S, 0), per channel. `stencils`, `directFlux` and
/// `surfelFlux` hold nS entries; the last two may not alias.
void bounceSurfelFlux(const BakeData& bake, std::span<const CacheStencil> stencils,
                      std::span<const glm::vec3> directFlux, const CacheValues& previousBounce,
                      std::span<glm::vec3> surfelFlux, glm::vec3 tail = glm::vec3(0.0f));

/// Both parts at once: direct flux, plus the bounce from `previousBounce` when it is not null
/// (null for the first pass). `surfelFlux` must hold nS entries.
void lightSurfels(const Scene& scene, const EmbreeScene& rays, const BakeData& bake,
                  const LightSet& lights, const CacheValues* previousBounce,
                  std::span<glm::vec3> surfelFlux);

}  // namespace pic
