// The pull's CPU twin (render/cpu/pull.h): inner nodes of a three-level hierarchy hold the
// exact sums of their leaves.

#include <gtest/gtest.h>

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

/// The flux the fitted spread of `node` gives the part of it centred at `x` with share `share`
/// of its weight, in channel `c`.
float spreadFlux(const BakeData& bake, const NodeSpread& spread, const std::vector<glm::vec3>& flux,
                 const std::vector<glm::mat3>& gradient, uint32_t node, float x, float share, int c) {
    const glm::vec3 d = glm::vec3(x, 0.0f, 0.0f) - spread.centroid[node];
    return share * flux[node][c] * (1.0f + glm::dot(gradient[node][c], d));
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
    std::vector<glm::mat3> moment(7), gradient(7);
    pullFluxGradients(bake, spread, flux, moment, gradient);
    // M = Σ Φ_s (x_s − 1.5) = 5 in red, −5 in green, 0 in blue.
    EXPECT_NEAR(moment[6][0].x, 5.0f, 1e-5f);
    EXPECT_NEAR(moment[6][1].x, -5.0f, 1e-5f);
    EXPECT_NEAR(moment[6][2].x, 0.0f, 1e-5f);
    for (uint32_t s = 0; s < 4; ++s)
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(spreadFlux(bake, spread, flux, gradient, 6, float(s), 0.25f, c), flux[s][c], 1e-4f)
                << "surfel " << s << " channel " << c;
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(spreadFlux(bake, spread, flux, gradient, 6, 0.5f, 0.5f, c), flux[4][c], 1e-4f);
        EXPECT_NEAR(spreadFlux(bake, spread, flux, gradient, 6, 2.5f, 0.5f, c), flux[5][c], 1e-4f);
    }
    for (uint32_t s = 0; s < 4; ++s) EXPECT_EQ(gradient[s], glm::mat3(0.0f));
}

TEST(Pull, SpreadOfConcentratedFluxStaysNonNegativeAndKeepsTheTotal) {
    // All flux on the last surfel: the fit would go negative at x = 0 (1 − 1.2·1.5 < 0), so the
    // limiter scales the gradient until the spread there is exactly 0.
    const BakeData bake = lineBake();
    std::vector<glm::vec3> flux(7, glm::vec3(0.0f));
    flux[3] = glm::vec3(1.0f);
    pullFlux(bake, flux);
    const NodeSpread spread = nodeSpread(bake);
    std::vector<glm::mat3> moment(7), gradient(7);
    pullFluxGradients(bake, spread, flux, moment, gradient);
    float total = 0.0f;
    for (uint32_t s = 0; s < 4; ++s) {
        const float part = spreadFlux(bake, spread, flux, gradient, 6, float(s), 0.25f, 0);
        EXPECT_GE(part, -1e-6f) << "surfel " << s;
        total += part;
    }
    EXPECT_NEAR(spreadFlux(bake, spread, flux, gradient, 6, 0.0f, 0.25f, 0), 0.0f, 1e-6f);
    EXPECT_NEAR(total, 1.0f, 1e-5f);
    // Still brighter towards the light: 0, 1/6, 1/3, 1/2.
    EXPECT_NEAR(spreadFlux(bake, spread, flux, gradient, 6, 3.0f, 0.25f, 0), 0.5f, 1e-5f);
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
