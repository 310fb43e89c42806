// Flux weights (bake/surfel_exposure.h): the free distance against a worked integral, the
// weights' normalisation and floor, and the links' factors built from them.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "bake/link_generation.h"
#include "bake/surfel_hierarchy.h"
#include "bake/surfel_exposure.h"
#include "core/color.h"
#include "core/sampling.h"
#include "core/sh.h"
#include "rays/embree_scene.h"
#include "tests/support/baked_scene.h"

namespace pic {
namespace {

/// Adds the rectangle [x0, x1] × [z0, z1] at height y, facing +y (up) or −y.
void addRectangle(Scene& scene, float y, float x0, float x1, float z0, float z1, bool up) {
    const glm::vec3 a(x0, y, z0), b(x1, y, z0), c(x1, y, z1), d(x0, y, z1);
    auto triangle = [&](glm::vec3 p, glm::vec3 q, glm::vec3 r) {
        Triangle t;
        for (int k = 0; k < 3; ++k) {
            Vertex v;
            v.position = k == 0 ? p : k == 1 ? q : r;
            t.v[k] = uint32_t(scene.vertices.size());
            scene.vertices.push_back(v);
            scene.bounds.extend(v.position);
        }
        scene.triangles.push_back(t);
    };
    if (up) {
        triangle(a, d, c);
        triangle(a, c, b);
    } else {
        triangle(a, b, c);
        triangle(a, c, d);
    }
}

/// The square [−h, h]² at height y.
void addSquare(Scene& scene, float y, float h, bool up) { addRectangle(scene, y, -h, h, -h, h, up); }

Surfel surfelAt(glm::vec3 position, glm::vec3 normal) {
    Surfel s{};
    s.position = position;
    s.normal = normal;
    s.area = 1e-4f;
    s.radius = std::sqrt(s.area / std::numbers::pi_v<float>);
    s.albedo = glm::vec3(0.5f);
    return s;
}

TEST(SurfelExposure, FreeDistanceUnderAPlaneIsTwiceItsHeight) {
    // Under a plane at height h, t(θ) = h / cosθ, so E_cos[t] = ∫ (h/cosθ)·cosθ/π dω = 2h over
    // the hemisphere. Plates 200 h wide leave out only directions with tanθ > 100.
    const float h = 0.1f;
    Scene scene;
    scene.sourcePath = "plates.gltf";
    addSquare(scene, 0.0f, 100.0f * h, true);
    addSquare(scene, h, 100.0f * h, false);
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays) << rays.error().message;
    const std::vector<Surfel> surfels = {surfelAt({0.0f, 0.0f, 0.0f}, {0, 1, 0}),
                                         surfelAt({3.0f * h, 0.0f, -h}, {0, 1, 0})};
    auto exposure = surfelExposure(**rays, scene.bounds, 1e3f, surfels, ExposureParams{256, 1});
    ASSERT_TRUE(exposure) << exposure.error().message;
    for (float d : exposure->freeDistance) EXPECT_NEAR(d, 2.0f * h, 0.1f * h);
}

TEST(SurfelView, NearACacheOnlyThePartsOfADiscOnItsSurfaceCount) {
    // A surfel of 6.6 cm radius on a slat 2 cm wide, seen from 7 mm above the slat's plane and
    // 4 cm beside its centre line, over empty space: most of the disc overhangs the slat, and
    // what the cache sees of it is the slat's strip. On a wide plate the whole disc counts.
    const float r = 0.066f;
    Surfel surfel = surfelAt({0.0f, 0.0f, 0.0f}, {0, 1, 0});
    surfel.radius = r;
    surfel.area = std::numbers::pi_v<float> * r * r;
    gpu::Cache cache{};
    cache.position = glm::vec3(0.04f, 0.007f, 0.0f);
    cache.kind = gpu::kCacheKindGrid;
    const float disc = surfelSolidAngle(cache.position, surfel);
    ASSERT_GT(disc, 1.0f);
    for (float halfWidth : {0.01f, 0.5f}) {
        Scene scene;
        scene.sourcePath = "slat.gltf";
        addRectangle(scene, 0.0f, -halfWidth, halfWidth, -0.5f, 0.5f, true);
        auto rays = EmbreeScene::create(scene);
        ASSERT_TRUE(rays) << rays.error().message;
        const SurfelView view = viewSurfel(**rays, cache, surfel);
        EXPECT_TRUE(view.visible);
        if (halfWidth < r) {
            EXPECT_GT(view.solidAngle, 0.0f);
            EXPECT_LT(view.solidAngle, 0.3f * disc);
        } else {
            EXPECT_NEAR(view.solidAngle, disc, 1e-3f * disc);
        }
    }
}

TEST(SurfelExposure, HiddenSurfelsWeighLessAndWeightsAverageOne) {
    // A 2 m floor under a ceiling 2 m up, with a lid 1 cm over its x < 0 half: the surfel under
    // the lid sees about 2 cm of free space, the open one metres.
    Scene scene;
    scene.sourcePath = "lid.gltf";
    addSquare(scene, 0.0f, 1.0f, true);
    addSquare(scene, 2.0f, 1.0f, false);
    addRectangle(scene, 0.01f, -1.0f, 0.0f, -1.0f, 1.0f, false);
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays) << rays.error().message;
    std::vector<Surfel> surfels = {surfelAt({-0.5f, 0.0f, 0.0f}, {0, 1, 0}),
                                   surfelAt({0.5f, 0.0f, 0.0f}, {0, 1, 0})};
    Surfel emitter = surfelAt({0.0f, 1.99f, 0.0f}, {0, -1, 0});
    emitter.emission = glm::vec3(3.0f);
    surfels.push_back(emitter);
    auto exposure = surfelExposure(**rays, scene.bounds, 1e3f, surfels, ExposureParams{64, 1});
    ASSERT_TRUE(exposure);
    const std::vector<float>& free = exposure->freeDistance;
    EXPECT_NEAR(free[0], 0.02f, 0.005f);  // 2h under the lid
    EXPECT_GT(free[1], 1.0f);
    EXPECT_LT(free[1], 4.0f);
    const std::vector<float> w = fluxWeights(surfels, free);
    // Reflectors: E_cos[min(t, R)], scaled to an area-weighted mean of 1; the emitter alone is 1.
    EXPECT_NEAR(w[0] + w[1], 2.0f, 1e-5f);
    EXPECT_NEAR(w[0] / w[1], free[0] / free[1], 1e-4f);
    EXPECT_LT(w[0], 0.05f * w[1]);
    EXPECT_NEAR(w[2], 1.0f, 1e-6f);
}

