// Solids: closed, consistently wound triangle sets, found by edge pairing.

#include <gtest/gtest.h>

#include <array>

#include "core/solids.h"

namespace pic {
namespace {

/// Appends a quad (two triangles a b c, a c d) with its own four vertices, as exporters
/// write flat-shaded boxes: corners are shared by position only.
void addQuad(Scene& scene, const glm::vec3& a, const glm::vec3& b, const glm::vec3& c,
             const glm::vec3& d) {
    const uint32_t first = uint32_t(scene.vertices.size());
    for (const glm::vec3& p : {a, b, c, d}) {
        Vertex v;
        v.position = p;
        scene.vertices.push_back(v);
        scene.bounds.extend(p);
    }
    scene.triangles.push_back(Triangle{{first, first + 1, first + 2}});
    scene.triangles.push_back(Triangle{{first, first + 2, first + 3}});
}

/// An axis-aligned box from `lo` to `hi`, faces counter-clockwise seen from outside unless
/// `inward`; `skipFace` (0–5) leaves one face out.
void addBox(Scene& scene, const glm::vec3& lo, const glm::vec3& hi, bool inward = false,
            int skipFace = -1) {
    auto corner = [&](int i) {
        return glm::vec3(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z);
    };
    // Each face's corners counter-clockwise seen from outside.
    const std::array<std::array<int, 4>, 6> faces = {{{0, 4, 6, 2},    // −x
                                                      {1, 3, 7, 5},    // +x
                                                      {0, 1, 5, 4},    // −y
                                                      {2, 6, 7, 3},    // +y
                                                      {0, 2, 3, 1},    // −z
                                                      {4, 5, 7, 6}}};  // +z
    for (int f = 0; f < 6; ++f) {
        if (f == skipFace) continue;
        const auto& q = faces[f];
        if (inward)
            addQuad(scene, corner(q[0]), corner(q[3]), corner(q[2]), corner(q[1]));
        else
            addQuad(scene, corner(q[0]), corner(q[1]), corner(q[2]), corner(q[3]));
    }
}

TEST(Solids, AClosedBoxIsOneSolidWoundOutwards) {
    Scene scene;
    addBox(scene, {0, 0, 0}, {1, 2, 3});
    const Solids solids = findSolids(scene);
    ASSERT_EQ(solids.count(), 1u);
    EXPECT_FALSE(solids.inverted[0]);
    for (uint32_t s : solids.solidOf) EXPECT_EQ(s, 0u);
    EXPECT_EQ(solids.bounds[0].min, glm::vec3(0, 0, 0));
    EXPECT_EQ(solids.bounds[0].max, glm::vec3(1, 2, 3));
}

TEST(Solids, ABoxWoundInwardsIsInverted) {
    // A room modelled as a box seen from inside.
    Scene scene;
    addBox(scene, {-2, 0, -2}, {2, 3, 2}, /*inward=*/true);
    const Solids solids = findSolids(scene);
    ASSERT_EQ(solids.count(), 1u);
    EXPECT_TRUE(solids.inverted[0]);
}

TEST(Solids, OpenSurfacesAreNotSolids) {
    Scene scene;
    addBox(scene, {0, 0, 0}, {1, 1, 1}, false, /*skipFace=*/3);  // a box without its lid
    addQuad(scene, {2, 0, 0}, {3, 0, 0}, {3, 0, 1}, {2, 0, 1});     // a lone quad
    const Solids solids = findSolids(scene);
    EXPECT_EQ(solids.count(), 0u);
    for (uint32_t s : solids.solidOf) EXPECT_EQ(s, Solids::kOpen);
}

TEST(Solids, OneFlippedTriangleOpensItsSet) {
    Scene scene;
    addBox(scene, {0, 0, 0}, {1, 1, 1});
    std::swap(scene.triangles[5].v[1], scene.triangles[5].v[2]);
    EXPECT_EQ(findSolids(scene).count(), 0u);
}

TEST(Solids, SeparateBoxesAreSeparateSolidsAndOpenNeighboursStayOpen) {
    Scene scene;
    addBox(scene, {0, 0, 0}, {1, 1, 1});                         // triangles 0–11
    addQuad(scene, {5, 0, 0}, {6, 0, 0}, {6, 0, 1}, {5, 0, 1});  // 12–13
    addBox(scene, {2, 0, 0}, {3, 1, 1}, /*inward=*/true);        // 14–25
    // A box that touches the first at a corner only: edges are not shared, so it stays a
    // separate solid.
    addBox(scene, {1, 1, 1}, {2, 2, 2});  // 26–37
    const Solids solids = findSolids(scene);
    ASSERT_EQ(solids.count(), 3u);
    EXPECT_EQ(solids.solidOf[0], 0u);
    EXPECT_EQ(solids.solidOf[12], Solids::kOpen);
    EXPECT_EQ(solids.solidOf[13], Solids::kOpen);
    EXPECT_EQ(solids.solidOf[14], 1u);
    EXPECT_EQ(solids.solidOf[26], 2u);
    EXPECT_FALSE(solids.inverted[0]);
    EXPECT_TRUE(solids.inverted[1]);
    EXPECT_FALSE(solids.inverted[2]);
    EXPECT_EQ(solids.bounds[1].min, glm::vec3(2, 0, 0));
}

TEST(Solids, ThreeTrianglesOnAnEdgeOpenTheSet) {
    // Two boxes sharing a whole face are a non-manifold union: the face's edges carry
    // four triangles each.
    Scene scene;
    addBox(scene, {0, 0, 0}, {1, 1, 1});
    addBox(scene, {1, 0, 0}, {2, 1, 1});
    EXPECT_EQ(findSolids(scene).count(), 0u);
}

TEST(Solids, DegenerateTrianglesJoinNoSolid) {
    Scene scene;
    addBox(scene, {0, 0, 0}, {1, 1, 1});
    const uint32_t v = scene.triangles[0].v[0];
    scene.triangles.push_back(Triangle{{v, v, scene.triangles[0].v[1]}});
    const Solids solids = findSolids(scene);
    ASSERT_EQ(solids.count(), 1u);
    EXPECT_EQ(solids.solidOf.back(), Solids::kOpen);
}

}  // namespace
}  // namespace pic
