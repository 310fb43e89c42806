#pragma once
/// The sky light (core/light_set.h SkyLight) as the runtime and picref use it: its environment
/// image, its radiance per direction, and the SH it relights with.
///
/// Precomputed sky transfer (the PRT idea; bake/sky_transfer.h) keeps the runtime to
/// multiplications. The sky's radiance is projected to kSkyBands bands, s_j (RGB). A surfel
/// stores the projection of its cosine-weighted visibility, T_k = ∫ V(ω) max(0, n·ω) y_k(ω) dω,
/// so that its sky irradiance is E = Σ_k s_k T_k. A cache stores the projection of its
/// visibility, v_k = ∫ V(ω) y_k(ω) dω, in skyVisibilityBands(lY) bands; the sky it sees has
/// the coefficients c_i = ∫ V L y_i = Σ_j s_j Σ_k v_k G_ijk with the Gaunt coefficients
/// G_ijk = ∫ y_i y_j y_k, exact for the projected sky because y_i·y_j holds no band above
/// lY + kSkyBands − 2. Per update the runtime folds the sky into skyCacheWeights, so a cache
/// costs one small matrix-vector product.
///
/// Environment images are equirectangular with +Y up: texel coordinate (u, v) ∈ [0, 1]², v = 0
/// at the top row, looks along skyDirection(u, v): θ = π·v from +Y and azimuth φ = 2π·u, u = 0
/// along −Z and u = 0.25 along +X (the image's centre column, u = 0.5, looks along +Z). A sky
/// rotation of r degrees turns the image counter-clockwise about +Y seen from above (−Z
/// towards −X, as rotating the world's view the other way).

#include <array>
#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "core/bake_data.h"
#include "core/error.h"
#include "core/image.h"
#include "core/light_set.h"
#include "core/scene.h"

namespace pic {

/// SH bands of the sky's radiance at runtime.
inline constexpr int kSkyBands = 3;
/// Its coefficients per colour channel.
inline constexpr int kSkyCoefficients = kSkyBands * kSkyBands;
/// Largest environment image side, texels.
inline constexpr uint32_t kMaxEnvironmentSide = 16384;

/// Bands of a cache's sky visibility for caches of `bandsY` bands: bandsY + kSkyBands − 1 (the
/// exact product), at most 8 (core/sh.h; from lY = 7 on the product loses its top bands).
constexpr int skyVisibilityBands(int bandsY) {
    return bandsY + kSkyBands - 1 < 8 ? bandsY + kSkyBands - 1 : 8;
}

/// Sky visibility values a bake stores per cache (BakeData::cacheSky): skyVisibilityBands(lY)²
/// with sky transfer, 0 without.
size_t skyValuesPerCache(const BakeParams& params);

/// The direction texel coordinate (u, v) of an environment image looks along (unit).
glm::vec3 skyDirection(float u, float v);
/// The texel coordinate of a unit direction, u in [0, 1), v in [0, 1].
glm::vec2 skyUv(const glm::vec3& direction);

/// Reads environment `name` (SkyLight::environment) from the folder of scene file
/// `scenePath` and checks it: NotFound when missing, InvalidInput for a side above
/// kMaxEnvironmentSide or any negative or non-finite texel (naming it). Images are kept by
/// resolved path and modification time, so sessions that share a sky share its texels.
Result<std::shared_ptr<const Image>> loadEnvironment(const std::string& scenePath,
                                                     const std::string& name);

/// A sky ready to evaluate.
class Sky {
public:
    /// A constant sky of `radiance` W/(m²·sr) times `environment` (may be null) turned by
    /// `rotationDegrees` about +Y.
    Sky(glm::vec3 radiance, std::shared_ptr<const Image> environment, float rotationDegrees);

    /// The radiance from world direction `direction` (unit): the environment's texel there,
    /// nearest (piecewise constant, the density picref samples).
    glm::vec3 radiance(const glm::vec3& direction) const;
    /// The radiance of the whole texel (x, y) (the constant radiance without an image).
    glm::vec3 texelRadiance(uint32_t x, uint32_t y) const;
    /// The world direction of environment texel coordinate (u, v) after the rotation.
    glm::vec3 direction(float u, float v) const;
    /// The texel coordinate world direction `direction` reads.
    glm::vec2 uv(const glm::vec3& direction) const;

    const Image* environment() const { return mEnvironment.get(); }
    glm::vec3 scale() const { return mRadiance; }

    /// RGB SH of the radiance to kSkyBands bands, ∫ L(ω) y_k(ω) dω integrated texel by
    /// texel (exact solid angles; a constant sky gives s_0 = 2√π·L).
    std::array<glm::vec3, kSkyCoefficients> project() const;

private:
    glm::vec3 mRadiance;
    std::shared_ptr<const Image> mEnvironment;
    float mCos = 1.0f, mSin = 0.0f;  ///< of the rotation
};

/// The sky of a light set, its environment read next to scene file `scenePath`.
Result<Sky> resolveSky(const SkyLight& sky, const std::string& scenePath);

/// The Gaunt coefficients G_ijk = ∫ y_i y_j y_k dω for i < shCount(bandsI), j < kSkyCoefficients,
/// k < shCount(bandsK), at (i·kSkyCoefficients + j)·shCount(bandsK) + k; computed by a
/// quadrature exact for these products (bandsI, bandsK ≤ 8).
std::vector<float> gauntCoefficients(int bandsI, int bandsK);

/// The sky folded for caches of lY = `bandsY`, lC = `bandsC` bands: c_i = Σ_k W_ik v_k with v a
/// cache's sky visibility (skyVisibilityBands(lY) bands), W_ik = Σ_j s_j G_ijk, per YCoCg
/// channel of `skySh` (Sky::project converted to YCoCg).
struct SkyCacheWeights {
    int bandsY = 0, bandsC = 0, visibilityBands = 0;
    std::vector<float> y;   ///< lY²·nV², row i at i·nV²
    std::vector<float> co;  ///< lC²·nV²
    std::vector<float> cg;  ///< lC²·nV²
};
SkyCacheWeights skyCacheWeights(const std::array<glm::vec3, kSkyCoefficients>& skySh, int bandsY,
                                int bandsC);

}  // namespace pic