TEST(SurfelExposure, WeightsHaveAFloorAndNodeAreasSumThem) {
    std::vector<Surfel> surfels = {surfelAt({0, 0, 0}, {0, 1, 0}), surfelAt({1, 0, 0}, {0, 1, 0})};
    surfels[1].area = 3e-4f;
    const std::vector<float> w = fluxWeights(surfels, {0.0f, 2.0f});
    EXPECT_FLOAT_EQ(w[0], kMinFluxWeight);
    EXPECT_NEAR(w[1], 4.0f / 3.0f, 1e-5f);  // Σ w·a = Σ a: w₁·3a = 4a
    std::vector<Node> nodes(3);
    nodes[0].left = nodes[0].right = kNoNode;
    nodes[1].left = nodes[1].right = kNoNode;
    nodes[2].left = 0;
    nodes[2].right = 1;
    const std::vector<double> area = weightedNodeArea(surfels, nodes, w);
    EXPECT_NEAR(area[2], double(w[0]) * surfels[0].area + double(w[1]) * surfels[1].area, 1e-12);
    // No surfel with any light: every weight is 1.
    const std::vector<float> dark = fluxWeights(surfels, {0.0f, 0.0f});
    EXPECT_FLOAT_EQ(dark[0], 1.0f);
    EXPECT_FLOAT_EQ(dark[1], 1.0f);
}

/// Adds the parallelogram o, o + u, o + u + v, o + v, facing u × v.
void addQuad(Scene& scene, glm::vec3 o, glm::vec3 u, glm::vec3 v) {
    const glm::vec3 corners[4] = {o, o + u, o + u + v, o + v};
    const uint32_t first = uint32_t(scene.vertices.size());
    for (const glm::vec3& p : corners) {
        Vertex vertex;
        vertex.position = p;
        scene.vertices.push_back(vertex);
        scene.bounds.extend(p);
    }
    for (const uint32_t c : {1u, 2u}) {
        Triangle t;
        t.v[0] = first;
        t.v[1] = first + c;
        t.v[2] = first + c + 1;
        scene.triangles.push_back(t);
    }
}

/// n × n surfels of grey albedo ρ at the centres of the parallelogram's cells, facing u × v.
void addLattice(std::vector<Surfel>& surfels, glm::vec3 o, glm::vec3 u, glm::vec3 v, int n, float rho) {
    const glm::vec3 normal = glm::normalize(glm::cross(u, v));
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            Surfel s = surfelAt(o + (i + 0.5f) / n * u + (j + 0.5f) / n * v, normal);
            s.area = glm::length(glm::cross(u, v)) / float(n * n);
            s.radius = std::sqrt(s.area / std::numbers::pi_v<float>);
            s.albedo = glm::vec3(rho);
            surfels.push_back(s);
        }
}

/// The six inner faces of the unit cube: origin and edges, each facing into the cube.
struct Face {
    glm::vec3 o, u, v;
};
constexpr Face kCubeFaces[6] = {
    {{0, 0, 0}, {0, 0, 1}, {1, 0, 0}},  // floor, +y
    {{0, 1, 0}, {1, 0, 0}, {0, 0, 1}},  // ceiling, −y
    {{0, 0, 0}, {0, 1, 0}, {0, 0, 1}},  // x = 0, +x
    {{1, 0, 0}, {0, 0, 1}, {0, 1, 0}},  // x = 1, −x
    {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}},  // z = 0, +z
    {{0, 0, 1}, {0, 1, 0}, {1, 0, 0}},  // z = 1, −z
};

TEST(SurfelExposure, BouncesSolveTheTransportBetweenSurfels) {
    // Surfel 0 sees surfel 1 along two of its four rays, the sky along one, and along the last
    // a surface with no surfel (left out); surfel 1 sees surfel 0 all round. E/c = d + bounces:
    // E₀ = d₀ + (2/3)·ρ₁·E₁ and E₁ = d₁ + ρ₀·E₀, so E₀ = (d₀ + (2/3)·ρ₁·d₁) / (1 − (2/3)·ρ₀·ρ₁).
    std::vector<Surfel> surfels = {surfelAt({0, 0, 0}, {0, 1, 0}), surfelAt({0, 1, 0}, {0, -1, 0})};
    surfels[0].albedo = glm::vec3(0.8f);
    surfels[1].albedo = glm::vec3(0.6f);
    SurfelExposure exposure;
    exposure.raysPerSurfel = 4;
    exposure.freeDistance = {1.0f, 2.0f};
    exposure.seen = {1, 1, kRayEscaped, kRayUnresolved, 0, 0, 0, 0};
    const std::vector<float> e = bouncedExposure(surfels, exposure);
    const double e0 = (1.0 + 2.0 / 3.0 * 0.6 * 2.0) / (1.0 - 2.0 / 3.0 * 0.8 * 0.6);
    EXPECT_NEAR(e[0], e0, 1e-4 * e0);
    EXPECT_NEAR(e[1], 2.0 + 0.8 * e0, 1e-4 * e0);
    // Black surfels, or rays that all escape: no bounce.
    surfels[0].albedo = surfels[1].albedo = glm::vec3(0.0f);
    EXPECT_EQ(bouncedExposure(surfels, exposure), std::vector<float>({1.0f, 2.0f}));
}

