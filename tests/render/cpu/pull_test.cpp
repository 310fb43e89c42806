// The pull's CPU twin (render/cpu/pull.h) and the node spreads (render/node_spread.h): inner
// nodes of a three-level hierarchy hold the exact sums of their leaves; the limited linear and
// the exponential flux spreads and the box points links read them at.

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/bake_data.h"
#include "render/cpu/pull.h"
#include "render/node_spread.h"

namespace pic {
namespace {

TEST(Pull, InnerNodesHoldExactSumsOfTheirLeaves) {
    // Leaves 0..4; level 1: 5 = (0, 1), 6 = (2, 3); level 2: 7 = (5, 4); level 3: 8 = (7, 6).
    BakeData bake;
    bake.surfels.resize(5);
    bake.nodes.resize(9);
    const uint32_t children[4][2] = {{0, 1}, {2, 3}, {5, 4}, {7, 6}};
    for (uint32_t k = 0; k < 4; ++k) {
        bake.nodes[5 + k].left = children[k][0];
        bake.nodes[5 + k].right = children[k][1];
    }
    bake.levelOffsets = {5, 7, 8, 9};
    // Leaf values far apart in magnitude: any other summation would still be exact for these
    // dyadic numbers, so equality tests the tree, not the rounding.
    std::vector<glm::vec3> flux(9, glm::vec3(-1.0f));
    flux[0] = {1.0f, 0.5f, 0.0f};
    flux[1] = {2.0f, 0.25f, 1.0f};
    flux[2] = {4.0f, 0.125f, 1024.0f};
    flux[3] = {8.0f, 0.0625f, 0.0f};
    flux[4] = {16.0f, 0.03125f, 2.0f};
    pullFlux(bake, flux);
    EXPECT_EQ(flux[5], glm::vec3(3.0f, 0.75f, 1.0f));
    EXPECT_EQ(flux[6], glm::vec3(12.0f, 0.1875f, 1024.0f));
    EXPECT_EQ(flux[7], glm::vec3(19.0f, 0.78125f, 3.0f));
    EXPECT_EQ(flux[8], glm::vec3(31.0f, 0.96875f, 1027.0f));
    EXPECT_EQ(flux[0], glm::vec3(1.0f, 0.5f, 0.0f));  // leaves untouched
}

/// `count` (a power of two) unit-area surfels at x = 0, 1, …, count − 1 under a balanced
/// hierarchy, level by level: for four, leaves 0-3, 4 = (0, 1), 5 = (2, 3), root 6 = (4, 5).
BakeData lineBake(uint32_t count = 4) {
    BakeData bake;
    bake.surfels.resize(count);
    for (uint32_t s = 0; s < count; ++s) {
        bake.surfels[s].position = {float(s), 0.0f, 0.0f};
        bake.surfels[s].area = 1.0f;
    }
    bake.surfelWeights.assign(count, 1.0f);
    bake.nodes.resize(2 * count - 1);
    for (uint32_t s = 0; s < count; ++s) {
        bake.nodes[s].left = bake.nodes[s].right = kNoNode;
        bake.nodes[s].firstSurfel = s;
        bake.nodes[s].surfelCount = 1;
    }
    uint32_t first = 0, width = count;  // the level below: nodes [first, first + width)
    while (width > 1) {
        const uint32_t begin = first + width;
        for (uint32_t k = 0; k < width / 2; ++k) {
            Node& node = bake.nodes[begin + k];
            node.left = first + 2 * k;
            node.right = first + 2 * k + 1;
            node.firstSurfel = bake.nodes[node.left].firstSurfel;
            node.surfelCount = 2 * bake.nodes[node.left].surfelCount;
        }
        first = begin;
        width /= 2;
        bake.levelOffsets.push_back(first);
    }
    bake.levelOffsets.push_back(2 * count - 1);
    return bake;
}

/// The nodes' spreads as pullFluxSpread writes them.
struct Spreads {
    std::vector<glm::mat3> moment, slopes;
    std::vector<glm::vec3> centre, concentration;
    std::vector<uint8_t> exponential;
};

Spreads pulledSpreads(const BakeData& bake, const NodeSpread& spread,
                      const std::vector<glm::vec3>& flux) {
    const size_t n = flux.size();
    Spreads out{std::vector<glm::mat3>(n), std::vector<glm::mat3>(n), std::vector<glm::vec3>(n),
                std::vector<glm::vec3>(n), std::vector<uint8_t>(n)};
    pullFluxSpread(bake, spread, flux, out.moment, out.centre, out.slopes, out.concentration,
                   out.exponential);
    return out;
}

/// Box coordinates of the point at x on the line, unquantised: (axisᵀ·(x − x̄) − centre) /
/// half extent per axis, 0 on flat axes.
glm::vec3 boxPoint(const NodeSpread& spread, uint32_t node, float x) {
    const glm::vec3 y = (glm::vec3(x, 0.0f, 0.0f) - spread.centroid[node]) * spread.axes[node];
    glm::vec3 u(0.0f);
    for (int k = 0; k < 3; ++k) {
        const float half = 0.5f * (spread.high[node][k] - spread.low[node][k]);
        if (half > 0.0f) u[k] = (y[k] - 0.5f * (spread.low[node][k] + spread.high[node][k])) / half;
    }
    return u;
}

/// The flux the spread of `node` gives the part of it centred at `x` with share `share` of its
/// weight and spread share `rho`, in channel `c`, as a link reads it
/// (render/cpu/cache_lighting.h NodeLight).
float spreadFlux(const NodeSpread& spread, const Spreads& s, uint32_t node, float x, float share,
                 int c, float rho = 0.0f) {
    const float along = glm::dot(s.slopes[node][c], boxPoint(spread, node, x));
    if (s.exponential[node])
        return share * s.centre[node][c] * std::exp(along - (1.0f - rho) * s.concentration[node][c]);
    return share * s.centre[node][c] * (1.0f + along);
}

TEST(Pull, LinearFluxIsSpreadExactly) {
    // Φ_s = 1 + x_s in red, 4 − x_s in green, constant in blue: the fitted spread of every
    // node reproduces every part of it, and the root's halves read their own flux.
    const BakeData bake = lineBake();
    std::vector<glm::vec3> flux(7);
    for (uint32_t s = 0; s < 4; ++s) flux[s] = {1.0f + float(s), 4.0f - float(s), 2.0f};
    pullFlux(bake, flux);
    const NodeSpread spread = nodeSpread(bake);
    EXPECT_NEAR(spread.centroid[6].x, 1.5f, 1e-6f);
    const Spreads s = pulledSpreads(bake, spread, flux);
    // M = Σ Φ_s (x_s − 1.5) = 5 in red, −5 in green, 0 in blue.
    EXPECT_NEAR(s.moment[6][0].x, 5.0f, 1e-5f);
    EXPECT_NEAR(s.moment[6][1].x, -5.0f, 1e-5f);
    EXPECT_NEAR(s.moment[6][2].x, 0.0f, 1e-5f);
    // The box is [0, 3] about its centre 1.5: the centre reads the mean, 2.5 per quarter.
    EXPECT_NEAR(s.centre[6].x, 10.0f, 1e-4f);
    for (uint32_t x = 0; x < 4; ++x)
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(spreadFlux(spread, s, 6, float(x), 0.25f, c), flux[x][c], 1e-4f)
                << "surfel " << x << " channel " << c;
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(spreadFlux(spread, s, 6, 0.5f, 0.5f, c), flux[4][c], 1e-4f);
        EXPECT_NEAR(spreadFlux(spread, s, 6, 2.5f, 0.5f, c), flux[5][c], 1e-4f);
    }
    for (uint32_t x = 0; x < 4; ++x) {
        EXPECT_EQ(s.slopes[x], glm::mat3(0.0f));
        EXPECT_EQ(s.centre[x], flux[x]);  // a leaf reads its own flux
    }
}

TEST(Pull, LimitedLinearSpreadStaysNonNegativeAndKeepsTheTotal) {
    // All flux on the last surfel, seen by the limiter alone: the fit would go negative at
    // x = 0 (1 − 1.2·1.5 < 0), so it scales the gradient until the spread there is exactly 0.
    const BakeData bake = lineBake();
    const NodeSpread spread = nodeSpread(bake);
    const glm::vec3 moment(1.5f, 0.0f, 0.0f);  // Σ Φ_s (x_s − 1.5), all of Φ = 1 at x = 3
    const ChannelSpread s = limitedSpread(spread, 6, 1.0f, moment);
    EXPECT_TRUE(s.limited);
    const auto part = [&](float x) {
        return 0.25f * s.centre * (1.0f + glm::dot(s.slopes, boxPoint(spread, 6, x)));
    };
    float total = 0.0f;
    for (uint32_t x = 0; x < 4; ++x) {
        EXPECT_GE(part(float(x)), -1e-6f) << "surfel " << x;
        total += part(float(x));
    }
    EXPECT_NEAR(part(0.0f), 0.0f, 1e-6f);
    EXPECT_NEAR(total, 1.0f, 1e-5f);
    // Brighter towards the light, but only 0, 1/6, 1/3, 1/2: a line cannot hold the peak.
    EXPECT_NEAR(part(3.0f), 0.5f, 1e-5f);
    EXPECT_NEAR(std::abs(s.slopes.x) + std::abs(s.slopes.y) + std::abs(s.slopes.z), 1.0f, 1e-5f);
}

TEST(Pull, ConcentratedFluxSpreadsExponentially) {
    // All flux on the last of eight surfels: the fitted line would fall to 1 − 6/9·3.5 < −1
    // at x = 0, so the limiter keeps 3/7 of it, less than kExponentialLimit, and the root,
    // flat, spreads exponentially; its reads follow the peak the line could not.
    const BakeData bake = lineBake(8);
    const uint32_t root = 14, lit = 7;
    std::vector<glm::vec3> flux(15, glm::vec3(0.0f));
    flux[lit] = glm::vec3(1.0f, 0.0f, 1.0f);  // nothing in green
    pullFlux(bake, flux);
    const NodeSpread spread = nodeSpread(bake);
    const Spreads s = pulledSpreads(bake, spread, flux);
    ASSERT_EQ(s.exponential[root], 1);
    EXPECT_EQ(s.exponential[8], 0);  // surfels 0 and 1, no flux: nothing to limit
    // Green holds no flux and reads none.
    EXPECT_EQ(s.centre[root].g, 0.0f);
    EXPECT_EQ(spreadFlux(spread, s, root, float(lit), 0.125f, 1), 0.0f);
    // A link that sees the whole node evenly (spread share 1, centroid at x̄ = 3.5) reads Φ.
    EXPECT_NEAR(spreadFlux(spread, s, root, 3.5f, 1.0f, 0, 1.0f), 1.0f, 1e-5f);
    // Each surfel seen alone (spread share 0): positive, rising towards the light, the lit one
    // with more than half of the flux (the limited line gives it 7/28 = 0.25) and the parts'
    // sum close to Φ.
    float total = 0.0f, previous = 0.0f;
    for (uint32_t x = 0; x < 8; ++x) {
        const float part = spreadFlux(spread, s, root, float(x), 0.125f, 0);
        EXPECT_GT(part, previous) << "surfel " << x;
        previous = part;
        total += part;
    }
    EXPECT_GT(spreadFlux(spread, s, root, float(lit), 0.125f, 0), 0.5f);
    EXPECT_NEAR(total, 1.0f, 0.1f);
    // The cap: Σ|slopes| ≤ 3, so the far end reads at least e^−6 of the near end.
    const glm::vec3 slopes = s.slopes[root][0];
    EXPECT_LE(std::abs(slopes.x) + std::abs(slopes.y) + std::abs(slopes.z),
              gpu::kExponentialSpreadCap + 1e-5f);
}

TEST(Pull, AFluxCentroidBeyondTheBoxModelKeepsTheLine) {
    // Seven surfels at x = 0…6 and one at 20, all flux on the far one. The root's box model
    // is x̄ ± √3σ = 5.125 ± 10.26, and its flux centroid lies 14.875 from x̄, 1.45 of that:
    // an exponential normalised over the model would read the far end many times over. The
    // limiter keeps less than kExponentialLimit of the line, yet the root stays linear.
    BakeData bake = lineBake(8);
    bake.surfels[7].position.x = 20.0f;
    const uint32_t root = 14, lit = 7;
    std::vector<glm::vec3> flux(15, glm::vec3(0.0f));
    flux[lit] = glm::vec3(1.0f);
    pullFlux(bake, flux);
    const NodeSpread spread = nodeSpread(bake);
    const Spreads s = pulledSpreads(bake, spread, flux);
    EXPECT_TRUE(isFlat(spread, root));
    EXPECT_TRUE(limitedSpread(spread, root, 1.0f, s.moment[root][0]).concentrated);
    EXPECT_FALSE(fitsBoxModel(spread, root, flux[root], s.moment[root]));
    EXPECT_EQ(s.exponential[root], 0);
    EXPECT_EQ(s.concentration[root], glm::vec3(0.0f));
    // The even line of ConcentratedFluxSpreadsExponentially fits: its flux centroid, 3.5 from
    // x̄, is 0.88 of √3σ.
    const BakeData even = lineBake(8);
    std::vector<glm::vec3> evenFlux(15, glm::vec3(0.0f));
    evenFlux[lit] = glm::vec3(1.0f);
    pullFlux(even, evenFlux);
    const NodeSpread evenSpread = nodeSpread(even);
    const Spreads e = pulledSpreads(even, evenSpread, evenFlux);
    EXPECT_TRUE(fitsBoxModel(evenSpread, root, evenFlux[root], e.moment[root]));
    EXPECT_EQ(e.exponential[root], 1);
}

TEST(Pull, ALightlyLimitedNodeKeepsItsLine) {
    // All flux on the last of four surfels: the limiter keeps 5/9 of the fitted gradient,
    // more than kExponentialLimit, so the root stays linear (its reads 0, 1/6, 1/3, 1/2 as in
    // LimitedLinearSpreadStaysNonNegativeAndKeepsTheTotal).
    const BakeData bake = lineBake();
    const NodeSpread spread = nodeSpread(bake);
    const ChannelSpread channel = limitedSpread(spread, 6, 1.0f, glm::vec3(1.5f, 0.0f, 0.0f));
    EXPECT_TRUE(channel.limited);
    EXPECT_FALSE(channel.concentrated);
    std::vector<glm::vec3> flux(7, glm::vec3(0.0f));
    flux[3] = glm::vec3(1.0f);
    pullFlux(bake, flux);
    const Spreads s = pulledSpreads(bake, spread, flux);
    EXPECT_EQ(s.exponential[6], 0);
    EXPECT_NEAR(spreadFlux(spread, s, 6, 3.0f, 0.25f, 0), 0.5f, 1e-5f);
}

TEST(Pull, InverseLangevinInvertsTheMeanOfATiltedInterval) {
    // L(x), the mean of u ∈ [−1, 1] under density ∝ e^{x·u}, by midpoint quadrature (an oracle
    // independent of the closed form coth x − 1/x): inverseLangevin(L(x)) is x within 2 %.
    const auto mean = [](double x) {
        double sum = 0.0, weight = 0.0;
        const int n = 20000;
        for (int i = 0; i < n; ++i) {
            const double u = -1.0 + (i + 0.5) * 2.0 / n, w = std::exp(x * u);
            sum += w * u;
            weight += w;
        }
        return sum / weight;
    };
    for (double x : {-20.0, -6.0, -2.5, -1.0, -0.3, 0.05, 0.4, 1.5, 3.0, 8.0, 30.0}) {
        const double r = mean(x);
        if (std::abs(r) > 0.99) continue;  // beyond the clamp
        EXPECT_NEAR(inverseLangevin(float(r)), x, 0.02 * std::abs(x) + 1e-4) << "r " << r;
    }
    EXPECT_EQ(inverseLangevin(0.0f), 0.0f);
    // Clamped: a centroid at the edge of the support stays finite.
    EXPECT_TRUE(std::isfinite(inverseLangevin(1.0f)));
    EXPECT_EQ(inverseLangevin(1.0f), -inverseLangevin(-1.0f));
}

TEST(Pull, ExponentialSpreadMatchesTheMomentOfAnEvenlySpreadNode) {
    // A node spread evenly over the square [−1, 1]² (variance 1/3 per axis, a = 1) whose flux
    // is Φ·e^{β₀·y} / Z: the fit finds β₀ from the moment alone (within the inverse Langevin
    // approximation's 1.5 %), ln Z = Σ ln(sinh β / β), and a point's read is its density.
    NodeSpread spread;
    spread.centroid = {glm::vec3(0.0f)};
    spread.axes = {glm::mat3(1.0f)};
    spread.inverseVariance = {glm::vec3(3.0f, 3.0f, 0.0f)};
    spread.low = {glm::vec3(-1.0f, -1.0f, 0.0f)};
    spread.high = {glm::vec3(1.0f, 1.0f, 0.0f)};
    for (const glm::vec2 beta0 : {glm::vec2(0.5f, 0.0f), glm::vec2(1.2f, -0.8f), glm::vec2(-2.0f, 0.7f)}) {
        // Σ Φ_s·y_s over a fine grid of the square, Φ = 2.
        const int n = 200;
        double z = 0.0;
        glm::dvec2 first(0.0);
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) {
                const glm::dvec2 y(-1.0 + (i + 0.5) * 2.0 / n, -1.0 + (j + 0.5) * 2.0 / n);
                const double w = std::exp(glm::dot(glm::dvec2(beta0), y));
                z += w;
                first += w * y;
            }
        const float flux = 2.0f;
        const glm::vec3 moment(glm::vec2(first / z) * flux, 0.0f);
        const ExponentialSpread e = exponentialSpread(spread, 0, flux, moment);
        for (int k = 0; k < 2; ++k)
            EXPECT_NEAR(e.slopes[k], beta0[k], 0.02f * std::abs(beta0[k]) + 1e-3f) << "axis " << k;
        EXPECT_EQ(e.slopes.z, 0.0f);  // flat
        const double lnZ = std::log(z / (n * n));
        EXPECT_NEAR(e.concentration, lnZ, 0.03 * lnZ + 1e-4);
        // A point's read, spread share 0: Φ·e^{β₀·y} / Z.
        const glm::vec3 u(0.5f, -0.25f, 0.0f);
        const float read = e.centre * std::exp(glm::dot(e.slopes, u) - e.concentration);
        const float density = flux * std::exp(glm::dot(beta0, glm::vec2(u))) / float(z / (n * n));
        EXPECT_NEAR(read, density, 0.03f * density);
        // The whole node at its centroid, spread share 1: Φ.
        EXPECT_NEAR(e.centre, flux, 1e-5f);
    }
    // Beyond the cap the exponent is scaled to Σ|slopes| = 3; no flux reads nothing.
    const ExponentialSpread capped = exponentialSpread(spread, 0, 1.0f, glm::vec3(0.9f, 0.5f, 0.0f));
    EXPECT_NEAR(std::abs(capped.slopes.x) + std::abs(capped.slopes.y), gpu::kExponentialSpreadCap, 1e-4f);
    EXPECT_GT(capped.slopes.x, capped.slopes.y);
    const ExponentialSpread dark = exponentialSpread(spread, 0, 0.0f, glm::vec3(0.0f));
    EXPECT_EQ(dark.centre, 0.0f);
    EXPECT_EQ(dark.concentration, 0.0f);
}

