#pragma once
/// Surfel visibility (paper 000 Figure 2 step 2, §3 and §4.1): which surfels each light
/// reaches, by Embree rays, and which caches each surfel's bounce reads. Shared by the GPU
/// backend (render/passes/ray_visibility_pass.h, render/gpu_runtime.h) and the CPU twin
/// (render/cpu/surfel_lighting.h).

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "core/bake_data.h"
#include "core/cache_values.h"
#include "core/light_set.h"
#include "core/scene.h"
#include "rays/embree_scene.h"

namespace pic {

/// E_light·V at `surfel`: the light's irradiance there, or zero where the surfel faces away,
/// lies outside the cone or range (no ray is cast) or the ray to the light is occluded. Rays
/// start just above the surface so that they do not hit the surfel's own triangle.
glm::vec3 visibleIrradiance(const EmbreeScene& rays, const Surfel& surfel, const Light& light);

/// Words of a visibility mask over nS surfels (surfelVisibility): one bit per surfel.
inline size_t visibilityWords(size_t surfels) {
    return (surfels + 31) / 32;
}

/// The V of directSurfelFlux for one light, as bits: bit i % 32 of `bits[i / 32]` is set where
/// the surfel faces the light within its cone and range and the ray to it is unoccluded. The
/// light's colour and intensity do not matter. `bits` must hold visibilityWords(nS) words.
void surfelVisibility(const EmbreeScene& rays, const BakeData& bake, const Light& light,
                      std::span<uint32_t> bits);

/// The caches each surfel's bounce reads: surfaceStencil at the surfel's barycentrics, less
/// the caches it cannot see. A cache is dropped when the segment from the surfel (offset along
/// its normal) to the cache (offset along a light-map cache's normal) is occluded, and the
/// others are renormalised; a surfel that sees none of them keeps them all. Bilinear light-map
/// texels and trilinear grid vertices otherwise reach through a thin wall: a floor that runs
/// under a partition interpolates the texels on its far side, and surfels there re-emit the
/// other room's light at every bounce. One ray per stencil entry, computed once per bake.
/// Light-map caches whose normal is within 25° of the surfel's are marked
/// (CacheStencil::alongNormal): the bounce reads their irradiance along their normal.
std::vector<CacheStencil> surfelStencils(const Scene& scene, const EmbreeScene& rays,
                                         const BakeData& bake);

}  // namespace pic