TEST(SurfelExposure, BouncesKeepTheEnergyOfAClosedBox) {
    // Inside a closed box of albedo ρ every ray hits a wall, and reciprocity (a_s·F_sh =
    // a_h·F_hs) makes each bounce carry ρ times the last over the box's area: the area mean of
    // E/c is 1/(1 − ρ) times that of d. The bounces also even the light out: a floor surfel in
    // a corner, which sees little free space but lit walls all round, gains on one at the
    // centre.
    Scene scene;
    scene.sourcePath = "box.gltf";
    std::vector<Surfel> surfels;
    const int n = 8;
    const float rho = 0.5f;
    for (const Face& f : kCubeFaces) {
        addQuad(scene, f.o, f.u, f.v);
        addLattice(surfels, f.o, f.u, f.v, n, rho);
    }
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays) << rays.error().message;
    auto exposure = surfelExposure(**rays, scene.bounds, 1e3f, surfels, ExposureParams{256, 1});
    ASSERT_TRUE(exposure) << exposure.error().message;
    size_t escaped = 0, unresolved = 0;
    for (uint32_t h : exposure->seen) {
        escaped += h == kRayEscaped;
        unresolved += h == kRayUnresolved;
    }
    EXPECT_LT(escaped, exposure->seen.size() / 1000);
    EXPECT_LT(unresolved, exposure->seen.size() / 1000);
    const std::vector<float> e = bouncedExposure(surfels, *exposure);
    double direct = 0.0, total = 0.0;
    for (size_t i = 0; i < surfels.size(); ++i) {
        direct += exposure->freeDistance[i];
        total += e[i];
    }
    EXPECT_NEAR(total / direct, 1.0 / (1.0 - rho), 0.03 / (1.0 - rho));
    const size_t corner = 0, centre = (n / 2) * n + n / 2;  // floor surfels (0.06, 0, 0.06), (0.56, 0, 0.56)
    const std::vector<float>& d = exposure->freeDistance;
    EXPECT_LT(d[corner], 0.8f * d[centre]);
    EXPECT_GT(e[corner] / e[centre], 1.1f * d[corner] / d[centre]);
}

TEST(SurfelExposure, UnderASlabBouncesStayLow) {
    // A slab 2 cm above the floor of a closed white box (ρ 0.8), its top and underside lined with
    // surfels: the floor under it sees only the underside, which sees only that floor, so with
    // its bounces it stays below a tenth of the open floor, as without them, while the open
    // floor gains from the walls.
    Scene scene;
    scene.sourcePath = "slab_box.gltf";
    std::vector<Surfel> surfels;
    const float rho = 0.8f;
    for (const Face& f : kCubeFaces) {
        addQuad(scene, f.o, f.u, f.v);
        addLattice(surfels, f.o, f.u, f.v, 16, rho);
    }
    const glm::vec3 x(0.5f, 0, 0), z(0, 0, 0.5f);
    addQuad(scene, {0.25f, 0.02f, 0.25f}, x, z);  // underside, −y
    addLattice(surfels, {0.25f, 0.02f, 0.25f}, x, z, 8, rho);
    addQuad(scene, {0.25f, 0.04f, 0.25f}, z, x);  // top, +y
    addLattice(surfels, {0.25f, 0.04f, 0.25f}, z, x, 8, rho);
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays) << rays.error().message;
    auto exposure = surfelExposure(**rays, scene.bounds, 1e3f, surfels, ExposureParams{128, 1});
    ASSERT_TRUE(exposure) << exposure.error().message;
    const std::vector<float> e = bouncedExposure(surfels, *exposure);
    const std::vector<float>& d = exposure->freeDistance;
    // Floor surfel (i, j) of 16 × 16 sits at x = (j + 0.5)/16, z = (i + 0.5)/16.
    const size_t under = 7 * 16 + 7, open = 14 * 16 + 2;
    const size_t top = 6 * 256 + 64 + 3 * 8 + 4;  // on the slab
    EXPECT_LT(d[under], 0.1f * d[open]);
    EXPECT_LT(e[under], 0.1f * e[open]);
    EXPECT_GT(e[open], 2.0f * d[open]);
    // The slab's top reads as lit as the open floor, not as the floor under it.
    EXPECT_GT(e[top], 0.7f * e[open]);
}

