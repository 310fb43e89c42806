#include "core/solids.h"

#include <algorithm>
#include <array>
#include <bit>
#include <numeric>

namespace pic {
namespace {

/// Union-find over triangles, with path halving.
class Components {
public:
    explicit Components(size_t count) : mParent(count) {
        std::iota(mParent.begin(), mParent.end(), 0u);
    }
    uint32_t find(uint32_t i) {
        while (mParent[i] != i) i = mParent[i] = mParent[mParent[i]];
        return i;
    }
    void unite(uint32_t a, uint32_t b) {
        a = find(a);
        b = find(b);
        if (a != b) mParent[std::max(a, b)] = std::min(a, b);
    }

private:
    std::vector<uint32_t> mParent;
};

/// Ids of the scene's vertices with equal positions made equal (+0 and −0 alike).
std::vector<uint32_t> weldByPosition(const Scene& scene) {
    using Key = std::array<uint32_t, 3>;
    std::vector<std::pair<Key, uint32_t>> keyed(scene.vertices.size());
    for (uint32_t v = 0; v < scene.vertices.size(); ++v) {
        const glm::vec3 p = scene.vertices[v].position + glm::vec3(0.0f);
        keyed[v] = {Key{std::bit_cast<uint32_t>(p.x), std::bit_cast<uint32_t>(p.y),
                        std::bit_cast<uint32_t>(p.z)},
                    v};
    }
    std::sort(keyed.begin(), keyed.end());
    std::vector<uint32_t> weld(scene.vertices.size());
    uint32_t id = 0;
    for (size_t i = 0; i < keyed.size(); ++i) {
        if (i > 0 && keyed[i].first != keyed[i - 1].first) ++id;
        weld[keyed[i].second] = id;
    }
    return weld;
}

}  // namespace

Solids findSolids(const Scene& scene) {
    const size_t nT = scene.triangles.size();
    const std::vector<uint32_t> weld = weldByPosition(scene);

    // Every edge use: the edge as (lower id, higher id), its triangle and whether the triangle
    // runs from the lower to the higher id. Sorted, the uses of one edge lie together.
    struct EdgeUse {
        uint64_t edge;
        uint32_t triangle;
        uint32_t upward;
        bool operator<(const EdgeUse& o) const {
            return edge < o.edge || (edge == o.edge && triangle < o.triangle);
        }
    };
    std::vector<EdgeUse> uses;
    uses.reserve(3 * nT);
    std::vector<bool> degenerate(nT, false);
    for (uint32_t t = 0; t < nT; ++t) {
        const Triangle& tri = scene.triangles[t];
        const uint32_t w[3] = {weld[tri.v[0]], weld[tri.v[1]], weld[tri.v[2]]};
        if (w[0] == w[1] || w[1] == w[2] || w[2] == w[0]) {
            degenerate[t] = true;
            continue;
        }
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = w[k], b = w[(k + 1) % 3];
            uses.push_back({(uint64_t(std::min(a, b)) << 32) | std::max(a, b), t, a < b ? 1u : 0u});
        }
    }
    std::sort(uses.begin(), uses.end());

    // Triangles sharing an edge are connected; an edge that is not one upward and one
    // downward use makes its set open.
    Components components(nT);
    std::vector<uint32_t> openedBy;
    for (size_t begin = 0; begin < uses.size();) {
        size_t end = begin + 1;
        while (end < uses.size() && uses[end].edge == uses[begin].edge) ++end;
        for (size_t i = begin + 1; i < end; ++i)
            components.unite(uses[begin].triangle, uses[i].triangle);
        const bool paired = end - begin == 2 && uses[begin].upward != uses[begin + 1].upward;
        if (!paired) openedBy.push_back(uses[begin].triangle);
        begin = end;
    }
    std::vector<bool> open(nT, false);
    for (uint32_t t : openedBy) open[components.find(t)] = true;

    // Number the closed sets in triangle order; bound them and sum their signed volume
    // (the divergence theorem: V = Σ a · (b × c) / 6, about a point of the set for precision).
    Solids solids;
    solids.solidOf.assign(nT, Solids::kOpen);
    std::vector<uint32_t> solidOfRoot(nT, Solids::kOpen);
    std::vector<double> volume;
    std::vector<glm::dvec3> origin;
    for (uint32_t t = 0; t < nT; ++t) {
        if (degenerate[t]) continue;
        const uint32_t root = components.find(t);
        if (open[root]) continue;
        const Triangle& tri = scene.triangles[t];
        const glm::vec3& a = scene.vertices[tri.v[0]].position;
        const glm::vec3& b = scene.vertices[tri.v[1]].position;
        const glm::vec3& c = scene.vertices[tri.v[2]].position;
        if (solidOfRoot[root] == Solids::kOpen) {
            solidOfRoot[root] = solids.count();
            solids.bounds.emplace_back();
            volume.push_back(0.0);
            origin.emplace_back(a);
        }
        const uint32_t s = solidOfRoot[root];
        solids.solidOf[t] = s;
        solids.bounds[s].extend(a);
        solids.bounds[s].extend(b);
        solids.bounds[s].extend(c);
        const glm::dvec3 da = glm::dvec3(a) - origin[s], db = glm::dvec3(b) - origin[s],
                         dc = glm::dvec3(c) - origin[s];
        volume[s] += glm::dot(da, glm::cross(db, dc));
    }
    solids.inverted.resize(solids.count());
    for (uint32_t s = 0; s < solids.count(); ++s) solids.inverted[s] = volume[s] < 0.0;
    return solids;
}

}  // namespace pic
