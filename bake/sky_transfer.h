#pragma once
/// The sky transfer of a bake (core/sky.h): per surfel the projection of its cosine-weighted
/// sky visibility, T_k = ∫ V(ω)·max(0, n·ω)·y_k(ω) dω (kSkyBands bands), and per cache the
/// projection of its visibility, v_k = ∫ V(ω)·y_k(ω) dω (skyVisibilityBands(lY) bands). V is 1
/// where a ray from the point escapes the scene. Light-map caches count only the hemisphere
/// above their surface (their own surface blocks the rest); grid caches the whole sphere.
/// Estimated with `rays` stratified directions per point (a Hammersley set turned by a random
/// rotation per point, seeded by the bake's seed, so bakes stay deterministic).

#include <cstdint>
#include <span>
#include <vector>

#include "core/bake_data.h"
#include "rays/embree_scene.h"

namespace pic {

/// T of every surfel, nS·kSkyCoefficients values.
std::vector<float> surfelSkyTransfer(const EmbreeScene& rays, std::span<const Surfel> surfels,
                                     uint32_t rayCount, uint64_t seed);

/// v of caches [begin, end), (end − begin)·skyVisibilityBands(bandsY)² values.
std::vector<float> cacheSkyVisibility(const EmbreeScene& rays, std::span<const Cache> caches,
                                      uint64_t begin, uint64_t end, uint32_t bandsY,
                                      uint32_t rayCount, uint64_t seed);

}  // namespace pic