TEST(SurfelExposure, LinkFactorsFollowTheWeightsOfTheVisibleSurfels) {
    // Scaling every weight leaves the links alone; doubling the weight of one surfel raises the
    // links that see it and lowers those that do not, by Σ_visible w·Ω / (π Σ w·a).
    const test::BakedScene& b = test::bakedScene("cornell", test::smallBakeOptions(4096, 32, 0.25f, 0.2f));
    ASSERT_TRUE(b.ok);
    const BakeData& bake = b.bake;
    LinkParams params;
    params.linksPerCache = 32;
    std::vector<float> ones(bake.surfels.size(), 1.0f), threes(bake.surfels.size(), 3.0f);
    auto uniform = generateLinks(*b.rays, bake.surfels, bake.nodes, bake.caches, params);
    auto unweighted = generateLinks(*b.rays, bake.surfels, bake.nodes, bake.caches, params, ones);
    auto scaled = generateLinks(*b.rays, bake.surfels, bake.nodes, bake.caches, params, threes);
    ASSERT_TRUE(uniform && unweighted && scaled);
    for (size_t i = 0; i < uniform->links.rtp.size(); i += 13) {
        EXPECT_EQ(uniform->links.rtp[i].node, scaled->links.rtp[i].node);
        EXPECT_NEAR(uniform->links.rtp[i].factor, unweighted->links.rtp[i].factor,
                    1e-5f * uniform->links.rtp[i].factor);
        EXPECT_NEAR(uniform->links.rtp[i].factor, scaled->links.rtp[i].factor,
                    1e-5f * uniform->links.rtp[i].factor);
    }
    // Leaves: the factor is the surfel's own, whatever its weight (Σ_visible w·Ω / (π w·a)).
    // That holds where the leaf's estimate was exact; with more final rays than cut rays a
    // drawn estimate whose visible samples all hit one heavy surfel also reads that leaf
    // (bake/link_generation.cpp, localise), so both counts stay at 16 here.
    params.finalSamplesPerNode = params.samplesPerNode;
    uniform = generateLinks(*b.rays, bake.surfels, bake.nodes, bake.caches, params);
    ASSERT_TRUE(uniform);
    std::vector<float> mixed(bake.surfels.size());
    for (size_t s = 0; s < mixed.size(); ++s) mixed[s] = s % 2 ? 5.0f : 0.5f;
    auto weighted = generateLinks(*b.rays, bake.surfels, bake.nodes, bake.caches, params, mixed);
    ASSERT_TRUE(weighted);
    const size_t nS = bake.surfels.size();
    int leaves = 0;
    for (size_t i = 0; i < uniform->links.rtp.size(); ++i) {
        const RtpLink& a = uniform->links.rtp[i];
        const RtpLink& w = weighted->links.rtp[i];
        if (a.factor == 0.0f || a.node >= nS || a.node != w.node) continue;
        ++leaves;
        EXPECT_NEAR(a.factor, w.factor, 1e-5f * a.factor);
    }
    EXPECT_GT(leaves, 0);
    // Bad weights are refused, naming the surfel.
    mixed[7] = -1.0f;
    auto bad = generateLinks(*b.rays, bake.surfels, bake.nodes, bake.caches, params, mixed);
    ASSERT_FALSE(bad);
    EXPECT_NE(bad.error().message.find("surfel 7"), std::string::npos) << bad.error().message;
}

TEST(LinkReads, ACacheReadsTheSideOfAThinSlabItSees) {
    // A 2 m slab 1 cm thick, 8 × 8 surfels on its top face and on its bottom face, one
    // cluster over both, and a grid cache 1 m above it with one link: paper 000's link reads
    // the cluster's flux, so light under the slab leaks to the cache; a link that reads the
    // visible part reads the top face alone, with the factor doubled (half the area).
    Scene scene;
    scene.sourcePath = "slab.gltf";
    addSquare(scene, 0.005f, 1.0f, true);
    addSquare(scene, -0.005f, 1.0f, false);
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays) << rays.error().message;
    std::vector<Surfel> surfels;
    for (int side = 0; side < 2; ++side)
        for (int i = 0; i < 8; ++i)
            for (int j = 0; j < 8; ++j) {
                const float y = side == 0 ? 0.005f : -0.005f;
                Surfel s = surfelAt({-0.875f + 0.25f * i, y, -0.875f + 0.25f * j},
                                    {0.0f, side == 0 ? 1.0f : -1.0f, 0.0f});
                s.area = 0.0625f;
                s.radius = std::sqrt(s.area / std::numbers::pi_v<float>);
                surfels.push_back(s);
            }
    auto hierarchy = buildHierarchy(surfels, HierarchyParams{.sceneExtent = 2.83f});
    ASSERT_TRUE(hierarchy) << hierarchy.error().message;
    const std::vector<Surfel>& leaves = hierarchy->surfels;
    const std::vector<Node>& nodes = hierarchy->nodes;
    Cache cache{};
    cache.position = glm::vec3(0.1f, 1.0f, -0.2f);
    cache.kind = gpu::kCacheKindGrid;

    LinkParams params;
    params.linksPerCache = 1;
    params.reads = LinkReads::Node;
    auto paper = generateLinks(**rays, leaves, nodes, {cache}, params);
    params.reads = LinkReads::Visible;
    auto visible = generateLinks(**rays, leaves, nodes, {cache}, params);
    ASSERT_TRUE(paper && visible);
    const RtpLink& whole = paper->links.rtp[0];
    const RtpLink& part = visible->links.rtp[0];
    ASSERT_EQ(whole.node, nodes.size() - 1);  // the root: both faces
    const Node& read = nodes[part.node];
    ASSERT_GT(read.surfelCount, 0u);
    bool onlyTop = true;
    for (uint32_t s = read.firstSurfel; s < read.firstSurfel + read.surfelCount; ++s)
        onlyTop = onlyTop && leaves[s].normal.y > 0.0f;
    EXPECT_TRUE(onlyTop);
    EXPECT_EQ(read.surfelCount, 64u);  // the whole top face: the cache sees all of it
    EXPECT_NEAR(part.factor / whole.factor, 2.0f, 1e-5f);

    // Flux on the bottom face only (lit from below): the node-read link carries half of it to
    // the cache, the visible-part link none.
    std::vector<glm::vec3> flux(nodes.size(), glm::vec3(0.0f));
    for (size_t s = 0; s < leaves.size(); ++s)
        if (leaves[s].normal.y < 0.0f) flux[s] = glm::vec3(1.0f);
    for (size_t n = leaves.size(); n < nodes.size(); ++n)
        flux[n] = flux[nodes[n].left] + flux[nodes[n].right];
    EXPECT_GT(flux[whole.node].x * whole.factor, 0.0f);
    EXPECT_EQ(flux[part.node].x * part.factor, 0.0f);
}

