#include "render/node_spread.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "core/error.h"
#include "core/parallel.h"

namespace pic {
namespace {

/// Eigenvalues (ascending order not guaranteed) and orthonormal eigenvectors (columns) of a
/// symmetric 3×3 matrix by cyclic Jacobi rotations, to double precision.
void symmetricEigen(glm::dmat3 a, glm::dvec3& values, glm::dmat3& vectors) {
    vectors = glm::dmat3(1.0);
    for (int sweep = 0; sweep < 32; ++sweep) {
        const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        const double diagonal = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
        if (!(off > 1e-30 * diagonal)) break;
        for (int p = 0; p < 2; ++p)
            for (int q = p + 1; q < 3; ++q) {
                if (a[p][q] == 0.0) continue;
                // The rotation in the (p, q) plane that zeroes a[p][q].
                const double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                const double t = (theta >= 0.0 ? 1.0 : -1.0) /
                                 (std::abs(theta) + std::sqrt(theta * theta + 1.0));
                const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
                glm::dmat3 rotation(1.0);
                rotation[p][p] = c;
                rotation[q][q] = c;
                rotation[q][p] = s;   // column q, row p
                rotation[p][q] = -s;  // column p, row q
                a = glm::transpose(rotation) * a * rotation;
                vectors = vectors * rotation;
            }
    }
    values = {a[0][0], a[1][1], a[2][2]};
}

/// A node's variance along each of its axes (0 for leaves).
glm::vec3 variances(const NodeSpread& spread, size_t node) {
    glm::vec3 variance(0.0f);
    for (int k = 0; k < 3; ++k)
        if (spread.inverseVariance[node][k] > 0.0f) variance[k] = 1.0f / spread.inverseVariance[node][k];
    return variance;
}

/// A node's box model, the half extent a_k = √3·σ_k of an even spread with its variance along
/// each axis; 0 along axes it is flat on (variance at most gpu::kFlatVariance of the total).
glm::vec3 boxModel(const NodeSpread& spread, size_t node) {
    const glm::vec3 variance = variances(spread, node);
    const float total = variance.x + variance.y + variance.z;
    glm::vec3 a(0.0f);
    for (int k = 0; k < 3; ++k)
        if (variance[k] > gpu::kFlatVariance * total) a[k] = std::sqrt(3.0f * variance[k]);
    return a;
}

}  // namespace

NodeSpread nodeSpread(const BakeData& bake) {
    const size_t nS = bake.surfels.size(), nodes = bake.nodes.size();
    PIC_CHECK(bake.surfelWeights.empty() || bake.surfelWeights.size() == nS);
    // Σ ω, Σ ω·x and Σ ω·x·xᵀ per node in double, summed up the tree (children precede parents).
    std::vector<double> weight(nodes, 0.0);
    std::vector<glm::dvec3> first(nodes, glm::dvec3(0.0));
    std::vector<glm::dmat3> second(nodes, glm::dmat3(0.0));
    for (size_t n = 0; n < nodes; ++n) {
        const Node& node = bake.nodes[n];
        if (node.left == kNoNode) {
            const Surfel& s = bake.surfels[n];
            const double w =
                (bake.surfelWeights.empty() ? 1.0 : double(bake.surfelWeights[n])) * double(s.area);
            const glm::dvec3 x(s.position);
            weight[n] = w;
            first[n] = w * x;
            second[n] = w * glm::outerProduct(x, x);
        } else {
            weight[n] = weight[node.left] + weight[node.right];
            first[n] = first[node.left] + first[node.right];
            second[n] = second[node.left] + second[node.right];
        }
    }
    NodeSpread spread;
    spread.centroid.resize(nodes);
    spread.axes.assign(nodes, glm::mat3(1.0f));
    spread.inverseVariance.assign(nodes, glm::vec3(0.0f));
    spread.low.assign(nodes, glm::vec3(0.0f));
    spread.high.assign(nodes, glm::vec3(0.0f));
    parallelFor(
        0, nodes,
        [&](size_t n) {
            if (!(weight[n] > 0.0)) return;  // no area: nothing spreads
            const glm::dvec3 mean = first[n] / weight[n];
            spread.centroid[n] = glm::vec3(mean);
            const Node& node = bake.nodes[n];
            if (node.left == kNoNode) return;
            const glm::dmat3 covariance = second[n] / weight[n] - glm::outerProduct(mean, mean);
            const double trace = covariance[0][0] + covariance[1][1] + covariance[2][2];
            if (!(trace > 0.0)) return;  // every surfel at one point: no spread to fit
            glm::dvec3 variance;
            glm::dmat3 axes;
            symmetricEigen(covariance, variance, axes);
            spread.axes[n] = glm::mat3(axes);
            for (int i = 0; i < 3; ++i)
                spread.inverseVariance[n][i] =
                    float(1.0 / (std::max(variance[i], 0.0) + 1e-6 * trace));
            glm::dvec3 low(0.0), high(0.0);
            for (uint32_t s = node.firstSurfel; s < node.firstSurfel + node.surfelCount; ++s) {
                const glm::dvec3 y =
                    glm::transpose(axes) * (glm::dvec3(bake.surfels[s].position) - mean);
                low = glm::min(low, y);
                high = glm::max(high, y);
            }
            spread.low[n] = glm::vec3(low);
            spread.high[n] = glm::vec3(high);
        },
        256);
    return spread;
}

ChannelSpread limitedSpread(const NodeSpread& spread, size_t node, float flux,
                            const glm::vec3& moment) {
    if (!(flux > 0.0f)) return {};
    // The box as centre ± half extent about x̄_n, in the axes' frame.
    const glm::vec3 centre = 0.5f * (spread.low[node] + spread.high[node]);
    const glm::vec3 half = 0.5f * (spread.high[node] - spread.low[node]);
    glm::vec3 g = (moment * spread.axes[node]) * spread.inverseVariance[node];
    // The least of Φ + g·y over the box is Φ + g·centre − Σ_k |g_k|·half_k: where it is
    // negative, scale g until it is 0 (the drop Σ|g|·half − g·centre then exceeds Φ ≥ 0).
    float atCentre = flux + glm::dot(g, centre);
    glm::vec3 change = glm::abs(g * half);
    const float swing = change.x + change.y + change.z;
    const bool limited = swing > atCentre;
    float kept = 1.0f;  // the share of g the limiter keeps
    if (limited) {
        kept = flux / (swing - glm::dot(g, centre));
        g *= kept;
        atCentre = flux + glm::dot(g, centre);
    }
    const bool concentrated = kept < gpu::kExponentialLimit;
    if (!(atCentre > 0.0f)) return {0.0f, glm::vec3(0.0f), limited, concentrated};
    ChannelSpread out{atCentre, g * half * (1.0f / atCentre), limited, concentrated};
    // Σ|slopes| ≤ 1 holds up to rounding; keep it exact, so no point of the box reads < 0.
    change = glm::abs(out.slopes);
    const float sum = change.x + change.y + change.z;
    if (sum > 1.0f) out.slopes *= 1.0f / sum;
    return out;
}

bool isFlat(const NodeSpread& spread, size_t node) {
    const glm::vec3 variance = variances(spread, node);
    const float total = variance.x + variance.y + variance.z;
    return std::min({variance.x, variance.y, variance.z}) <= gpu::kFlatVariance * total;
}

bool fitsBoxModel(const NodeSpread& spread, size_t node, const glm::vec3& flux,
                  const glm::mat3& moment) {
    const glm::vec3 a = boxModel(spread, node);
    for (int c = 0; c < 3; ++c) {
        if (!(flux[c] > 0.0f)) continue;
        const glm::vec3 mean = (moment[c] * spread.axes[node]) * (1.0f / flux[c]);
        for (int k = 0; k < 3; ++k)
            if (a[k] > 0.0f && std::abs(mean[k]) > gpu::kExponentialReach * a[k]) return false;
    }
    return true;
}

float inverseLangevin(float r) {
    const float a = std::min(std::abs(r), 0.99f);
    const float x = a * (3.0f - 2.6f * a + 0.7f * a * a) / ((1.0f - a) * (1.0f + 0.1f * a));
    return r < 0.0f ? -x : x;
}

ExponentialSpread exponentialSpread(const NodeSpread& spread, size_t node, float flux,
                                    const glm::vec3& moment) {
    if (!(flux > 0.0f)) return {};
    const glm::vec3 low = spread.low[node], high = spread.high[node];
    const glm::vec3 centre = 0.5f * (low + high), half = 0.5f * (high - low);
    // The flux centroid's offset along the axes, M / Φ.
    const glm::vec3 mean = (moment * spread.axes[node]) * (1.0f / flux);
    const glm::vec3 a = boxModel(spread, node);
    glm::vec3 beta(0.0f);
    for (int k = 0; k < 3; ++k)
        if (a[k] > 0.0f) beta[k] = inverseLangevin(mean[k] / a[k]) / a[k];
    const float sum = glm::dot(glm::abs(beta), half);
    if (sum > gpu::kExponentialSpreadCap) beta *= gpu::kExponentialSpreadCap / sum;
    ExponentialSpread out;
    for (int k = 0; k < 3; ++k) {
        const float x = std::abs(beta[k] * a[k]);
        // ln(sinh x / x), its series where x is small.
        if (x > 1e-2f) out.concentration += std::log(std::sinh(x) / x);
        else out.concentration += x * x * (1.0f / 6.0f);
    }
    out.centre = flux * std::exp(glm::dot(beta, centre));
    out.slopes = beta * half;
    return out;
}

namespace {
/// How many nodes ahead the pull prefetches a node's children.
constexpr size_t kPrefetchNodes = 8;
/// Nodes per task of a level's spreads (about 0.2 µs a node): fine enough that the levels of
/// a few thousand nodes still spread over many cores (1,024 kept a 16-core machine's pull
/// at 1.3 ms, a level of 2,047 nodes on two of its cores).
constexpr size_t kSpreadGrain = 64;
}  // namespace

void pullFluxSpread(const BakeData& bake, const NodeSpread& spread,
                    std::span<const glm::vec3> nodeFlux, std::span<glm::mat3> moment,
                    std::span<glm::vec3> centreFlux, std::span<glm::mat3> slopes,
                    std::span<glm::vec3> concentration, std::span<uint8_t> exponential) {
    const size_t nS = bake.surfels.size();
    PIC_CHECK_EQ(nodeFlux.size(), bake.nodes.size());
    PIC_CHECK_EQ(moment.size(), bake.nodes.size());
    PIC_CHECK_EQ(centreFlux.size(), bake.nodes.size());
    PIC_CHECK_EQ(slopes.size(), bake.nodes.size());
    PIC_CHECK_EQ(concentration.size(), bake.nodes.size());
    PIC_CHECK_EQ(exponential.size(), bake.nodes.size());
    PIC_CHECK_EQ(spread.centroid.size(), bake.nodes.size());
    // Leaves (and any node the levels leave out) read their own flux, evenly.
    const size_t innerBegin = bake.levelOffsets.empty() ? nS : bake.levelOffsets.front();
    const size_t innerEnd = bake.levelOffsets.empty() ? nS : bake.levelOffsets.back();
    // (Megabytes at the moderate setting: written in parallel, not to hold the update up
    // on many cores.)
    for (const auto& [first, last] :
         {std::pair{size_t{0}, innerBegin}, std::pair{innerEnd, nodeFlux.size()}}) {
        parallelForChunks(first, last, [&](size_t begin, size_t end) {
            std::fill(moment.begin() + begin, moment.begin() + end, glm::mat3(0.0f));
            std::copy(nodeFlux.begin() + begin, nodeFlux.begin() + end, centreFlux.begin() + begin);
            std::fill(slopes.begin() + begin, slopes.begin() + end, glm::mat3(0.0f));
            std::fill(concentration.begin() + begin, concentration.begin() + end, glm::vec3(0.0f));
            std::fill(exponential.begin() + begin, exponential.begin() + end, uint8_t{0});
        }, 4096);
    }
    for (size_t level = 1; level < bake.levelOffsets.size(); ++level) {
        const size_t levelEnd = bake.levelOffsets[level];
        parallelFor(
            bake.levelOffsets[level - 1], levelEnd,
            [&](size_t n) {
                // The children lie scattered over the levels below: fetch a later node's
                // moments and centroids ahead of their use.
                if (n + kPrefetchNodes < levelEnd) {
                    const Node& later = bake.nodes[n + kPrefetchNodes];
                    for (const uint32_t child : {later.left, later.right}) {
                        __builtin_prefetch(&moment[child]);
                        __builtin_prefetch(&spread.centroid[child]);
                        __builtin_prefetch(&nodeFlux[child]);
                    }
                }
                const Node& node = bake.nodes[n];
                glm::mat3 m = moment[node.left] + moment[node.right];
                for (const uint32_t child : {node.left, node.right}) {
                    const glm::vec3 offset = spread.centroid[child] - spread.centroid[n];
                    for (int c = 0; c < 3; ++c) m[c] += nodeFlux[child][c] * offset;
                }
                moment[n] = m;
                bool concentrated = false;
                for (int c = 0; c < 3; ++c) {
                    const ChannelSpread channel = limitedSpread(spread, n, nodeFlux[n][c], m[c]);
                    centreFlux[n][c] = channel.centre;
                    slopes[n][c] = channel.slopes;
                    concentrated = concentrated || channel.concentrated;
                }
                concentration[n] = glm::vec3(0.0f);
                exponential[n] =
                    concentrated && isFlat(spread, n) && fitsBoxModel(spread, n, nodeFlux[n], m) ? 1 : 0;
                if (!exponential[n]) return;
                for (int c = 0; c < 3; ++c) {
                    const ExponentialSpread channel = exponentialSpread(spread, n, nodeFlux[n][c], m[c]);
                    centreFlux[n][c] = channel.centre;
                    slopes[n][c] = channel.slopes;
                    concentration[n][c] = channel.concentration;
                }
            },
            kSpreadGrain);
    }
}

uint32_t encodeBoxPoint(const NodeSpread& spread, size_t node, const glm::vec3& offset) {
    const glm::vec3 low = spread.low[node], high = spread.high[node];
    const glm::vec3 y = offset * spread.axes[node];  // axesᵀ·offset
    uint32_t code = 0;
    for (int k = 0; k < 3; ++k) {
        const float half = 0.5f * (high[k] - low[k]);
        const float u = half > 0.0f ? (y[k] - 0.5f * (low[k] + high[k])) / half : 0.0f;
        const float clamped = std::isfinite(u) ? std::clamp(u, -1.0f, 1.0f) : 0.0f;
        code |= uint32_t(uint8_t(int8_t(std::lround(clamped * 127.0f)))) << (8 * k);
    }
    return code;
}

glm::vec3 decodeBoxPoint(uint32_t code) {
    glm::vec3 u;
    for (int k = 0; k < 3; ++k)
        u[k] = std::max(float(int8_t(uint8_t(code >> (8 * k)))) / 127.0f, -1.0f);
    return u;
}

}  // namespace pic