TEST(Pull, SlopesStayBoundedForAnyFlux) {
    // Random non-negative flux on a 3-D cloud of surfels and on the same cloud flattened:
    // every linear node's every channel keeps Σ|slopes| ≤ 1, so no point of its box reads
    // negative flux, and every exponential one (flat nodes only) Σ|slopes| ≤ 3.
    BakeData bake = lineBake();
    uint32_t state = 12345u;
    const auto next = [&] {
        state = state * 1664525u + 1013904223u;
        return float(state >> 8) / float(1u << 24);
    };
    for (Surfel& s : bake.surfels) s.position = {3.0f * next(), next(), next()};
    const NodeSpread cloud = nodeSpread(bake);
    // And the same cloud flattened, whose limited nodes spread exponentially.
    for (Surfel& s : bake.surfels) s.position.z = 0.0f;
    const NodeSpread flat = nodeSpread(bake);
    EXPECT_FALSE(isFlat(cloud, 6));
    EXPECT_TRUE(isFlat(flat, 6));
    size_t exponentials = 0;
    for (int trial = 0; trial < 200; ++trial) {
        const NodeSpread& spread = trial % 2 ? flat : cloud;
        std::vector<glm::vec3> flux(7);
        for (uint32_t x = 0; x < 4; ++x) {
            const float bright = next() < 0.3f ? 100.0f : 1.0f;
            flux[x] = bright * glm::vec3(next(), next(), next() < 0.5f ? 0.0f : next());
        }
        pullFlux(bake, flux);
        const Spreads s = pulledSpreads(bake, spread, flux);
        for (uint32_t n = 4; n < 7; ++n)
            for (int c = 0; c < 3; ++c) {
                // Linear spreads keep Σ|slopes| ≤ 1; exponential ones ≤ 3 with ln Z in range.
                const glm::vec3 k = s.slopes[n][c];
                const float bound = s.exponential[n] ? gpu::kExponentialSpreadCap : 1.0f;
                EXPECT_LE(std::abs(k.x) + std::abs(k.y) + std::abs(k.z), bound + 1e-5f);
                EXPECT_GE(s.centre[n][c], 0.0f);
                EXPECT_TRUE(std::isfinite(s.centre[n][c]));
                EXPECT_GE(s.concentration[n][c], 0.0f);
                EXPECT_LE(s.concentration[n][c], gpu::kConcentrationRange);
                if (!s.exponential[n]) {
                    EXPECT_EQ(s.concentration[n][c], 0.0f);
                }
                if (trial % 2 == 0 && n == 6) {
                    EXPECT_EQ(s.exponential[n], 0);  // four points off a plane: not flat
                }
                exponentials += s.exponential[n];
            }
    }
    EXPECT_GT(exponentials, 0u);
}