TEST(LinkReads, ALinkTakesTheColourOfThePartItSees) {
    // Two places 2.4 m apart on a 1 cm slab, each with a red surfel on top and a white one
    // underneath. The hierarchy pairs each red surfel with the white one under it (their
    // normals differ by 0.2 in the metric, the places by 2.4² / 2.83² = 0.72), so a cache
    // above sees one surfel of each pair and its link reads the root, whose flux is half white
    // when uniform light falls on all four. The visible-part link's tint gives the cache the
    // red it sees: per channel, red ÷ the root's mean albedo; paper 000's link stays neutral.
    const glm::vec3 red(0.8f, 0.1f, 0.1f), white(0.8f);
    Scene scene;
    scene.sourcePath = "slab.gltf";
    addSquare(scene, 0.005f, 1.5f, true);
    addSquare(scene, -0.005f, 1.5f, false);
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays) << rays.error().message;
    std::vector<Surfel> surfels;
    for (const float x : {-1.2f, 1.2f})
        for (const bool top : {true, false}) {
            Surfel s = surfelAt({x, top ? 0.005f : -0.005f, 0.0f}, {0.0f, top ? 1.0f : -1.0f, 0.0f});
            s.albedo = top ? red : white;
            surfels.push_back(s);
        }
    auto hierarchy = buildHierarchy(surfels, HierarchyParams{.sceneExtent = 2.83f});
    ASSERT_TRUE(hierarchy) << hierarchy.error().message;
    const std::vector<Surfel>& leaves = hierarchy->surfels;
    const std::vector<Node>& nodes = hierarchy->nodes;
    const uint32_t root = uint32_t(nodes.size() - 1);
    for (const uint32_t child : {nodes[root].left, nodes[root].right}) {
        ASSERT_EQ(nodes[child].surfelCount, 2u);  // a pair: one red, one white
        const uint32_t first = nodes[child].firstSurfel;
        ASSERT_EQ(leaves[first].position.x, leaves[first + 1].position.x);
    }
    Cache cache{};
    cache.position = glm::vec3(0.1f, 1.0f, 0.3f);
    cache.kind = gpu::kCacheKindGrid;

    LinkParams params;
    params.linksPerCache = 1;
    params.reads = LinkReads::Node;
    auto paper = generateLinks(**rays, leaves, nodes, {cache}, params);
    params.reads = LinkReads::Visible;
    auto visible = generateLinks(**rays, leaves, nodes, {cache}, params);
    ASSERT_TRUE(paper && visible);
    ASSERT_EQ(paper->links.rtp[0].node, root);
    ASSERT_EQ(visible->links.rtp[0].node, root);  // the red surfels are in both children
    EXPECT_EQ(paper->links.tint[0], kNeutralLinkTint);
    const glm::vec3 rootAlbedo = (red + white) * 0.5f;
    const glm::vec3 expected = red / rootAlbedo;  // (1, 0.22, 0.22)
    const glm::vec3 tint = decodeLinkTint(visible->links.tint[0]) *
                           (visible->links.rtp[0].factor / paper->links.rtp[0].factor);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(tint[c], expected[c], 1e-3f) << "channel " << c;

    // Under uniform irradiance E the root's flux is E·a·Σρ: the tinted link carries the red
    // surfels' radiance in every channel, the neutral one the root's mean colour.
    const glm::vec3 rootFlux = leaves[0].area * (2.0f * red + 2.0f * white);
    const glm::vec3 seen = rootFlux * tint;
    EXPECT_NEAR(seen.g / seen.r, red.g / red.r, 1e-3f);
    EXPECT_NEAR(rootFlux.g / rootFlux.r, rootAlbedo.g / rootAlbedo.r, 1e-6f);
}

TEST(LinkReadWeight, IsTheKernelOfTheIrradianceOfTheLumasBands) {
    // Σ_j L_j·k(n·ω_j) must equal the irradiance at n of the lY-band projection of the point
    // radiances L_j at ω_j (core/sh.h shIrradiance): the addition theorem. A grid cache counts
    // every direction once.
    Rng rng(5, 2);
    for (const uint32_t bands : {1u, 2u, 3u, 5u}) {
        const LinkReadWeight weight(bands);
        std::vector<float> sh(size_t(bands) * bands, 0.0f);
        std::vector<glm::vec3> directions;
        std::vector<float> radiance;
        for (int j = 0; j < 12; ++j) {
            directions.push_back(sampleUniformSphere(rng.uniform(), rng.uniform()));
            radiance.push_back(0.2f + rng.uniform());
            float basis[kMaxShBands * kMaxShBands];
            shEvaluate(int(bands), directions.back(), basis);
            for (size_t i = 0; i < sh.size(); ++i) sh[i] += radiance.back() * basis[i];
        }
        for (int k = 0; k < 8; ++k) {
            Cache cache{};
            cache.kind = gpu::kCacheKindLightmap;
            cache.normal = sampleUniformSphere(rng.uniform(), rng.uniform());
            double sum = 0.0;
            for (size_t j = 0; j < directions.size(); ++j) {
                const float w = weight(cache, directions[j]);
                EXPECT_GE(w, 0.0f);
                sum += double(radiance[j]) * w;
            }
            const float expected = shIrradiance(int(bands), sh.data(), cache.normal);
            // Where k < 0 (below the horizon, bands ≥ 4) it is clamped: compare only if none was.
            bool clamped = false;
            for (const glm::vec3& d : directions) clamped = clamped || weight(cache, d) == 0.0f;
            if (!clamped) {
                EXPECT_NEAR(sum, expected, 1e-4 * std::abs(expected) + 1e-5) << bands << " bands";
            }
            cache.kind = gpu::kCacheKindGrid;
            EXPECT_EQ(weight(cache, directions[0]), 1.0f);
        }
    }
}

