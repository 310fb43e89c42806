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

}  // namespace
}  // namespace pic
