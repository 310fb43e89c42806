#include "bake/surfel_hierarchy.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <numbers>
#include <set>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "bake/surfel_placement.h"
#include "core/parallel.h"
#include "rays/embree_scene.h"
#include "tests/support/baked_scene.h"

namespace pic {
namespace {

constexpr HierarchyMethod kMethods[] = {HierarchyMethod::Agglomerative, HierarchyMethod::KdTree};

const char* methodName(HierarchyMethod method) {
    return method == HierarchyMethod::KdTree ? "kd-tree" : "agglomerative";
}

// Uniform float in [0, 1) from a counter (splitmix64), the same on every platform.
float random01(uint64_t counter) {
    uint64_t z = counter * 0x9e3779b97f4a7c15ull + 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return static_cast<float>(z >> 40) * 0x1p-24f;
}

// A surfel whose `triangle` field carries its input index, to follow it through reordering.
Surfel makeSurfel(glm::vec3 position, glm::vec3 normal, float area, uint32_t index) {
    Surfel s{};
    s.position = position;
    s.area = area;
    s.normal = normal;
    s.radius = std::sqrt(area / std::numbers::pi_v<float>);
    s.albedo = glm::vec3(0.5f);
    s.triangle = index;
    return s;
}

// Jittered k × k samples on each face of the box [0, 1]³ with outward normals, equal areas.
std::vector<Surfel> boxSurfels(uint32_t k) {
    std::vector<Surfel> surfels;
    const float area = 1.0f / static_cast<float>(k * k);
    for (uint32_t face = 0; face < 6; ++face) {
        int axis = static_cast<int>(face / 2);
        float side = face % 2 ? 1.0f : 0.0f;
        glm::vec3 normal(0.0f);
        normal[axis] = face % 2 ? 1.0f : -1.0f;
        for (uint32_t v = 0; v < k; ++v) {
            for (uint32_t u = 0; u < k; ++u) {
                auto index = static_cast<uint32_t>(surfels.size());
                glm::vec3 p;
                p[axis] = side;
                p[(axis + 1) % 3] = (static_cast<float>(u) + random01(2 * index)) / k;
                p[(axis + 2) % 3] = (static_cast<float>(v) + random01(2 * index + 1)) / k;
                surfels.push_back(makeSurfel(p, normal, area, index));
            }
        }
    }
    return surfels;
}

// `count` surfels at uniformly random positions on the faces of the box [0, 1]³.
std::vector<Surfel> randomBoxSurfels(uint32_t count) {
    std::vector<Surfel> surfels(count);
    const float area = 6.0f / static_cast<float>(count);
    for (uint32_t i = 0; i < count; ++i) {
        uint32_t face = i % 6;
        int axis = static_cast<int>(face / 2);
        glm::vec3 normal(0.0f);
        normal[axis] = face % 2 ? 1.0f : -1.0f;
        glm::vec3 p;
        p[axis] = face % 2 ? 1.0f : 0.0f;
        p[(axis + 1) % 3] = random01(2 * uint64_t{i});
        p[(axis + 2) % 3] = random01(2 * uint64_t{i} + 1);
        surfels[i] = makeSurfel(p, normal, area, i);
    }
    return surfels;
}

// A 1 m × 1 m wall 1 cm thick: k × k jittered surfels on each side, the −z side first.
std::vector<Surfel> thinWallSurfels(uint32_t k) {
    std::vector<Surfel> surfels;
    const float area = 1.0f / static_cast<float>(k * k);
    for (int side = 0; side < 2; ++side) {
        for (uint32_t v = 0; v < k; ++v) {
            for (uint32_t u = 0; u < k; ++u) {
                auto index = static_cast<uint32_t>(surfels.size());
                glm::vec3 p((static_cast<float>(u) + random01(2 * index)) / k,
                            (static_cast<float>(v) + random01(2 * index + 1)) / k,
                            side ? 0.01f : 0.0f);
                surfels.push_back(
                    makeSurfel(p, glm::vec3(0.0f, 0.0f, side ? 1.0f : -1.0f), area, index));
            }
        }
    }
    return surfels;
}

float diagonal(const std::vector<Surfel>& surfels) {
    glm::vec3 lo(1e30f), hi(-1e30f);
    for (const Surfel& s : surfels) {
        lo = glm::min(lo, s.position);
        hi = glm::max(hi, s.position);
    }
    return std::max(glm::length(hi - lo), 1e-3f);
}

SurfelHierarchy build(const std::vector<Surfel>& surfels, HierarchyParams params) {
    Result<SurfelHierarchy> hierarchy = buildHierarchy(surfels, params);
    EXPECT_TRUE(hierarchy.has_value()) << (hierarchy ? "" : hierarchy.error().message);
    return hierarchy ? std::move(*hierarchy) : SurfelHierarchy{};
}

SurfelHierarchy build(const std::vector<Surfel>& surfels, HierarchyMethod method) {
    HierarchyParams params;
    params.method = method;
    params.sceneExtent = diagonal(surfels);
    return build(surfels, params);
}

uint32_t depth(const SurfelHierarchy& h) {
    return h.nodes.back().level;
}

// Checks every invariant of bake_layout.h against brute-force recomputation from the
// surfels each node covers.
void expectValidHierarchy(const SurfelHierarchy& h, const std::vector<Surfel>& input) {
    const auto nS = static_cast<uint32_t>(input.size());
    ASSERT_EQ(h.surfels.size(), nS);
    ASSERT_EQ(h.nodes.size(), 2 * size_t{nS} - 1);

    // The surfels are a permutation of the input, and leaf i is surfel i.
    std::vector<int> seen(nS, 0);
    for (uint32_t i = 0; i < nS; ++i) {
        const Surfel& s = h.surfels[i];
        ASSERT_LT(s.triangle, nS);
        ++seen[s.triangle];
        EXPECT_EQ(std::memcmp(&s, &input[s.triangle], sizeof(Surfel)), 0) << "surfel " << i;
        const Node& leaf = h.nodes[i];
        EXPECT_EQ(leaf.left, kNoNode);
        EXPECT_EQ(leaf.right, kNoNode);
        EXPECT_EQ(leaf.firstSurfel, i);
        EXPECT_EQ(leaf.surfelCount, 1u);
        EXPECT_EQ(leaf.level, 0u);
        EXPECT_EQ(leaf.center, s.position);
        EXPECT_EQ(leaf.normal, s.normal);
        EXPECT_EQ(leaf.area, s.area);
        EXPECT_EQ(leaf.radius, s.radius);
    }
    for (uint32_t t = 0; t < nS; ++t) EXPECT_EQ(seen[t], 1) << "input surfel " << t;

    // Levels are contiguous, ascending and described by levelOffsets.
    ASSERT_FALSE(h.levelOffsets.empty());
    EXPECT_EQ(h.levelOffsets.front(), nS);
    EXPECT_EQ(h.levelOffsets.back(), h.nodes.size());
    for (size_t k = 1; k < h.levelOffsets.size(); ++k) {
        ASSERT_LT(h.levelOffsets[k - 1], h.levelOffsets[k]) << "empty level " << k;
        for (uint32_t i = h.levelOffsets[k - 1]; i < h.levelOffsets[k]; ++i)
            EXPECT_EQ(h.nodes[i].level, k) << "node " << i;
    }

    // Tree structure: children precede parents, ranges are the union of the children's.
    const uint32_t root = static_cast<uint32_t>(h.nodes.size()) - 1;
    EXPECT_EQ(h.nodes[root].parent, kNoNode);
    EXPECT_EQ(h.nodes[root].firstSurfel, 0u);
    EXPECT_EQ(h.nodes[root].surfelCount, nS);
    for (uint32_t i = 0; i < root; ++i) {
        uint32_t parent = h.nodes[i].parent;
        ASSERT_TRUE(parent > i && parent <= root) << "node " << i << " parent " << parent;
        EXPECT_TRUE(h.nodes[parent].left == i || h.nodes[parent].right == i) << "node " << i;
    }
    for (uint32_t i = nS; i <= root; ++i) {
        const Node& node = h.nodes[i];
        ASSERT_LT(node.left, i);
        ASSERT_LT(node.right, i);
        const Node& left = h.nodes[node.left];
        const Node& right = h.nodes[node.right];
        EXPECT_EQ(node.level, 1 + std::max(left.level, right.level)) << "node " << i;
        EXPECT_EQ(node.firstSurfel, left.firstSurfel) << "node " << i;
        EXPECT_EQ(right.firstSurfel, left.firstSurfel + left.surfelCount) << "node " << i;
        EXPECT_EQ(node.surfelCount, left.surfelCount + right.surfelCount) << "node " << i;
        EXPECT_NEAR(node.area, left.area + right.area, 1e-6f * node.area) << "node " << i;
    }

    // Geometry against the node's own surfels: area sum, area-weighted centre and normal,
    // and a radius enclosing every surfel disc.
    for (uint32_t i = nS; i <= root; ++i) {
        const Node& node = h.nodes[i];
        double area = 0.0;
        glm::dvec3 center(0.0), normal(0.0);
        for (uint32_t s = node.firstSurfel; s < node.firstSurfel + node.surfelCount; ++s) {
            area += h.surfels[s].area;
            center += double{h.surfels[s].area} * glm::dvec3(h.surfels[s].position);
            normal += double{h.surfels[s].area} * glm::dvec3(h.surfels[s].normal);
        }
        center /= area;
        EXPECT_NEAR(node.area, area, 1e-5 * area) << "node " << i;
        EXPECT_LT(glm::length(glm::dvec3(node.center) - center), 1e-5) << "node " << i;
        double normalLength = glm::length(normal) / area;
        if (normalLength > 1e-3) {
            EXPECT_LT(glm::length(glm::dvec3(node.normal) - normal / glm::length(normal)), 1e-4)
                << "node " << i;
        } else if (normalLength < 1e-5) {
            EXPECT_EQ(node.normal, glm::vec3(0.0f)) << "node " << i;
        }
        for (uint32_t s = node.firstSurfel; s < node.firstSurfel + node.surfelCount; ++s) {
            float reach = glm::length(h.surfels[s].position - node.center) + h.surfels[s].radius;
            ASSERT_LE(reach, node.radius * (1.0f + 1e-5f) + 1e-6f)
                << "node " << i << " surfel " << s;
        }
    }
}

TEST(SurfelHierarchy, RejectsInvalidInput) {
    auto expectError = [](const std::vector<Surfel>& surfels, const HierarchyParams& params,
                          const char* fragment) {
        Result<SurfelHierarchy> h = buildHierarchy(surfels, params);
        ASSERT_FALSE(h.has_value()) << fragment;
        EXPECT_EQ(h.error().code, ErrorCode::InvalidInput);
        EXPECT_NE(h.error().message.find(fragment), std::string::npos) << h.error().message;
    };
    const HierarchyParams params;
    expectError({}, params, "no surfels");

    std::vector<Surfel> surfels = boxSurfels(2);
    auto with = [&](size_t i, auto edit) {
        std::vector<Surfel> bad = surfels;
        edit(bad[i]);
        return bad;
    };
    expectError(with(5, [](Surfel& s) { s.position.y = std::nanf(""); }), params, "surfel 5");
    expectError(with(3, [](Surfel& s) { s.area = 0.0f; }), params, "area 0");
    expectError(with(7, [](Surfel& s) { s.radius = -1.0f; }), params, "radius -1");
    expectError(with(2, [](Surfel& s) { s.normal = glm::vec3(0.0f, 2.0f, 0.0f); }), params,
                "(0, 2, 0)");

    HierarchyParams bad = params;
    bad.sceneExtent = 0.0f;
    expectError(surfels, bad, "scene extent 0");
    bad = params;
    bad.normalWeight = -1.0f;
    expectError(surfels, bad, "C_n = -1");
    bad = params;
    bad.balanceWeight = std::numeric_limits<float>::infinity();
    expectError(surfels, bad, "C_b = inf");
    bad = params;
    bad.method = static_cast<HierarchyMethod>(7);
    expectError(surfels, bad, "unknown method 7");
    bad = params;
    bad.sceneExtent = 1e-30f;
    expectError(surfels, bad, "scene extent");
}

TEST(SurfelHierarchy, SingleSurfelIsRootLeaf) {
    std::vector<Surfel> one{makeSurfel({1, 2, 3}, {0, 1, 0}, 0.25f, 0)};
    for (HierarchyMethod method : kMethods) {
        SCOPED_TRACE(methodName(method));
        SurfelHierarchy h = build(one, method);
        expectValidHierarchy(h, one);
        ASSERT_EQ(h.nodes.size(), 1u);
        EXPECT_EQ(h.nodes[0].parent, kNoNode);
        EXPECT_EQ(h.levelOffsets, std::vector<uint32_t>{1});
    }
}

TEST(SurfelHierarchy, TinyInputs) {
    std::vector<Surfel> surfels{makeSurfel({0, 0, 0}, {0, 0, 1}, 0.01f, 0),
                                makeSurfel({1, 0, 0}, {0, 0, 1}, 0.01f, 1),
                                makeSurfel({0.9f, 0, 0}, {0, 0, 1}, 0.01f, 2)};
    for (HierarchyMethod method : kMethods) {
        SCOPED_TRACE(methodName(method));
        std::vector<Surfel> two(surfels.begin(), surfels.begin() + 2);
        SurfelHierarchy h2 = build(two, method);
        expectValidHierarchy(h2, two);
        EXPECT_EQ(h2.levelOffsets, (std::vector<uint32_t>{2, 3}));
        EXPECT_EQ(h2.nodes[2].center, glm::vec3(0.5f, 0.0f, 0.0f));
        EXPECT_FLOAT_EQ(h2.nodes[2].radius, 0.5f + surfels[0].radius);

        // Both methods pair the two close surfels first; the far one joins at the root.
        SurfelHierarchy h3 = build(surfels, method);
        expectValidHierarchy(h3, surfels);
        EXPECT_EQ(h3.levelOffsets, (std::vector<uint32_t>{3, 4, 5}));
        const Node& pair = h3.nodes[3];
        EXPECT_EQ(pair.surfelCount, 2u);
        for (uint32_t s = pair.firstSurfel; s < pair.firstSurfel + 2; ++s)
            EXPECT_NE(h3.surfels[s].triangle, 0u);
    }
}

// Surfel input indices (triangle field) of the two children of the root.
std::pair<std::vector<uint32_t>, std::vector<uint32_t>> rootSplit(const SurfelHierarchy& h) {
    auto members = [&](uint32_t node) {
        std::vector<uint32_t> ids;
        const Node& n = h.nodes[node];
        for (uint32_t s = n.firstSurfel; s < n.firstSurfel + n.surfelCount; ++s)
            ids.push_back(h.surfels[s].triangle);
        std::sort(ids.begin(), ids.end());
        return ids;
    };
    auto split = std::pair{members(h.nodes.back().left), members(h.nodes.back().right)};
    if (split.first.front() > split.second.front()) std::swap(split.first, split.second);
    return split;
}

TEST(SurfelHierarchy, MetricNormalTermSeparatesOppositeFaces) {
    // a, b 1 cm apart facing away from each other; c, d the same 20 cm further along x.
    std::vector<Surfel> surfels{makeSurfel({0.0f, 0, 0}, {0, 0, 1}, 0.01f, 0),
                                makeSurfel({0.01f, 0, 0}, {0, 0, -1}, 0.01f, 1),
                                makeSurfel({0.2f, 0, 0}, {0, 0, 1}, 0.01f, 2),
                                makeSurfel({0.21f, 0, 0}, {0, 0, -1}, 0.01f, 3)};
    HierarchyParams params;
    // d(a, c) = 0.04 beats d(a, b) = 1e-4 + 2 C_n for C_n = 0.1, not for C_n = 0.
    auto [first, second] = rootSplit(build(surfels, params));
    EXPECT_EQ(first, (std::vector<uint32_t>{0, 2}));
    EXPECT_EQ(second, (std::vector<uint32_t>{1, 3}));
    params.normalWeight = 0.0f;
    std::tie(first, second) = rootSplit(build(surfels, params));
    EXPECT_EQ(first, (std::vector<uint32_t>{0, 1}));
    EXPECT_EQ(second, (std::vector<uint32_t>{2, 3}));
}

TEST(SurfelHierarchy, MetricBalanceTermPrefersEqualSizes) {
    // {a, b} and {c, d} form first (d = 0.01); then d({ab}, {cd}) = 0.09 against
    // d({cd}, e) = 0.04 + C_b / 2, so e joins {c, d} unless C_b > 0.1.
    std::vector<Surfel> surfels;
    for (float x : {0.0f, 0.1f, 0.3f, 0.4f, 0.55f})
        surfels.push_back(
            makeSurfel({x, 0, 0}, {0, 1, 0}, 0.01f, static_cast<uint32_t>(surfels.size())));
    HierarchyParams params;
    params.balanceWeight = 0.0f;
    auto [first, second] = rootSplit(build(surfels, params));
    EXPECT_EQ(first, (std::vector<uint32_t>{0, 1}));
    EXPECT_EQ(second, (std::vector<uint32_t>{2, 3, 4}));
    params.balanceWeight = 0.2f;
    std::tie(first, second) = rootSplit(build(surfels, params));
    EXPECT_EQ(first, (std::vector<uint32_t>{0, 1, 2, 3}));
    EXPECT_EQ(second, (std::vector<uint32_t>{4}));
}

TEST(SurfelHierarchy, BoxIsValidAndBalanced) {
    std::vector<Surfel> surfels = boxSurfels(24);
    const double log2n = std::log2(static_cast<double>(surfels.size()));
    for (HierarchyMethod method : kMethods) {
        SCOPED_TRACE(methodName(method));
        SurfelHierarchy h = build(surfels, method);
        expectValidHierarchy(h, surfels);
        EXPECT_LT(depth(h), 4.0 * log2n);
        if (method == HierarchyMethod::KdTree) {
            EXPECT_EQ(depth(h), static_cast<uint32_t>(std::ceil(log2n)));
        }
        std::printf("[ box %zu surfels ] %s depth %u (log2 nS = %.1f)\n", surfels.size(),
                    methodName(method), depth(h), log2n);
    }
}

TEST(SurfelHierarchy, KdTreeSplitsAlongLargestExtent) {
    // Surfels spread 4 m along x and 10 cm along y: the root splits x at the median.
    std::vector<Surfel> surfels;
    for (uint32_t i = 0; i < 64; ++i)
        surfels.push_back(
            makeSurfel({4.0f * random01(i), 0.1f * random01(100 + i), 0.0f}, {0, 0, 1}, 0.01f, i));
    HierarchyParams params;
    params.method = HierarchyMethod::KdTree;
    SurfelHierarchy h = build(surfels, params);
    expectValidHierarchy(h, surfels);
    const Node& left = h.nodes[h.nodes.back().left];
    const Node& right = h.nodes[h.nodes.back().right];
    ASSERT_EQ(left.surfelCount, 32u);
    ASSERT_EQ(right.surfelCount, 32u);
    float leftMax = -1.0f;
    float rightMin = 1e30f;
    for (uint32_t s = left.firstSurfel; s < left.firstSurfel + 32; ++s)
        leftMax = std::max(leftMax, h.surfels[s].position.x);
    for (uint32_t s = right.firstSurfel; s < right.firstSurfel + 32; ++s)
        rightMin = std::min(rightMin, h.surfels[s].position.x);
    EXPECT_LT(leftMax, rightMin);
}

TEST(SurfelHierarchy, ThinWallSidesStaySeparate) {
    // Same-side neighbours are ~3 cm apart, the other side only 1 cm: only the normal term
    // keeps the sides apart.
    constexpr uint32_t k = 32;
    std::vector<Surfel> surfels = thinWallSurfels(k);
    const uint32_t perSide = k * k;
    HierarchyParams params;
    params.sceneExtent = diagonal(surfels);

    // backSide[i]: how many of the first i surfels (in leaf order) lie on the +z side.
    auto countMixed = [&](const SurfelHierarchy& h, uint32_t maxCount, uint32_t& largestPure) {
        std::vector<uint32_t> backSide(h.surfels.size() + 1, 0);
        for (size_t i = 0; i < h.surfels.size(); ++i)
            backSide[i + 1] = backSide[i] + (h.surfels[i].triangle >= perSide ? 1 : 0);
        uint32_t mixed = 0;
        largestPure = 0;
        for (const Node& node : h.nodes) {
            uint32_t back =
                backSide[node.firstSurfel + node.surfelCount] - backSide[node.firstSurfel];
            bool pure = back == 0 || back == node.surfelCount;
            if (!pure && node.surfelCount <= maxCount) ++mixed;
            if (pure) largestPure = std::max(largestPure, node.surfelCount);
        }
        return mixed;
    };

    SurfelHierarchy h = build(surfels, params);
    expectValidHierarchy(h, surfels);
    uint32_t largestPure = 0;
    EXPECT_EQ(countMixed(h, 64, largestPure), 0u);
    EXPECT_GE(largestPure, perSide / 2);
    uint32_t mixedAnywhere = countMixed(h, 2 * perSide, largestPure);
    std::printf("[ thin wall ] mixed nodes %u of %zu, largest one-sided node %u of %u\n",
                mixedAnywhere, h.nodes.size() - surfels.size(), largestPure, perSide);

    // Without the normal term most pairs straddle the wall.
    params.normalWeight = 0.0f;
    SurfelHierarchy blind = build(surfels, params);
    EXPECT_GT(countMixed(blind, 2, largestPure), perSide / 2);
}

TEST(SurfelHierarchy, DeterministicAcrossWorkerCounts) {
    std::vector<Surfel> surfels = boxSurfels(40);
    for (HierarchyMethod method : kMethods) {
        SCOPED_TRACE(methodName(method));
        setWorkerCount(1);
        SurfelHierarchy reference = build(surfels, method);
        for (int workers : {2, 0}) {
            setWorkerCount(workers);
            SurfelHierarchy h = build(surfels, method);
            ASSERT_EQ(h.nodes.size(), reference.nodes.size());
            EXPECT_EQ(
                std::memcmp(h.nodes.data(), reference.nodes.data(), h.nodes.size() * sizeof(Node)),
                0)
                << workers << " workers";
            EXPECT_EQ(std::memcmp(h.surfels.data(), reference.surfels.data(),
                                  h.surfels.size() * sizeof(Surfel)),
                      0)
                << workers << " workers";
            EXPECT_EQ(h.levelOffsets, reference.levelOffsets);
        }
    }
    setWorkerCount(0);
}

TEST(SurfelHierarchy, Builds128kSurfels) {
    std::vector<Surfel> surfels = randomBoxSurfels(128 * 1024);
    for (HierarchyMethod method : kMethods) {
        SCOPED_TRACE(methodName(method));
        auto start = std::chrono::steady_clock::now();
        SurfelHierarchy h = build(surfels, method);
        double seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::printf("[ 128k surfels ] %s: %.3f s on %d workers, depth %u\n", methodName(method),
                    seconds, workerCount(), depth(h));
        expectValidHierarchy(h, surfels);
    }
}

TEST(SurfelHierarchy, EmittersOfEachMaterialStayInNodesOfTheirOwn) {
    // A ceiling of 24 × 24 reflector surfels, with two emissive panels of different materials
    // 1 mm under it, interleaved with it in space: only the nodes that join the three classes
    // (two of them, the root among them) may hold surfels of more than one.
    std::vector<Surfel> surfels;
    for (uint32_t v = 0; v < 24; ++v)
        for (uint32_t u = 0; u < 24; ++u)
            surfels.push_back(makeSurfel({u / 24.0f, 1.0f, v / 24.0f}, {0, -1, 0}, 1.0f / 576.0f,
                                         uint32_t(surfels.size())));
    for (uint32_t panel = 0; panel < 2; ++panel)
        for (uint32_t v = 0; v < 6; ++v)
            for (uint32_t u = 0; u < 6; ++u) {
                Surfel s = makeSurfel({0.1f + 0.5f * panel + u / 48.0f, 0.999f, 0.4f + v / 48.0f},
                                      {0, -1, 0}, 1.0f / 576.0f, uint32_t(surfels.size()));
                s.material = 1 + panel;
                s.emission = glm::vec3(5.0f);
                surfels.push_back(s);
            }
    // Both methods: the agglomerative metric's class penalty, the kd-tree's trees per class.
    for (const HierarchyMethod method : {HierarchyMethod::Agglomerative, HierarchyMethod::KdTree}) {
        SCOPED_TRACE(method == HierarchyMethod::KdTree ? "kd-tree" : "agglomerative");
        HierarchyParams params;
        params.method = method;
        params.sceneExtent = std::sqrt(2.0f);
        auto hierarchy = buildHierarchy(surfels, params);
        ASSERT_TRUE(hierarchy) << hierarchy.error().message;
        const std::vector<Node>& nodes = hierarchy->nodes;
        int mixed = 0;
        for (const Node& node : nodes) {
            std::set<uint32_t> classes;
            for (uint32_t s = node.firstSurfel; s < node.firstSurfel + node.surfelCount; ++s) {
                const Surfel& surfel = hierarchy->surfels[s];
                classes.insert(surfel.emission.r > 0.0f ? surfel.material : 0xFFFFu);
            }
            mixed += classes.size() > 1;
        }
        EXPECT_EQ(mixed, 2);
    }
}

}  // namespace
}  // namespace pic