TEST(LinkReadWeight, ATiltedConeGathersAlongTheNormalWhatItsStripDoes) {
    // A light-map cache facing +z beside a wall: the wall's strip just above the horizon
    // (n·ω from 0.02 to 0.25, 120° of azimuth) is one link. The round cone of its solid angle
    // around its mean direction spreads across n·ω, and k is convex there, so it reads more
    // along n than the strip's directions do. Tilted (alongNormalDirection), the cone's
    // projection gives, at n, the irradiance of the strip's own projection, band 0 unchanged.
    constexpr double kPi = std::numbers::pi;
    const glm::vec3 n(0.0f, 0.0f, 1.0f);
    for (const uint32_t bands : {2u, 3u, 4u}) {
        const LinkReadWeight weight(bands);
        const int count = int(bands * bands);
        std::vector<float> strip(count, 0.0f);
        glm::vec3 directionSum(0.0f);
        double omega = 0.0, along = 0.0;
        float basis[kMaxShBands * kMaxShBands];
        const int rows = 24, columns = 96;
        const double zLow = 0.02, zHigh = 0.25, phi = 2.0 * kPi / 3.0;
        for (int i = 0; i < rows; ++i)
            for (int j = 0; j < columns; ++j) {
                // Equal solid angles: uniform in z and in azimuth.
                const double z = zLow + (i + 0.5) / rows * (zHigh - zLow);
                const double a = -0.5 * phi + (j + 0.5) / columns * phi;
                const double r = std::sqrt(1.0 - z * z);
                const glm::vec3 w(float(r * std::cos(a)), float(r * std::sin(a)), float(z));
                const double dOmega = (zHigh - zLow) * phi / (rows * columns);
                omega += dOmega;
                directionSum += float(dOmega) * w;
                along += dOmega * weight.kernel(z);
                shEvaluate(int(bands), w, basis);
                for (int k = 0; k < count; ++k) strip[k] += float(dOmega) * basis[k];
            }
        const float oneMinusCosAlpha = float(omega / (2.0 * kPi));
        const glm::vec3 mean = glm::normalize(directionSum);
        const double target = along / omega;
        const double x0 = glm::dot(n, mean);
        EXPECT_GT(weight.coneKernel(x0, oneMinusCosAlpha), target * 1.01) << bands << " bands";

        const glm::vec3 tilted = alongNormalDirection(weight, n, mean, oneMinusCosAlpha, target);
        EXPECT_NEAR(glm::length(tilted), 1.0f, 1e-5f);
        EXPECT_NEAR(glm::dot(glm::cross(n, mean), tilted), 0.0f, 1e-5f) << "stays in the plane";
        EXPECT_GE(glm::dot(n, tilted), 0.0f);
        EXPECT_NEAR(weight.coneKernel(glm::dot(n, tilted), oneMinusCosAlpha), target, 1e-5 * target);
        std::vector<float> cone(count, 0.0f);
        shAddCone(int(bands), tilted, oneMinusCosAlpha, 1.0f, cone.data());
        EXPECT_NEAR(cone[0], strip[0], 1e-3f * strip[0]) << "band 0 does not move";
        EXPECT_NEAR(shIrradiance(int(bands), cone.data(), n), shIrradiance(int(bands), strip.data(), n),
                    2e-3f * shIrradiance(int(bands), strip.data(), n))
            << bands << " bands";
        // A cone that already reads its target stays where it is.
        const glm::vec3 same = alongNormalDirection(weight, n, mean, oneMinusCosAlpha,
                                                    weight.coneKernel(x0, oneMinusCosAlpha));
        EXPECT_LT(glm::length(same - mean), 1e-5f);
    }
}

