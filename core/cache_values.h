#pragma once
/// Cache radiance as the runtime produces it (paper 000 §4.8, paper 001): per unique cache,
/// incident radiance as real SH (core/sh.h basis) in YCoCg, Y with lY bands and Co, Cg with
/// lC ≤ lY bands; and the lookups a renderer does with it (paper 000 §3.2).

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "core/bake_data.h"

namespace pic {

/// Incident radiance SH of every unique cache, W/(m²·sr), in YCoCg.
struct CacheValues {
    uint32_t bandsY = 0;    ///< lY
    uint32_t bandsC = 0;    ///< lC
    std::vector<float> y;   ///< nC·lY² luma coefficients, cache-major
    std::vector<float> co;  ///< nC·lC² orange chroma coefficients
    std::vector<float> cg;  ///< nC·lC² green chroma coefficients
    /// nC, or empty where unknown: RGB irradiance along each light-map cache's normal, W/m²,
    /// every colour through the luma's lY bands (0 for grid caches). What a surfel on the
    /// cache's surface receives: through the SH above, chroma keeps only lC bands, and the
    /// colour of light arriving from aside bends towards that of the light from the front.
    /// Cache lighting fills it for the next bounce; it is not stored, compressed or streamed.
    std::vector<glm::vec3> irradiance;

    /// Zero-filled values for `caches` caches.
    static CacheValues zeros(size_t caches, uint32_t bandsY, uint32_t bandsC);
    size_t cacheCount() const { return bandsY ? y.size() / (size_t{bandsY} * bandsY) : 0; }
};

/// Incident radiance at one point as RGB SH with lY bands (chroma bands above lC are zero).
struct RadianceSh {
    uint32_t bands = 0;
    float rgb[3][64] = {};  ///< per channel R, G, B: bands² coefficients
};

/// Up to 8 caches around a point with their final interpolation weights (they sum to 1 when
/// count > 0). A stencil depends on the bake only, so a runtime that looks up the same points
/// at every bounce computes it once (the GPU backend uploads one per surfel).
struct CacheStencil {
    uint32_t cache[8] = {};
    float weight[8] = {};
    int count = 0;
    /// Bit k: cache k is a light-map cache on the reader's own surface, read through its
    /// irradiance along its normal (CacheValues::irradiance; render/surfel_visibility.h
    /// surfelStencils) rather than its SH.
    uint8_t alongNormal = 0;
};

/// The stencil of lookupSurfaceRadiance (same arguments).
CacheStencil surfaceStencil(const BakeData& bake, uint32_t triangle, float b1, float b2,
                            const glm::vec3& position);

/// The stencil of lookupGridRadiance.
CacheStencil gridStencil(const BakeData& bake, const glm::vec3& position);

/// Σ_k weight_k · values of cache_k, converted to RGB SH.
RadianceSh blendCaches(const CacheValues& values, const CacheStencil& stencil);

/// Interpolates the caches around a surface point the way every renderer of pic does:
/// bilinearly from the 4 light-map texels around the triangle's light-map UV when the
/// triangle is light-mapped (triangleUvs != kNotLightmapped), else trilinearly from the 8
/// grid vertices around the position. Texels and vertices without a cache (kNoCache) take
/// no weight and the others are renormalised; no valid neighbour gives zero radiance.
/// `b1`, `b2` are the point's barycentric weights of vertices 1 and 2 of `triangle`.
RadianceSh lookupSurfaceRadiance(const BakeData& bake, const CacheValues& values,
                                 uint32_t triangle, float b1, float b2,
                                 const glm::vec3& position);

/// Trilinear grid lookup only (for points off the light-mapped surfaces).
RadianceSh lookupGridRadiance(const BakeData& bake, const CacheValues& values,
                              const glm::vec3& position);

/// Scales the luma Y of every coefficient by `y` and its chroma Co, Cg by `cocg` (paper 001
/// §4's artistic control, core/light_set.h IndirectScale): YCoCg is linear in RGB, so this is
/// the same as scaling the reconstructed light's Y and CoCg.
void scaleLumaChroma(RadianceSh& radiance, float y, float cocg);

/// Irradiance (W/m², RGB) from interpolated radiance on a surface with unit normal n:
/// E = Σ K_l L_lm y_lm(n) per channel (clamped-cosine convolution, paper 000 §3.2).
glm::vec3 irradiance(const RadianceSh& radiance, const glm::vec3& normal);

}  // namespace pic
