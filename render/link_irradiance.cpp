#include "render/link_irradiance.h"

#include <array>
#include <cstdint>
#include <numbers>

#include "core/color.h"
#include "core/sh.h"

namespace pic {

float linkIrradiance(const BakeData& bake, size_t slot) {
    const LinkSet& links = bake.links;
    const Cache& cache = bake.caches[slot / links.linksPerCache];
    if (cache.kind != gpu::kCacheKindLightmap) return 0.0f;
    const glm::vec3& normal = cache.normal;
    const int bandsY = int(bake.params.bandsY);
    if (links.mode == LinkMode::Rtp) {
        // The cone's projection factor·K_l(α)·y_lm(d) convolved with the clamped cosine at n:
        // Σ_m y_lm(d)·y_lm(n) = (2l + 1)/(4π)·P_l(n·d) (the addition theorem).
        const RtpLink& link = links.rtp[slot];
        const double x = glm::dot(normal, decodeOctahedral(link.directionOct));
        std::array<double, kMaxShBands> cone;
        coneZonalBands(bandsY, double(link.oneMinusCosAlpha), cone.data());
        double sum = 0.0, legendre = 1.0, previous = 0.0;  // P_l(x), P_{l−1}(x)
        for (int l = 0; l < bandsY; ++l) {
            sum += double(clampedCosineZonal(l)) * cone[l] * (2 * l + 1) /
                   (4.0 * std::numbers::pi) * legendre;
            const double next = ((2 * l + 1) * x * legendre - l * previous) / (l + 1);
            previous = legendre;
            legendre = next;
        }
        return float(double(link.factor) * sum);
    }
    float basis[shCount(kMaxShBands)];
    shEvaluate(bandsY, normal, basis);
    const uint16_t* coefficients = links.shCoefficients.data() + slot * size_t(shCount(bandsY));
    float sum = 0.0f;
    for (int l = 0; l < bandsY; ++l)
        for (int i = l * l; i < (l + 1) * (l + 1); ++i)
            sum += clampedCosineZonal(l) * halfToFloat(coefficients[i]) * basis[i];
    return sum;
}

}  // namespace pic
