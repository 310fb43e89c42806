#pragma once
/// Shading a camera view from the caches on the CPU (paper 000 §3.2, App. B), exactly as the
/// client will: direct light with exact visibility plus the cache term ρ/π·⟨L_SH, D_SH(n)⟩
/// from the light map (bilinear) or the grid (trilinear), and an optional glossy lobe.

#include <cstdint>

#include "core/bake_data.h"
#include "core/cache_values.h"
#include "core/error.h"
#include "core/image.h"
#include "core/light_set.h"
#include "core/scene.h"
#include "core/shade_params.h"
#include "rays/embree_scene.h"

namespace pic {

/// Renders `camera`'s view of `scene` lit by `lights` and shaded from cache radiance `values`
/// of `bake`. Per pixel: a primary ray; at the hit, the geometric normal facing the camera,
/// albedo ρ with its base-colour texture averaged over the ray's footprint on the hit's plane
/// (Scene::albedoOverFootprint: mip-mapped and anisotropic, as the G-buffer pass; the
/// footprint of each of n subsamples is the pixel's with sides scaled by 1/√n); direct = Σ ρ/π·E_light·V (Embree shadow rays), indirect = ρ/π·E_SH(n) (negative
/// SH ringing clamped to 0 per channel) + glossyWeight·glossy lobe, emission (front faces,
/// emissive scale applied) in Full only; misses are black. Deterministic (independent of the
/// thread count), never NaN or negative for valid inputs. InvalidInput for zero sizes or
/// subsamples, bad glossy parameters, or a bake or cache values that do not fit the scene.
Result<Image> shadeFromCaches(const Scene& scene, const EmbreeScene& rays, const BakeData& bake,
                              const CacheValues& values, const LightSet& lights,
                              const Camera& camera, const ShadeParams& params);

}  // namespace pic
