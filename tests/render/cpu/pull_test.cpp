// The pull's CPU twin (render/cpu/pull.h): inner nodes of a three-level hierarchy hold the
// exact sums of their leaves; the limited flux spread and the box points links read it at.

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/bake_data.h"
#include "render/cpu/pull.h"

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

/// Four unit-area surfels at x = 0, 1, 2, 3 under a balanced hierarchy: leaves 0-3,
/// 4 = (0, 1), 5 = (2, 3), root 6 = (4, 5).
BakeData lineBake() {
    BakeData bake;
    bake.surfels.resize(4);
    for (uint32_t s = 0; s < 4; ++s) {
        bake.surfels[s].position = {float(s), 0.0f, 0.0f};
        bake.surfels[s].area = 1.0f;
    }
    bake.surfelWeights.assign(4, 1.0f);
    bake.nodes.resize(7);
    for (uint32_t s = 0; s < 4; ++s) {
        bake.nodes[s].left = bake.nodes[s].right = kNoNode;
        bake.nodes[s].firstSurfel = s;
        bake.nodes[s].surfelCount = 1;
    }
    const uint32_t children[3][2] = {{0, 1}, {2, 3}, {4, 5}};
    for (uint32_t k = 0; k < 3; ++k) {
        Node& node = bake.nodes[4 + k];
        node.left = children[k][0];
        node.right = children[k][1];
        node.firstSurfel = k == 1 ? 2 : 0;
        node.surfelCount = k == 2 ? 4 : 2;
    }
    bake.levelOffsets = {4, 6, 7};
    return bake;
}

/// A node's limited spreads as pullFluxSpread writes them.
struct Spreads {
    std::vector<glm::mat3> moment, slopes;
    std::vector<glm::vec3> centre;
};

Spreads pulledSpreads(const BakeData& bake, const NodeSpread& spread,
                      const std::vector<glm::vec3>& flux) {
    Spreads out{std::vector<glm::mat3>(flux.size()), std::vector<glm::mat3>(flux.size()),
                std::vector<glm::vec3>(flux.size())};
    pullFluxSpread(bake, spread, flux, out.moment, out.centre, out.slopes);
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

/// The flux the limited spread of `node` gives the part of it centred at `x` with share `share`
/// of its weight, in channel `c`.
float spreadFlux(const NodeSpread& spread, const Spreads& s, uint32_t node, float x, float share,
                 int c) {
    return share * s.centre[node][c] *
           (1.0f + glm::dot(s.slopes[node][c], boxPoint(spread, node, x)));
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

TEST(Pull, SpreadOfConcentratedFluxStaysNonNegativeAndKeepsTheTotal) {
    // All flux on the last surfel: the fit would go negative at x = 0 (1 − 1.2·1.5 < 0), so the
    // limiter scales the gradient until the spread there is exactly 0.
    const BakeData bake = lineBake();
    std::vector<glm::vec3> flux(7, glm::vec3(0.0f));
    flux[3] = glm::vec3(1.0f);
    pullFlux(bake, flux);
    const NodeSpread spread = nodeSpread(bake);
    const Spreads s = pulledSpreads(bake, spread, flux);
    float total = 0.0f;
    for (uint32_t x = 0; x < 4; ++x) {
        const float part = spreadFlux(spread, s, 6, float(x), 0.25f, 0);
        EXPECT_GE(part, -1e-6f) << "surfel " << x;
        total += part;
    }
    EXPECT_NEAR(spreadFlux(spread, s, 6, 0.0f, 0.25f, 0), 0.0f, 1e-6f);
    EXPECT_NEAR(total, 1.0f, 1e-5f);
    // Still brighter towards the light: 0, 1/6, 1/3, 1/2.
    EXPECT_NEAR(spreadFlux(spread, s, 6, 3.0f, 0.25f, 0), 0.5f, 1e-5f);
    // Non-negative over the whole box is Σ|slopes| ≤ 1; here the far end reads exactly 0.
    const glm::vec3 slopes = s.slopes[6][0];
    EXPECT_NEAR(std::abs(slopes.x) + std::abs(slopes.y) + std::abs(slopes.z), 1.0f, 1e-5f);
}

TEST(Pull, SlopesStayWithinTheUnitBallForAnyFlux) {
    // Random non-negative flux on a 3-D cloud of surfels: every node's every channel keeps
    // Σ|slopes| ≤ 1, so no point of its box reads negative flux.
    BakeData bake = lineBake();
    uint32_t state = 12345u;
    const auto next = [&] {
        state = state * 1664525u + 1013904223u;
        return float(state >> 8) / float(1u << 24);
    };
    for (Surfel& s : bake.surfels) s.position = {3.0f * next(), next(), 0.2f * next()};
    const NodeSpread spread = nodeSpread(bake);
    for (int trial = 0; trial < 200; ++trial) {
        std::vector<glm::vec3> flux(7);
        for (uint32_t x = 0; x < 4; ++x) {
            const float bright = next() < 0.3f ? 100.0f : 1.0f;
            flux[x] = bright * glm::vec3(next(), next(), next() < 0.5f ? 0.0f : next());
        }
        pullFlux(bake, flux);
        const Spreads s = pulledSpreads(bake, spread, flux);
        for (uint32_t n = 4; n < 7; ++n)
            for (int c = 0; c < 3; ++c) {
                const glm::vec3 k = s.slopes[n][c];
                EXPECT_LE(std::abs(k.x) + std::abs(k.y) + std::abs(k.z), 1.0f + 1e-6f);
                EXPECT_GE(s.centre[n][c], 0.0f);
            }
    }
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