TEST(Pull, BoxPointsRoundTripWithinOneStep) {
    const BakeData bake = lineBake();
    const NodeSpread spread = nodeSpread(bake);
    // The root's box along the line is [0, 3]: a step is 1.5 / 127 m.
    for (float x = 0.0f; x <= 3.0f; x += 0.0625f) {
        const glm::vec3 offset = glm::vec3(x, 0.0f, 0.0f) - spread.centroid[6];
        const glm::vec3 u = decodeBoxPoint(encodeBoxPoint(spread, 6, offset));
        const glm::vec3 exact = boxPoint(spread, 6, x);
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(u[k], exact[k], 0.5f / 127.0f + 1e-6f) << x;
    }
    // Outside the box clamps to its faces; a flat axis, a leaf and a NaN read 0.
    const glm::vec3 far = decodeBoxPoint(encodeBoxPoint(spread, 6, glm::vec3(10.0f, 5.0f, 0.0f)));
    EXPECT_FLOAT_EQ(std::abs(far.x) + std::abs(far.y) + std::abs(far.z), 1.0f);
    EXPECT_EQ(decodeBoxPoint(encodeBoxPoint(spread, 2, glm::vec3(1.0f))), glm::vec3(0.0f));
    EXPECT_EQ(decodeBoxPoint(encodeBoxPoint(spread, 6, glm::vec3(NAN))), glm::vec3(0.0f));
    EXPECT_EQ(encodeBoxPoint(spread, 6, glm::vec3(1.0f)) >> 24, 0u);
}

TEST(Pull, WeightsMoveTheCentroid) {
    // The flux weights are the prior the spread is fitted about.
    BakeData bake = lineBake();
    bake.surfelWeights = {3.0f, 1.0f, 1.0f, 3.0f};
    const NodeSpread spread = nodeSpread(bake);
    EXPECT_NEAR(spread.centroid[4].x, 0.25f, 1e-6f);
    EXPECT_NEAR(spread.centroid[5].x, 2.75f, 1e-6f);
    EXPECT_NEAR(spread.centroid[6].x, 1.5f, 1e-6f);
}

}  // namespace
}  // namespace pic
