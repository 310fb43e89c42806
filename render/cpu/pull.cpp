#include "render/cpu/pull.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/parallel.h"

namespace pic {

void pullFlux(const BakeData& bake, std::span<glm::vec3> nodeFlux) {
    PIC_CHECK_EQ(nodeFlux.size(), bake.nodes.size());
    PIC_CHECK(!bake.levelOffsets.empty());
    PIC_CHECK_EQ(size_t{bake.levelOffsets.back()}, bake.nodes.size());
    // Level k ≥ 1 is [levelOffsets[k − 1], levelOffsets[k]); its children lie on lower levels,
    // so one parallel loop per level, in order, is a complete pull (one dispatch per level on
    // the GPU).
    for (size_t level = 1; level < bake.levelOffsets.size(); ++level) {
        parallelFor(bake.levelOffsets[level - 1], bake.levelOffsets[level], [&](size_t n) {
            const Node& node = bake.nodes[n];
            PIC_DCHECK(node.left < n && node.right < n);
            nodeFlux[n] = nodeFlux[node.left] + nodeFlux[node.right];
        }, 1024);
    }
}

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
            const double w = (bake.surfelWeights.empty() ? 1.0 : double(bake.surfelWeights[n])) *
                             double(s.area);
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
    parallelFor(0, nodes, [&](size_t n) {
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
            spread.inverseVariance[n][i] = float(1.0 / (std::max(variance[i], 0.0) + 1e-6 * trace));
        glm::dvec3 low(0.0), high(0.0);
        for (uint32_t s = node.firstSurfel; s < node.firstSurfel + node.surfelCount; ++s) {
            const glm::dvec3 y = glm::transpose(axes) * (glm::dvec3(bake.surfels[s].position) - mean);
            low = glm::min(low, y);
            high = glm::max(high, y);
        }
        spread.low[n] = glm::vec3(low);
        spread.high[n] = glm::vec3(high);
    }, 256);
    return spread;
}

glm::vec3 limitedGradient(const NodeSpread& spread, size_t node, float flux, const glm::vec3& moment) {
    if (!(flux > 0.0f)) return glm::vec3(0.0f);
    const glm::mat3& axes = spread.axes[node];
    const glm::vec3 g = (moment * axes) * spread.inverseVariance[node];  // in the axes' frame
    // The least of Φ + g·y over the box: each axis at the end where g·y is lowest.
    const glm::vec3 lowest = glm::min(g * spread.low[node], g * spread.high[node]);
    const float drop = -(lowest.x + lowest.y + lowest.z);
    const float limit = drop > flux ? flux / drop : 1.0f;
    return axes * (g * (limit / flux));
}

void pullFluxGradients(const BakeData& bake, const NodeSpread& spread,
                       std::span<const glm::vec3> nodeFlux, std::span<glm::mat3> moment,
                       std::span<glm::mat3> gradient) {
    const size_t nS = bake.surfels.size();
    PIC_CHECK_EQ(nodeFlux.size(), bake.nodes.size());
    PIC_CHECK_EQ(moment.size(), bake.nodes.size());
    PIC_CHECK_EQ(gradient.size(), bake.nodes.size());
    PIC_CHECK_EQ(spread.centroid.size(), bake.nodes.size());
    std::fill(moment.begin(), moment.begin() + nS, glm::mat3(0.0f));
    std::fill(gradient.begin(), gradient.begin() + nS, glm::mat3(0.0f));
    for (size_t level = 1; level < bake.levelOffsets.size(); ++level) {
        parallelFor(bake.levelOffsets[level - 1], bake.levelOffsets[level], [&](size_t n) {
            const Node& node = bake.nodes[n];
            glm::mat3 m = moment[node.left] + moment[node.right];
            for (const uint32_t child : {node.left, node.right}) {
                const glm::vec3 offset = spread.centroid[child] - spread.centroid[n];
                for (int c = 0; c < 3; ++c) m[c] += nodeFlux[child][c] * offset;
            }
            moment[n] = m;
            for (int c = 0; c < 3; ++c) gradient[n][c] = limitedGradient(spread, n, nodeFlux[n][c], m[c]);
        }, 1024);
    }
}

}  // namespace pic