namespace pic {
namespace {

// thin_wall's two rooms (tests/scenes: a 2 cm partition at x = 0): the inner nodes that hold
// surfels of both, with each method. Surfels on the partition's top and ends and on its faces'
// parts inside the floor, ceiling and walls belong to neither room.
size_t nodesAcrossThinWall(HierarchyMethod method) {
    const Scene scene = test::loadTestScene("thin_wall");
    auto rays = EmbreeScene::create(scene);
    auto surfels = placeSurfels(scene, SurfelParams{.count = 4096});
    if (!rays || !surfels) {
        ADD_FAILURE() << "thin_wall: no rays or surfels";
        return 0;
    }
    HierarchyParams params;
    params.method = method;
    params.sceneExtent = scene.bounds.diagonal();
    params.rays = rays->get();
    auto hierarchy = buildHierarchy(*std::move(surfels), params);
    if (!hierarchy) {
        ADD_FAILURE() << hierarchy.error().message;
        return 0;
    }
    const std::vector<Surfel>& leaves = hierarchy->surfels;
    auto room = [](const Surfel& s) {
        const glm::vec3 p = s.position;
        if (p.y < 0.0f || p.y > 2.5f || std::abs(p.z) > 2.0f) return 0;  // buried
        if (s.position.x < -0.0105f || (s.position.x < 0.0f && s.normal.x < -0.5f)) return 1;
        if (s.position.x > 0.0105f || (s.position.x > 0.0f && s.normal.x > 0.5f)) return 2;
        return 0;
    };
    size_t across = 0;
    for (size_t n = leaves.size(); n < hierarchy->nodes.size(); ++n) {
        const Node& node = hierarchy->nodes[n];
        int rooms = 0;
        for (uint32_t s = node.firstSurfel; s < node.firstSurfel + node.surfelCount; ++s)
            rooms |= room(leaves[s]);
        across += rooms == 3;
    }
    return across;
}

TEST(SurfelHierarchy, VisibleMethodKeepsTheTwoSidesOfAWallApart) {
    // With the paper's metric, the floor, walls and ceiling that run under the partition join
    // the two rooms in nodes of 4 surfels and up (32 of them, measured); with visible, the
    // rooms join at the root (which must hold both).
    const size_t paper = nodesAcrossThinWall(HierarchyMethod::Agglomerative);
    const size_t visible = nodesAcrossThinWall(HierarchyMethod::Visible);
    std::printf("inner nodes across the partition: agglomerative %zu, visible %zu\n", paper,
                visible);
    EXPECT_GE(paper, 10u);
    EXPECT_LE(visible, 2u);
}

TEST(SurfelHierarchy, VisibleMethodNeedsRays) {
    HierarchyParams params;
    params.method = HierarchyMethod::Visible;
    const std::vector<Surfel> surfels = {makeSurfel({0, 0, 0}, {0, 1, 0}, 1.0f, 0),
                                         makeSurfel({1, 0, 0}, {0, 1, 0}, 1.0f, 1)};
    auto hierarchy = buildHierarchy(surfels, params);
    ASSERT_FALSE(hierarchy);
    EXPECT_NE(hierarchy.error().message.find("needs the scene's rays"), std::string::npos);
}

}  // namespace
}  // namespace pic
