#include "bake/surfel_hierarchy.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>
#include <tuple>
#include <utility>

#include "bake/surfel_exposure.h"
#include "core/parallel.h"
#include "core/progress.h"

namespace pic {

namespace {

// Half-width of the window of Morton-ordered clusters searched for a nearest neighbour.
constexpr size_t kSearchRadius = 32;
// A cluster whose mean normal is shorter than this has opposing normals that cancel.
constexpr float kCancelledNormal = 1e-4f;
// How far from unit length an input surfel normal may be.
constexpr float kNormalTolerance = 1e-3f;
// Bits per axis of the Morton codes that order the leaves (3 · 21 = 63 bits).
constexpr uint32_t kMortonBits = 21;

// What merging needs to know of a cluster; normalSum is the area-weighted sum of normals.
struct ClusterGeometry {
    glm::vec3 center{0.0f};
    float area = 0.0f;
    glm::vec3 normalSum{0.0f};
    float radius = 0.0f;
};

// A binary tree under construction: node ids [0, nS) are the input surfels, id nS + k is
// the inner node with children[k]. Children are created before their parents, the root last.
struct BuildTree {
    uint32_t leafCount = 0;
    std::vector<std::array<uint32_t, 2>> children;
};

ClusterGeometry leafGeometry(const Surfel& surfel) {
    return {surfel.position, surfel.area, surfel.normal * surfel.area, surfel.radius};
}

// Area-weighted centre, summed area and normals, and the radius of the sphere around the
// new centre that encloses both children's spheres.
ClusterGeometry merge(const ClusterGeometry& a, const ClusterGeometry& b) {
    ClusterGeometry merged;
    merged.area = a.area + b.area;
    merged.center = (a.area * a.center + b.area * b.center) / merged.area;
    merged.normalSum = a.normalSum + b.normalSum;
    merged.radius = std::max(glm::length(a.center - merged.center) + a.radius,
                             glm::length(b.center - merged.center) + b.radius);
    return merged;
}

// The unit mean normal m of a cluster, or zero where its normals cancel.
glm::vec3 meanNormal(const ClusterGeometry& geometry) {
    float length = glm::length(geometry.normalSum);
    return length > kCancelledNormal * geometry.area ? geometry.normalSum / length
                                                     : glm::vec3(0.0f);
}

std::string toString(const glm::vec3& v) {
    return fmt::format("({}, {}, {})", v.x, v.y, v.z);
}

bool isFinite(const glm::vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

Result<void> validate(const std::vector<Surfel>& surfels, const HierarchyParams& params) {
    if (surfels.empty()) return fail(ErrorCode::InvalidInput, "surfel hierarchy: no surfels");
    // 2·nS − 1 node indices must stay below kNoNode.
    constexpr size_t kMaxSurfels = size_t{1} << 31;
    if (surfels.size() > kMaxSurfels)
        return fail(ErrorCode::InvalidInput, "surfel hierarchy: {} surfels, at most {} supported",
                    surfels.size(), kMaxSurfels);
    if (params.method != HierarchyMethod::Agglomerative &&
        params.method != HierarchyMethod::KdTree && params.method != HierarchyMethod::Visible)
        return fail(ErrorCode::InvalidInput, "surfel hierarchy: unknown method {}",
                    static_cast<uint32_t>(params.method));
    if (params.method == HierarchyMethod::Visible && !params.rays)
        return fail(ErrorCode::InvalidInput,
                    "surfel hierarchy: method visible needs the scene's rays");
    if (!(std::isfinite(params.normalWeight) && params.normalWeight >= 0.0f))
        return fail(ErrorCode::InvalidInput,
                    "surfel hierarchy: normal weight C_n = {} must be finite and >= 0",
                    params.normalWeight);
    if (!(std::isfinite(params.balanceWeight) && params.balanceWeight >= 0.0f))
        return fail(ErrorCode::InvalidInput,
                    "surfel hierarchy: balance weight C_b = {} must be finite and >= 0",
                    params.balanceWeight);
    float invExtent2 = 1.0f / (params.sceneExtent * params.sceneExtent);
    if (!(std::isfinite(params.sceneExtent) && params.sceneExtent > 0.0f &&
          std::isfinite(invExtent2)))
        return fail(ErrorCode::InvalidInput,
                    "surfel hierarchy: scene extent {} m must be finite and positive",
                    params.sceneExtent);

    glm::vec3 lo(std::numeric_limits<float>::max());
    glm::vec3 hi(std::numeric_limits<float>::lowest());
    double totalArea = 0.0;
    for (size_t i = 0; i < surfels.size(); ++i) {
        const Surfel& s = surfels[i];
        if (!isFinite(s.position))
            return fail(ErrorCode::InvalidInput, "surfel {} has non-finite position {}", i,
                        toString(s.position));
        if (!(std::isfinite(s.area) && s.area > 0.0f))
            return fail(ErrorCode::InvalidInput, "surfel {} has area {} m², must be positive", i,
                        s.area);
        if (!(std::isfinite(s.radius) && s.radius >= 0.0f))
            return fail(ErrorCode::InvalidInput, "surfel {} has radius {} m, must be >= 0", i,
                        s.radius);
        if (!isFinite(s.normal) || std::abs(glm::length(s.normal) - 1.0f) > kNormalTolerance)
            return fail(ErrorCode::InvalidInput, "surfel {} has normal {}, must be unit length", i,
                        toString(s.normal));
        lo = glm::min(lo, s.position);
        hi = glm::max(hi, s.position);
        totalArea += s.area;
    }
    if (totalArea > std::numeric_limits<float>::max())
        return fail(ErrorCode::InvalidInput, "surfel hierarchy: total area {} m² overflows",
                    totalArea);
    // The spatial term of the metric must stay finite for every pair of surfels.
    glm::vec3 span = hi - lo;
    if (!std::isfinite(glm::dot(span, span) * invExtent2))
        return fail(ErrorCode::InvalidInput,
                    "surfel hierarchy: surfels span {} m, too large for scene extent {} m",
                    toString(span), params.sceneExtent);
    return {};
}

// ---- Agglomerative clustering ------------------------------------------------------------

// Spreads the low 21 bits of x so that bit k lands on bit 3k.
uint64_t spreadBits(uint64_t x) {
    x &= 0x1fffff;
    x = (x | x << 32) & 0x1f00000000ffffull;
    x = (x | x << 16) & 0x1f0000ff0000ffull;
    x = (x | x << 8) & 0x100f00f00f00f00full;
    x = (x | x << 4) & 0x10c30c30c30c30c3ull;
    x = (x | x << 2) & 0x1249249249249249ull;
    return x;
}

// The class of a surfel: emitters of one material form a class of their own (the light set
// scales a material's emission as a whole), all other surfels one more.
constexpr uint32_t kReflector = 0xFFFFFFFEu;
constexpr uint32_t kMixed = 0xFFFFFFFFu;
uint32_t surfelClass(const Surfel& s) { return isEmitter(s) ? s.material : kReflector; }

// Surfel indices sorted by class, then along a Morton curve over the surfels' bounding cube.
std::vector<uint32_t> mortonOrder(const std::vector<Surfel>& surfels) {
    glm::vec3 lo(std::numeric_limits<float>::max());
    glm::vec3 hi(std::numeric_limits<float>::lowest());
    for (const Surfel& s : surfels) {
        lo = glm::min(lo, s.position);
        hi = glm::max(hi, s.position);
    }
    // One scale for all axes keeps the curve isotropic.
    constexpr float kMaxCell = static_cast<float>((1u << kMortonBits) - 1);
    float extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
    float scale = extent > 0.0f ? kMaxCell / extent : 0.0f;
    std::vector<std::tuple<uint32_t, uint64_t, uint32_t>> keys(surfels.size());
    parallelFor(0, surfels.size(), [&](size_t i) {
        glm::vec3 cell = glm::min((surfels[i].position - lo) * scale, glm::vec3(kMaxCell));
        uint64_t code = spreadBits(static_cast<uint64_t>(cell.x)) |
                        spreadBits(static_cast<uint64_t>(cell.y)) << 1 |
                        spreadBits(static_cast<uint64_t>(cell.z)) << 2;
        keys[i] = {surfelClass(surfels[i]), code, static_cast<uint32_t>(i)};
    });
    // Keys are unique (the index breaks ties), so the order is deterministic.
    std::sort(keys.begin(), keys.end());
    std::vector<uint32_t> order(surfels.size());
    for (size_t i = 0; i < keys.size(); ++i) order[i] = std::get<2>(keys[i]);
    return order;
}

// The weights of the metric d(a, b), with the spatial term's normalisation folded in, and
// the scene's rays for the occlusion term (none: geometry only).
struct Metric {
    float invExtent2 = 1.0f;
    float normalWeight = 0.0f;
    float balanceWeight = 0.0f;
    const EmbreeScene* rays = nullptr;
};

// A cluster that has not been merged yet, with what the metric reads of it.
struct ActiveCluster {
    glm::vec3 center{0.0f};
    float area = 0.0f;
    glm::vec3 normal{0.0f};  // unit mean normal, zero where cancelled
    uint32_t node = 0;       // BuildTree node id
    uint32_t kind = kReflector;  // surfelClass of all its surfels, or kMixed
};

ActiveCluster activeCluster(uint32_t node, const ClusterGeometry& geometry, uint32_t kind) {
    return {geometry.center, geometry.area, meanNormal(geometry), node, kind};
}

// Clusters of different classes merge only when no cluster of the same class is in reach:
// an emitter's flux then stays on its own nodes instead of being spread over the surfaces
// around it (and a material's emissive scale moves only its own nodes). The penalty exceeds
// every term of the metric (the spatial one is at most 1, the others their weights).
constexpr float kClassPenalty = 16.0f;

// Paper 000 eq. (§4.3): d(a, b) = |x_a − x_b|² / extent² + C_n (1 − ⟨m_a, m_b⟩)
// + C_b |A_a − A_b| / max(A_a, A_b), plus kClassPenalty across classes. Callers pass a before b in cluster order, so that
// d(a, b) and d(b, a) are bitwise equal.
float distance(const ActiveCluster& a, const ActiveCluster& b, const Metric& metric) {
    glm::vec3 delta = a.center - b.center;
    return (a.kind == b.kind && a.kind != kMixed ? 0.0f : kClassPenalty) +
           glm::dot(delta, delta) * metric.invExtent2 +
           metric.normalWeight * (1.0f - glm::dot(a.normal, b.normal)) +
           metric.balanceWeight * std::abs(a.area - b.area) / std::max(a.area, b.area);
}

// Clusters that cannot see each other (the two faces of a wall, a room's floor and the next
// room's) merge only when no cluster they see is in reach: a node that straddles a wall
// spreads the light of one side over the other (paper 000 §5.2 (c)). The penalty exceeds the
// rest of the metric (at most 1 + 2·C_n + C_b) and stays below kClassPenalty.
constexpr float kOcclusionPenalty = 4.0f;
// The segment tested joins the clusters' centres, each lifted off its surface along its mean
// normal by this fraction of their distance, so that neighbours on a bent or curved surface
// (the sagitta between them is about d²/8r) and across a corner still see each other.
constexpr float kOcclusionLift = 0.25f;

// Whether the scene blocks the segment between clusters a and b (a before b in cluster order,
// so that the test is the same from either side).
bool occluded(const ActiveCluster& a, const ActiveCluster& b, const EmbreeScene& rays) {
    const float d = glm::distance(a.center, b.center);
    const glm::vec3 from = a.center + (kOcclusionLift * d) * a.normal;
    const glm::vec3 delta = b.center + (kOcclusionLift * d) * b.normal - from;
    const float length = glm::length(delta);
    const float epsilon = rays.epsilon();
    if (!(length > 2.0f * epsilon)) return false;
    return rays.occluded(from, delta / length, epsilon, length - epsilon);
}

// Position of the cluster nearest to active[i] among the kSearchRadius positions on either
// side; ties go to the lowest position, which orders all candidate pairs totally. The
// occlusion term is tested in order of the rest of the metric, only while it can still
// change the answer.
uint32_t nearestInWindow(const std::vector<ActiveCluster>& active, size_t i, const Metric& metric) {
    size_t begin = i > kSearchRadius ? i - kSearchRadius : 0;
    size_t end = std::min(active.size(), i + kSearchRadius + 1);
    std::array<std::pair<float, uint32_t>, 2 * kSearchRadius> candidates;
    size_t count = 0;
    for (size_t j = begin; j < end; ++j) {
        if (j == i) continue;
        float d =
            j < i ? distance(active[j], active[i], metric) : distance(active[i], active[j], metric);
        candidates[count++] = {d, static_cast<uint32_t>(j)};
    }
    const auto first = candidates.begin(), last = candidates.begin() + count;
    if (!metric.rays) return std::min_element(first, last)->second;
    std::sort(first, last);
    std::pair<float, uint32_t> best{std::numeric_limits<float>::infinity(), 0};
    for (auto it = first; it != last && it->first <= best.first; ++it) {
        const size_t j = it->second;
        const bool blocked = j < i ? occluded(active[j], active[i], *metric.rays)
                                   : occluded(active[i], active[j], *metric.rays);
        best = std::min(best, {it->first + (blocked ? kOcclusionPenalty : 0.0f), it->second});
    }
    return best.second;
}

// Hierarchical agglomerative clustering under the paper's metric, in the parallel
// locally-ordered form of PLOC (Meister and Bittner 2018; after Walter et al. 2008):
// clusters are kept in Morton order of their surfels; each round every cluster finds its
// nearest neighbour among the kSearchRadius clusters on either side (in parallel), and all
// mutual nearest neighbours merge, the merged cluster taking the lower position. The
// pair with the smallest distance in any window is always mutual, so each round merges at
// least once. The approximation against exact HAC is the window: a partner further along
// the curve is not seen. Since the normal and balance terms are often larger than the
// spatial one, a kd-tree search pruned by the spatial lower bound would visit much of the
// scene; the window keeps a round at O(n · kSearchRadius) and the windows widen in space
// as clusters merge.
BuildTree buildAgglomerative(const std::vector<Surfel>& surfels, const HierarchyParams& params) {
    const auto nS = static_cast<uint32_t>(surfels.size());
    BuildTree tree{nS, {}};
    tree.children.reserve(nS - 1);
    const Metric metric{1.0f / (params.sceneExtent * params.sceneExtent), params.normalWeight,
                        params.balanceWeight,
                        params.method == HierarchyMethod::Visible ? params.rays : nullptr};

    std::vector<ClusterGeometry> geometry(2 * size_t{nS} - 1);
    std::vector<uint32_t> order = mortonOrder(surfels);
    std::vector<ActiveCluster> active(nS);
    parallelFor(0, nS, [&](size_t i) {
        geometry[i] = leafGeometry(surfels[i]);
        active[i] = activeCluster(order[i], leafGeometry(surfels[order[i]]),
                                  surfelClass(surfels[order[i]]));
    });

    Progress progress("surfel hierarchy", nS - 1);
    std::vector<uint32_t> nearest;
    std::vector<ActiveCluster> next;
    while (active.size() > 1) {
        nearest.resize(active.size());
        parallelFor(0, active.size(),
                    [&](size_t i) { nearest[i] = nearestInWindow(active, i, metric); });

        // Merge mutual nearest neighbours in order, so node ids do not depend on scheduling.
        next.clear();
        uint32_t merges = 0;
        for (size_t i = 0; i < active.size(); ++i) {
            uint32_t j = nearest[i];
            if (nearest[j] != i) {
                next.push_back(active[i]);
            } else if (i < j) {
                uint32_t a = active[i].node;
                uint32_t b = active[j].node;
                auto node = static_cast<uint32_t>(nS + tree.children.size());
                tree.children.push_back({a, b});
                geometry[node] = merge(geometry[a], geometry[b]);
                next.push_back(activeCluster(node, geometry[node],
                                             active[i].kind == active[j].kind ? active[i].kind : kMixed));
                ++merges;
            }
        }
        progress.advance(merges);
        std::swap(active, next);
    }
    return tree;
}

// ---- Kd-tree ------------------------------------------------------------------------------

// Partitions perm[begin, end) around its middle along the largest extent of its surfel
// positions; equal coordinates are ordered by index so the result is deterministic.
void splitAtMedian(const std::vector<Surfel>& surfels, std::vector<uint32_t>& perm, uint32_t begin,
                   uint32_t end) {
    glm::vec3 lo(std::numeric_limits<float>::max());
    glm::vec3 hi(std::numeric_limits<float>::lowest());
    for (uint32_t k = begin; k < end; ++k) {
        lo = glm::min(lo, surfels[perm[k]].position);
        hi = glm::max(hi, surfels[perm[k]].position);
    }
    glm::vec3 extent = hi - lo;
    int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
    uint32_t middle = begin + (end - begin) / 2;
    std::nth_element(perm.begin() + begin, perm.begin() + middle, perm.begin() + end,
                     [&](uint32_t a, uint32_t b) {
                         float pa = surfels[a].position[axis];
                         float pb = surfels[b].position[axis];
                         return pa < pb || (pa == pb && a < b);
                     });
}

// Appends the inner nodes of the kd-tree over perm[begin, end) in post-order; returns the
// id of its root.
uint32_t appendKdNodes(const std::vector<uint32_t>& perm, uint32_t begin, uint32_t end,
                       BuildTree& tree) {
    if (end - begin == 1) return perm[begin];
    uint32_t middle = begin + (end - begin) / 2;
    uint32_t left = appendKdNodes(perm, begin, middle, tree);
    uint32_t right = appendKdNodes(perm, middle, end, tree);
    tree.children.push_back({left, right});
    return tree.leafCount + static_cast<uint32_t>(tree.children.size() - 1);
}

// Recursive median split along the largest extent of the surfel positions, within each
// surfel class (surfelClass: each emissive material, then the reflectors), the classes' trees
// joined pairwise at the top, so an emitter's flux stays on nodes of its own as in the
// agglomerative tree. Every range splits at its middle, so the tree's shape depends on the
// classes' sizes alone and the positions decide only which surfel lands in which leaf.
BuildTree buildKdTree(const std::vector<Surfel>& surfels) {
    const auto nS = static_cast<uint32_t>(surfels.size());
    std::vector<uint32_t> perm(nS);
    std::iota(perm.begin(), perm.end(), 0u);
    std::stable_sort(perm.begin(), perm.end(), [&](uint32_t a, uint32_t b) {
        return surfelClass(surfels[a]) < surfelClass(surfels[b]);
    });
    std::vector<std::pair<uint32_t, uint32_t>> classes;
    for (uint32_t begin = 0; begin < nS;) {
        uint32_t end = begin + 1;
        while (end < nS && surfelClass(surfels[perm[end]]) == surfelClass(surfels[perm[begin]])) ++end;
        classes.emplace_back(begin, end);
        begin = end;
    }

    // Split all ranges of one depth in parallel; they are disjoint.
    std::vector<std::pair<uint32_t, uint32_t>> ranges;
    for (auto [begin, end] : classes)
        if (end - begin > 1) ranges.emplace_back(begin, end);
    std::vector<std::pair<uint32_t, uint32_t>> next;
    while (!ranges.empty()) {
        parallelFor(
            0, ranges.size(),
            [&](size_t r) { splitAtMedian(surfels, perm, ranges[r].first, ranges[r].second); }, 1);
        next.clear();
        for (auto [begin, end] : ranges) {
            uint32_t middle = begin + (end - begin) / 2;
            if (middle - begin > 1) next.emplace_back(begin, middle);
            if (end - middle > 1) next.emplace_back(middle, end);
        }
        std::swap(ranges, next);
    }

    BuildTree tree{nS, {}};
    tree.children.reserve(nS - 1);
    std::vector<uint32_t> roots;
    for (auto [begin, end] : classes) roots.push_back(appendKdNodes(perm, begin, end, tree));
    // The classes' roots, joined in pairs until one is left.
    while (roots.size() > 1) {
        std::vector<uint32_t> joined;
        for (size_t i = 0; i + 1 < roots.size(); i += 2) {
            tree.children.push_back({roots[i], roots[i + 1]});
            joined.push_back(tree.leafCount + static_cast<uint32_t>(tree.children.size() - 1));
        }
        if (roots.size() % 2) joined.push_back(roots.back());
        roots = std::move(joined);
    }
    return tree;
}

// ---- Final layout -------------------------------------------------------------------------

// Lays a built tree out as bake_layout.h documents: leaves in depth-first order (so every
// subtree owns a contiguous surfel range), then inner nodes by ascending level, in creation
// order within a level; the root, created last at the highest level, ends up last.
SurfelHierarchy layOut(std::vector<Surfel> input, const BuildTree& tree) {
    const uint32_t nS = tree.leafCount;
    const uint32_t nodeCount = 2 * nS - 1;
    const uint32_t root = nodeCount - 1;
    PIC_CHECK_EQ(tree.children.size(), size_t{nS} - 1);

    // Children precede parents in creation order, so one pass gives every level.
    std::vector<uint32_t> level(nodeCount, 0);
    for (uint32_t k = 0; k + 1 < nS; ++k) {
        const auto& [a, b] = tree.children[k];
        level[nS + k] = 1 + std::max(level[a], level[b]);
    }
    const uint32_t levelCount = level[root] + 1;

    SurfelHierarchy out;
    out.levelOffsets.assign(levelCount, 0);
    out.levelOffsets[0] = nS;
    for (uint32_t k = 0; k + 1 < nS; ++k) ++out.levelOffsets[level[nS + k]];
    for (uint32_t l = 1; l < levelCount; ++l) out.levelOffsets[l] += out.levelOffsets[l - 1];

    // Final index of every node: inner nodes by a stable counting sort on level, leaves in
    // the order a left-first depth-first traversal meets them.
    std::vector<uint32_t> finalIndex(nodeCount);
    std::vector<uint32_t> cursor(levelCount);
    for (uint32_t l = 1; l < levelCount; ++l) cursor[l] = out.levelOffsets[l - 1];
    for (uint32_t k = 0; k + 1 < nS; ++k) finalIndex[nS + k] = cursor[level[nS + k]]++;
    uint32_t nextLeaf = 0;
    std::vector<uint32_t> stack{root};
    while (!stack.empty()) {
        uint32_t id = stack.back();
        stack.pop_back();
        if (id < nS) {
            finalIndex[id] = nextLeaf++;
        } else {
            stack.push_back(tree.children[id - nS][1]);
            stack.push_back(tree.children[id - nS][0]);
        }
    }

    out.surfels.resize(nS);
    out.nodes.resize(nodeCount);
    std::vector<ClusterGeometry> geometry(nodeCount);
    for (uint32_t id = 0; id < nS; ++id) {
        uint32_t i = finalIndex[id];
        out.surfels[i] = input[id];
        geometry[i] = leafGeometry(input[id]);
        Node& node = out.nodes[i];
        node = {};
        node.center = input[id].position;
        node.area = input[id].area;
        node.normal = input[id].normal;
        node.radius = input[id].radius;
        node.left = kNoNode;
        node.right = kNoNode;
        node.parent = kNoNode;
        node.firstSurfel = i;
        node.surfelCount = 1;
        node.level = 0;
    }
    for (uint32_t k = 0; k + 1 < nS; ++k) {
        Node& node = out.nodes[finalIndex[nS + k]];
        node = {};
        node.left = finalIndex[tree.children[k][0]];
        node.right = finalIndex[tree.children[k][1]];
        node.parent = kNoNode;
        node.level = level[nS + k];
        out.nodes[node.left].parent = finalIndex[nS + k];
        out.nodes[node.right].parent = finalIndex[nS + k];
    }

    // Children precede parents in the final order too, so one forward pass fills in the
    // inner nodes' geometry and surfel ranges.
    for (uint32_t i = nS; i < nodeCount; ++i) {
        Node& node = out.nodes[i];
        const Node& left = out.nodes[node.left];
        const Node& right = out.nodes[node.right];
        PIC_DCHECK(right.firstSurfel == left.firstSurfel + left.surfelCount);
        geometry[i] = merge(geometry[node.left], geometry[node.right]);
        node.center = geometry[i].center;
        node.area = geometry[i].area;
        node.normal = meanNormal(geometry[i]);
        node.radius = geometry[i].radius;
        node.firstSurfel = left.firstSurfel;
        node.surfelCount = left.surfelCount + right.surfelCount;
    }
    return out;
}

}  // namespace

Result<SurfelHierarchy> buildHierarchy(std::vector<Surfel> surfels, const HierarchyParams& params) {
    if (auto valid = validate(surfels, params); !valid) return std::unexpected(valid.error());
    BuildTree tree = params.method == HierarchyMethod::KdTree ? buildKdTree(surfels)
                                                              : buildAgglomerative(surfels, params);
    return layOut(std::move(surfels), tree);
}

}  // namespace pic