TEST(LinkReads, ALightMapCacheReadsAWallWhereItsNormalGathersItsLight) {
    // A 2 × 2 m wall of 8 × 8 surfels (x = 0, facing +x) and, 0.3 m in front of its foot, a
    // light-map cache facing up and a grid cache at the same place, one link each (the wall,
    // estimated exactly). The grid cache's link reads the wall's spread at the centroid of
    // what it sees, Σ Ω·x / Σ Ω, low on the wall where the solid angle is; the light-map
    // cache's at Σ Ω·k(n·ω)·x / Σ Ω·k, higher, where its normal gathers the wall's light.
    Scene scene;
    scene.sourcePath = "wall.gltf";
    addQuad(scene, {0, 0, -1}, {0, 2, 0}, {0, 0, 2});
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays) << rays.error().message;
    std::vector<Surfel> surfels;
    addLattice(surfels, {0, 0, -1}, {0, 2, 0}, {0, 0, 2}, 8, 0.5f);
    ASSERT_GT(surfels[0].normal.x, 0.0f);
    auto hierarchy = buildHierarchy(surfels, HierarchyParams{.sceneExtent = 2.83f});
    ASSERT_TRUE(hierarchy) << hierarchy.error().message;
    const std::vector<Surfel>& leaves = hierarchy->surfels;
    const std::vector<Node>& nodes = hierarchy->nodes;
    Cache lightmap{};
    lightmap.kind = gpu::kCacheKindLightmap;
    lightmap.position = glm::vec3(0.3f, 0.01f, 0.1f);
    lightmap.normal = glm::vec3(0, 1, 0);
    Cache grid = lightmap;
    grid.kind = gpu::kCacheKindGrid;
    LinkParams params;
    params.linksPerCache = 1;
    auto links = generateLinks(**rays, leaves, nodes, {lightmap, grid}, params);
    ASSERT_TRUE(links) << links.error().message;
    ASSERT_EQ(links->links.rtp[0].node, nodes.size() - 1);
    ASSERT_EQ(links->links.rtp[1].node, nodes.size() - 1);
    // The centroids the links should read at, from every surfel's view (the wall's centroid is
    // its middle, y = 1).
    const LinkReadWeight weight(params.bands);
    const SurfelCells cells = surfelCells(**rays, leaves);
    auto centroid = [&](const Cache& cache) {
        glm::dvec3 sum(0.0);
        double total = 0.0;
        for (size_t i = 0; i < leaves.size(); ++i) {
            const Surfel& s = leaves[i];
            const SurfelView view = viewSurfel(**rays, cache, s, cells.of(i));
            if (!view.visible) continue;
            const double w = double(view.solidAngle) * weight(cache, view.direction);
            sum += w * glm::dvec3(s.position);
            total += w;
        }
        return sum / total;
    };
    auto offsetY = [&](size_t slot) { return halfToFloat(links->links.offset[slot * 3 + 1]); };
    const double lightmapY = centroid(lightmap).y, gridY = centroid(grid).y;
    EXPECT_GT(lightmapY, gridY + 0.1);
    EXPECT_NEAR(offsetY(0), lightmapY - 1.0, 0.01);
    EXPECT_NEAR(offsetY(1), gridY - 1.0, 0.01);
}

TEST(LinkCut, RefinesALargeFarPatchBeforeASmallNearOne) {
    // A cache between two patches of 4 × 4 surfels that subtend about the same solid angle,
    // 0.16 sr: a 0.2 m square 0.5 m above it and a 2 m square 5 m below. The cut refines by
    // Ω·r, the bound on its nodes' model error (bake/link_generation.cpp), so with 8 links
    // the far patch, ten times the radius, takes all but one of them; by Ω alone, paper
    // 000's order, the two would split them about evenly.
    Scene scene;
    scene.sourcePath = "patches.gltf";
    addSquare(scene, 0.5f, 0.1f, false);
    addSquare(scene, -5.0f, 1.0f, true);
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays) << rays.error().message;
    std::vector<Surfel> surfels;
    for (const bool near : {true, false})
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j) {
                const float side = near ? 0.05f : 0.5f;  // surfel spacing, m
                const glm::vec3 at(side * (i - 1.5f), near ? 0.5f : -5.0f, side * (j - 1.5f));
                Surfel s = surfelAt(at, {0.0f, near ? -1.0f : 1.0f, 0.0f});
                s.area = side * side;
                s.radius = std::sqrt(s.area / std::numbers::pi_v<float>);
                surfels.push_back(s);
            }
    auto hierarchy = buildHierarchy(surfels, HierarchyParams{.sceneExtent = 6.0f});
    ASSERT_TRUE(hierarchy) << hierarchy.error().message;
    const std::vector<Surfel>& leaves = hierarchy->surfels;
    const std::vector<Node>& nodes = hierarchy->nodes;
    Cache cache{};
    cache.kind = gpu::kCacheKindGrid;

    // Links of each patch for a cut, and the solid angles they see.
    struct Split {
        int nearLinks = 0, farLinks = 0;
        double nearSolidAngle = 0.0, farSolidAngle = 0.0;
    };
    auto split = [&](LinkCut cut) {
        LinkParams params;
        params.linksPerCache = 8;
        params.cut = cut;
        auto links = generateLinks(**rays, leaves, nodes, {cache}, params);
        EXPECT_TRUE(links) << links.error().message;
        Split result;
        for (uint32_t l = 0; links && l < params.linksPerCache; ++l) {
            const RtpLink& link = links->links.rtp[l];
            EXPECT_GT(link.factor, 0.0f) << "link " << l << " is padding";
            const Node& node = nodes[link.node];
            bool nearNode = true, farNode = true;
            for (uint32_t s = node.firstSurfel; s < node.firstSurfel + node.surfelCount; ++s) {
                nearNode = nearNode && leaves[s].position.y > 0.0f;
                farNode = farNode && leaves[s].position.y < 0.0f;
            }
            EXPECT_TRUE(nearNode || farNode) << "link " << l << " reads both patches";
            (nearNode ? result.nearLinks : result.farLinks) += 1;
            (nearNode ? result.nearSolidAngle : result.farSolidAngle) +=
                links->visibleSolidAngle[l];
        }
        return result;
    };
    const Split error = split(LinkCut::ErrorBound);
    EXPECT_NEAR(error.nearSolidAngle / error.farSolidAngle, 1.0, 0.1);
    EXPECT_EQ(error.nearLinks, 1);
    EXPECT_EQ(error.farLinks, 7);
    const Split paper = split(LinkCut::SolidAngle);
    EXPECT_EQ(paper.nearLinks, 4);
    EXPECT_EQ(paper.farLinks, 4);
}

