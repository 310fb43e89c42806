#include "bake/surfel_exposure.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "core/color.h"
#include "core/geometry.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "core/sampling.h"

namespace pic {

namespace {

constexpr float kPi = std::numbers::pi_v<float>;
/// The golden ratio's fractional part: successive azimuths k·φ cover the circle evenly.
constexpr float kGolden = 0.6180339887f;

/// Distance from `origin` along unit `direction` to where the ray leaves `bounds` (0 when the
/// origin lies outside on that side).
float exitDistance(const Aabb& bounds, const glm::vec3& origin, const glm::vec3& direction) {
    float t = std::numeric_limits<float>::infinity();
    for (int a = 0; a < 3; ++a) {
        if (direction[a] > 0.0f) t = std::min(t, (bounds.max[a] - origin[a]) / direction[a]);
        else if (direction[a] < 0.0f) t = std::min(t, (bounds.min[a] - origin[a]) / direction[a]);
    }
    return std::max(t, 0.0f);
}

/// Rescales `weights` of the surfels with `kind(s)` to an area-weighted mean of 1; all-zero
/// kinds become 1.
template <class Kind>
void normalise(const std::vector<Surfel>& surfels, std::vector<float>& weights, Kind&& kind) {
    double weighted = 0.0, area = 0.0;
    for (size_t i = 0; i < surfels.size(); ++i) {
        if (!kind(surfels[i])) continue;
        weighted += double(weights[i]) * surfels[i].area;
        area += surfels[i].area;
    }
    const float scale = weighted > 0.0 ? float(area / weighted) : 0.0f;
    for (size_t i = 0; i < surfels.size(); ++i)
        if (kind(surfels[i])) weights[i] = scale > 0.0f ? weights[i] * scale : 1.0f;
}

}  // namespace

Result<std::vector<float>> surfelFreeDistance(const EmbreeScene& rays, const Aabb& bounds,
                                              float reach, const std::vector<Surfel>& surfels,
                                              const ExposureParams& params) {
    if (!(reach > 0.0f))
        return fail(ErrorCode::InvalidInput, "exposure reach must be positive, got {} m", reach);
    if (params.rays == 0)
        return fail(ErrorCode::InvalidInput, "exposure rays per surfel must be positive, got {}",
                    params.rays);
    std::vector<float> distance(surfels.size(), 0.0f);
    const float epsilon = rays.epsilon();
    const uint32_t k = params.rays;
    Progress progress("surfel exposure", surfels.size());
    parallelForChunks(0, surfels.size(), [&](size_t begin, size_t end) {
        for (size_t i = begin; i < end; ++i) {
            const Surfel& s = surfels[i];
            glm::vec3 tangent, bitangent;
            orthonormalBasis(s.normal, tangent, bitangent);
            const glm::vec3 origin = s.position + epsilon * s.normal;
            // Cosine-distributed directions, stratified in cos²θ and spread in azimuth by the
            // golden ratio, with a random offset of both per surfel.
            Rng rng(params.seed, i);
            const float jitter = rng.uniform(), turn = rng.uniform();
            double sum = 0.0;
            for (uint32_t j = 0; j < k; ++j) {
                const float u1 = (float(j) + jitter) / float(k);
                float u2 = float(j) * kGolden + turn;
                u2 -= std::floor(u2);
                const float r = std::sqrt(u1), phi = 2.0f * kPi * u2;
                const glm::vec3 w = r * std::cos(phi) * tangent + r * std::sin(phi) * bitangent +
                                    std::sqrt(std::max(0.0f, 1.0f - u1)) * s.normal;
                const float far = std::min(exitDistance(bounds, origin, w), reach);
                if (!(far > epsilon)) continue;
                const auto hit = rays.intersect(origin, w, 0.0f, far);
                sum += hit ? hit->t : far;
            }
            distance[i] = float(sum / k);
        }
        progress.advance(end - begin);
    }, 256);
    progress.finish();
    return distance;
}

float exposureReach(const Scene& scene) {
    const glm::vec3 e = scene.bounds.extent();
    const double volume = double(e.x) * e.y * e.z;
    const double reach = scene.totalArea > 0.0 ? 4.0 * volume / scene.totalArea : 0.0;
    return reach > 0.0 ? float(reach) : std::max({e.x, e.y, e.z, 1e-3f});
}

std::vector<float> fluxWeights(const std::vector<Surfel>& surfels,
                               const std::vector<float>& freeDistance) {
    PIC_CHECK_EQ(freeDistance.size(), surfels.size());
    std::vector<float> weights(surfels.size());
    for (size_t i = 0; i < surfels.size(); ++i) {
        const Surfel& s = surfels[i];
        // B = π·L_e for emitters (the light set scales a whole material), E_cos[min(t, R)]
        // otherwise.
        const float w = isEmitter(s) ? kPi * luminance(s.emission)
                                     : freeDistance[i];
        weights[i] = std::isfinite(w) ? std::max(w, 0.0f) : 0.0f;
    }
    normalise(surfels, weights, [](const Surfel& s) { return isEmitter(s); });
    normalise(surfels, weights, [](const Surfel& s) { return !isEmitter(s); });
    // A floor keeps every node's Σ w·a positive: a node of hidden or black surfels still
    // passes on whatever flux the runtime gives it.
    for (float& w : weights) w = std::max(w, kMinFluxWeight);
    return weights;
}

glm::vec3 fluxColour(const Surfel& surfel) {
    if (!isEmitter(surfel)) return surfel.albedo;
    const float y = luminance(surfel.emission);
    return y > 0.0f ? surfel.emission / y : glm::vec3(1.0f);
}

std::vector<double> weightedNodeArea(const std::vector<Surfel>& surfels,
                                     const std::vector<Node>& nodes,
                                     const std::vector<float>& weights) {
    PIC_CHECK_EQ(weights.size(), surfels.size());
    PIC_CHECK_EQ(nodes.size(), 2 * surfels.size() - 1);
    std::vector<double> area(nodes.size());
    for (size_t n = 0; n < nodes.size(); ++n) {
        const Node& node = nodes[n];
        area[n] = node.left == kNoNode ? double(weights[n]) * surfels[n].area
                                       : area[node.left] + area[node.right];
    }
    return area;
}

}  // namespace pic
