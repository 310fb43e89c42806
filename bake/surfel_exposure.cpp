#include "bake/surfel_exposure.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "bake/surfel_grid.h"
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

Result<SurfelExposure> surfelExposure(const EmbreeScene& rays, const Aabb& bounds, float reach,
                                      const std::vector<Surfel>& surfels,
                                      const ExposureParams& params) {
    if (!(reach > 0.0f))
        return fail(ErrorCode::InvalidInput, "exposure reach must be positive, got {} m", reach);
    if (params.rays == 0)
        return fail(ErrorCode::InvalidInput, "exposure rays per surfel must be positive, got {}",
                    params.rays);
    const uint32_t k = params.rays;
    SurfelExposure exposure;
    exposure.raysPerSurfel = k;
    exposure.freeDistance.assign(surfels.size(), 0.0f);
    exposure.seen.assign(surfels.size() * k, kRayEscaped);
    // A hit's surfel is the nearest one within two radii that faces the ray, distance out of
    // the hit's plane counting four times: surfels are about 1.8 radii apart, so every surface
    // but the smallest parts has one, and the top of a thin slab keeps its own surfels rather
    // than the floor's just under it.
    float radius = 0.0f;
    for (const Surfel& s : surfels) radius = std::max(radius, s.radius);
    const float reachOfHit = 2.0f * std::max(radius, 1e-6f);
    const SurfelGrid grid(surfels, 2.0f * reachOfHit, reachOfHit);
    auto surfelAt = [&](const glm::vec3& p, const glm::vec3& side) {
        uint32_t nearest = kRayUnresolved;
        float best = reachOfHit * reachOfHit;
        for (const SurfelGrid::Entry& e : grid.halo(p)) {
            if (glm::dot(e.normal, side) < 0.5f) continue;
            const glm::vec3 d = e.position - p;
            const float off = glm::dot(d, side);
            const float d2 = glm::dot(d, d) + 15.0f * off * off;
            if (d2 < best) {
                best = d2;
                nearest = e.index;
            }
        }
        return nearest;
    };
    const float epsilon = rays.epsilon();
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
                const float exit = exitDistance(bounds, origin, w);
                if (!(exit > epsilon)) continue;
                // Walls on the bounds themselves are hit a rounding error from the exit.
                const auto hit = rays.intersect(origin, w, 0.0f, exit + 2.0f * epsilon);
                sum += std::min(hit ? hit->t : exit, reach);
                if (!hit) continue;
                const glm::vec3 side = hit->backFace ? -hit->geometricNormal : hit->geometricNormal;
                exposure.seen[i * k + j] = surfelAt(origin + hit->t * w, side);
            }
            exposure.freeDistance[i] = float(sum / k);
        }
        progress.advance(end - begin);
    }, 256);
    progress.finish();
    return exposure;
}

std::vector<float> bouncedExposure(const std::vector<Surfel>& surfels,
                                   const SurfelExposure& exposure) {
    const size_t nS = surfels.size();
    const uint32_t k = exposure.raysPerSurfel;
    PIC_CHECK_EQ(exposure.freeDistance.size(), nS);
    PIC_CHECK_EQ(exposure.seen.size(), nS * k);
    std::vector<double> reflectance(nS);
    for (size_t i = 0; i < nS; ++i) reflectance[i] = std::clamp(double(luminance(surfels[i].albedo)), 0.0, 1.0);
    // E_b / c for the current bounce b, and the sum so far.
    std::vector<double> bounce(exposure.freeDistance.begin(), exposure.freeDistance.end());
    std::vector<double> total = bounce, next(nS);
    auto areaSum = [&](const std::vector<double>& v) {
        double sum = 0.0;
        for (size_t i = 0; i < nS; ++i) sum += v[i] * surfels[i].area;
        return sum;
    };
    constexpr int kMaxBounces = 64;
    constexpr double kConverged = 1e-4;
    double previous = areaSum(bounce);
    for (int b = 1; b <= kMaxBounces && previous > 0.0; ++b) {
        parallelFor(0, nS, [&](size_t i) {
            double sum = 0.0;
            uint32_t counted = 0;
            for (uint32_t j = 0; j < k; ++j) {
                const uint32_t h = exposure.seen[i * k + j];
                if (h == kRayUnresolved) continue;
                ++counted;
                if (h != kRayEscaped) sum += reflectance[h] * bounce[h];
            }
            next[i] = counted > 0 ? sum / counted : 0.0;
        }, 1024);
        const double added = areaSum(next);
        for (size_t i = 0; i < nS; ++i) total[i] += next[i];
        bounce.swap(next);
        // Once a bounce adds little, the rest follow it geometrically: q + q² + … = q/(1 − q)
        // of it, q the ratio of the last two bounces.
        if (added <= kConverged * areaSum(total) || b == kMaxBounces) {
            const double q = added / previous;
            if (q < 1.0)
                for (size_t i = 0; i < nS; ++i) total[i] += bounce[i] * q / (1.0 - q);
            break;
        }
        previous = added;
    }
    std::vector<float> result(nS);
    for (size_t i = 0; i < nS; ++i) result[i] = std::isfinite(total[i]) ? float(total[i]) : 0.0f;
    return result;
}

float exposureReach(const Scene& scene) {
    const glm::vec3 e = scene.bounds.extent();
    const double volume = double(e.x) * e.y * e.z;
    const double reach = scene.totalArea > 0.0 ? 4.0 * volume / scene.totalArea : 0.0;
    return reach > 0.0 ? float(reach) : std::max({e.x, e.y, e.z, 1e-3f});
}

std::vector<float> fluxWeights(const std::vector<Surfel>& surfels,
                               const std::vector<float>& exposure) {
    PIC_CHECK_EQ(exposure.size(), surfels.size());
    std::vector<float> weights(surfels.size());
    for (size_t i = 0; i < surfels.size(); ++i) {
        const Surfel& s = surfels[i];
        // B = π·L_e for emitters (the light set scales a whole material), E / c otherwise.
        const float w = isEmitter(s) ? kPi * luminance(s.emission) : exposure[i];
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