TEST(SurfelView, PartsOnSurfaceLeaveOutTheOverhang) {
    // A surfel of 10 cm radius in the middle of a 2 m floor lies wholly on it; at the floor's
    // edge half its disc overhangs; on a strip 4 cm wide about a quarter of it lies on the
    // strip (the band's area 2r·w over πr²: 0.25).
    const float r = 0.1f;
    Surfel surfel = surfelAt({0.0f, 0.0f, 0.0f}, {0, 1, 0});
    surfel.radius = r;
    surfel.area = std::numbers::pi_v<float> * r * r;
    Scene floor;
    floor.sourcePath = "floor.gltf";
    addSquare(floor, 0.0f, 1.0f, true);
    auto rays = EmbreeScene::create(floor);
    ASSERT_TRUE(rays) << rays.error().message;
    EXPECT_EQ(surfelPartsOnSurface(**rays, surfel), kDiscParts);
    Surfel atEdge = surfel;
    atEdge.position.x = 1.0f;
    EXPECT_NEAR(float(surfelPartsOnSurface(**rays, atEdge)), 16.0f, 3.0f);
    EXPECT_NEAR(discShareOnSurface(**rays, {surfel, atEdge}), 0.75, 0.05);

    Scene strip;
    strip.sourcePath = "strip.gltf";
    addRectangle(strip, 0.0f, -1.0f, 1.0f, -0.02f, 0.02f, true);
    rays = EmbreeScene::create(strip);
    ASSERT_TRUE(rays) << rays.error().message;
    EXPECT_NEAR(float(surfelPartsOnSurface(**rays, surfel)), 8.0f, 3.0f);
    // Facing down, the surfel finds no surface under it (its floor faces up).
    Surfel flipped = surfel;
    flipped.normal = glm::vec3(0, -1, 0);
    EXPECT_EQ(surfelPartsOnSurface(**rays, flipped), 0u);
}

/// Solid angle (sr) of the rectangle [x0, x1] × [z0, z1] of the plane y = 0 seen from p above
/// it: the four rectangles with a corner under p, each atan(a·b / (h·√(a² + b² + h²))).
double rectangleSolidAngle(const glm::dvec3& p, double x0, double x1, double z0, double z1) {
    auto corner = [&](double a, double b) {
        const double sa = a < 0.0 ? -1.0 : 1.0, sb = b < 0.0 ? -1.0 : 1.0;
        a = std::abs(a), b = std::abs(b);
        return sa * sb * std::atan(a * b / (p.y * std::sqrt(a * a + b * b + p.y * p.y)));
    };
    return corner(x1 - p.x, z1 - p.z) - corner(x0 - p.x, z1 - p.z) - corner(x1 - p.x, z0 - p.z) +
           corner(x0 - p.x, z0 - p.z);
}

TEST(SurfelCells, NearCachesSeeTheWholeSurfaceNotTheDiscsGaps) {
    // Surfels jittered about a 10 cm lattice on a 2 m floor, of equal area: their discs leave
    // gaps and overlap. Caches 0.6–1.4 radii above the floor, where a surfel's gap or overlap
    // fills much of what they see, must find the floor's solid angle. Each surfel's cell
    // (surfelCells) tiles the floor: its points' count times a candidate's square (r/2)² sums
    // to the floor's area.
    Scene scene;
    scene.sourcePath = "floor.gltf";
    addSquare(scene, 0.0f, 1.0f, true);
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays) << rays.error().message;
    Rng rng(3, 1);
    std::vector<Surfel> surfels;
    const float area = 4.0f / 400.0f;
    for (int i = 0; i < 20; ++i)
        for (int j = 0; j < 20; ++j) {
            const glm::vec3 at(-0.95f + 0.1f * float(i) + 0.06f * (rng.uniform() - 0.5f), 0.0f,
                               -0.95f + 0.1f * float(j) + 0.06f * (rng.uniform() - 0.5f));
            Surfel s = surfelAt(at, {0, 1, 0});
            s.area = area;
            s.radius = std::sqrt(area / std::numbers::pi_v<float>);
            surfels.push_back(s);
        }
    const SurfelCells cells = surfelCells(**rays, surfels);
    const float r = surfels[0].radius;
    EXPECT_NEAR(double(cells.points.size()) * 0.25 * r * r, 4.0, 0.2);
    for (const glm::vec3& p : cells.points) {
        EXPECT_LE(std::abs(p.x), 1.0f);
        EXPECT_LE(std::abs(p.z), 1.0f);
        EXPECT_NEAR(p.y, 0.0f, 1e-4f);
    }
    double cellError = 0.0, discError = 0.0;
    const int caches = 64;
    for (int k = 0; k < caches; ++k) {
        gpu::Cache cache{};
        cache.kind = gpu::kCacheKindGrid;
        cache.position = glm::vec3(rng.uniform() - 0.5f, r * (0.6f + 0.8f * rng.uniform()), rng.uniform() - 0.5f);
        double withCells = 0.0, withDiscs = 0.0;
        for (size_t s = 0; s < surfels.size(); ++s) {
            withCells += viewSurfel(**rays, cache, surfels[s], cells.of(s)).solidAngle;
            withDiscs += viewSurfel(**rays, cache, surfels[s]).solidAngle;
        }
        const double exact = rectangleSolidAngle(glm::dvec3(cache.position), -1, 1, -1, 1);
        cellError += std::pow(withCells / exact - 1.0, 2);
        discError += std::pow(withDiscs / exact - 1.0, 2);
    }
    cellError = std::sqrt(cellError / caches);
    discError = std::sqrt(discError / caches);
    // The cells' points lie half a radius apart, coarse for a cache 0.6 radii above them: 5 %
    // RMS here, against the discs' 11 %.
    EXPECT_LT(cellError, 0.06) << "discs " << discError;
    EXPECT_LT(cellError, 0.5 * discError);
}

}  // namespace
}  // namespace pic
