#include "bake/sky_transfer.h"

#include <cmath>

#include <glm/gtc/constants.hpp>

#include "core/parallel.h"
#include "core/sampling.h"
#include "core/sh.h"
#include "core/sky.h"

namespace pic {
namespace {

/// An orthonormal frame with `normal` as its z axis.
glm::mat3 frameAround(const glm::vec3& normal) {
    const glm::vec3 helper = std::abs(normal.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
    const glm::vec3 tangent = glm::normalize(glm::cross(helper, normal));
    return glm::mat3(tangent, glm::cross(normal, tangent), normal);
}

/// Point i of n of a 2D Hammersley set shifted by (s1, s2) modulo 1 (Cranley–Patterson).
glm::vec2 shiftedHammersley(uint32_t i, uint32_t n, float s1, float s2) {
    float u = (float(i) + 0.5f) / float(n) + s1;
    float v = float(radicalInverse(2, i)) + s2;
    return {u - std::floor(u), v - std::floor(v)};
}

/// Salts of the two estimates' random shifts, so that they differ from the bake's other rays.
constexpr uint64_t kSurfelSalt = 0x536b79537572ull;  // "SkySur"
constexpr uint64_t kCacheSalt = 0x536b79436163ull;   // "SkyCac"

}  // namespace

std::vector<float> surfelSkyTransfer(const EmbreeScene& rays, std::span<const Surfel> surfels,
                                     uint32_t rayCount, uint64_t seed) {
    std::vector<float> transfer(surfels.size() * kSkyCoefficients, 0.0f);
    if (rayCount == 0) return transfer;
    const float epsilon = rays.epsilon();
    const float infinity = std::numeric_limits<float>::infinity();
    parallelFor(0, surfels.size(), [&](size_t i) {
        const Surfel& surfel = surfels[i];
        const glm::mat3 frame = frameAround(surfel.normal);
        const glm::vec3 origin = surfel.position + epsilon * surfel.normal;
        Rng rng(seed ^ kSurfelSalt, i);
        const float s1 = rng.uniform(), s2 = rng.uniform();
        double sum[kSkyCoefficients] = {};
        float basis[kSkyCoefficients];
        for (uint32_t r = 0; r < rayCount; ++r) {
            // Cosine-weighted (Malley): density cosθ/π, so T_k ≈ π/N Σ V·y_k.
            const glm::vec2 u = shiftedHammersley(r, rayCount, s1, s2);
            const float radius = std::sqrt(u.x), phi = glm::two_pi<float>() * u.y;
            const glm::vec3 local(radius * std::cos(phi), radius * std::sin(phi),
                                  std::sqrt(std::max(0.0f, 1.0f - u.x)));
            const glm::vec3 direction = glm::normalize(frame * local);
            if (rays.occluded(origin, direction, 0.0f, infinity)) continue;
            shEvaluate(kSkyBands, direction, basis);
            for (int k = 0; k < kSkyCoefficients; ++k) sum[k] += basis[k];
        }
        for (int k = 0; k < kSkyCoefficients; ++k)
            transfer[i * kSkyCoefficients + size_t(k)] =
                float(sum[k] * glm::pi<double>() / rayCount);
    }, 16);
    return transfer;
}

std::vector<float> cacheSkyVisibility(const EmbreeScene& rays, std::span<const Cache> caches,
                                      uint64_t begin, uint64_t end, uint32_t bandsY,
                                      uint32_t rayCount, uint64_t seed) {
    const int bands = skyVisibilityBands(int(bandsY));
    const size_t count = size_t(shCount(bands));
    std::vector<float> visibility((end - begin) * count, 0.0f);
    if (rayCount == 0) return visibility;
    const float epsilon = rays.epsilon();
    const float infinity = std::numeric_limits<float>::infinity();
    parallelFor(begin, end, [&](size_t c) {
        const Cache& cache = caches[c];
        const bool hemisphere = cache.kind == gpu::kCacheKindLightmap;
        const glm::mat3 frame = hemisphere ? frameAround(cache.normal) : glm::mat3(1.0f);
        const glm::vec3 origin = hemisphere ? cache.position + epsilon * cache.normal : cache.position;
        Rng rng(seed ^ kCacheSalt, c);
        const float s1 = rng.uniform(), s2 = rng.uniform();
        std::vector<double> sum(count, 0.0);
        float basis[kMaxShBands * kMaxShBands];
        for (uint32_t r = 0; r < rayCount; ++r) {
            // Uniform over the sphere or the hemisphere: v_k ≈ Ω/N Σ V·y_k.
            const glm::vec2 u = shiftedHammersley(r, rayCount, s1, s2);
            glm::vec3 direction = sampleUniformSphere(hemisphere ? 0.5f * u.x : u.x, u.y);
            if (hemisphere) direction = glm::normalize(frame * direction);
            if (rays.occluded(origin, direction, epsilon, infinity)) continue;
            shEvaluate(bands, direction, basis);
            for (size_t k = 0; k < count; ++k) sum[k] += basis[k];
        }
        const double solidAngle = (hemisphere ? 2.0 : 4.0) * glm::pi<double>();
        for (size_t k = 0; k < count; ++k)
            visibility[(c - begin) * count + k] = float(sum[k] * solidAngle / rayCount);
    }, 16);
    return visibility;
}

}  // namespace pic
