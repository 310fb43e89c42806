#include "bake/link_generation.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <numbers>
#include <queue>

#include "bake/surfel_exposure.h"
#include "bake/surfel_grid.h"
#include "core/color.h"
#include "core/geometry.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "core/sampling.h"
#include "core/sh.h"

namespace pic {

namespace {

constexpr float kPi = std::numbers::pi_v<float>;

/// A visible surfel sample of a node: direction from the cache and its share of the link's
/// Σ w·Ω·V / Σ w·a (sr/m²), so that the samples of a node sum to its estimate.
struct VisibleSample {
    glm::vec3 direction;
    float share;
};

/// The estimate of one node's importance for one cache.
struct NodeEstimate {
    uint32_t node = 0;
    float visible = 0.0f;      ///< estimated visible solid angle, sr
    float unoccluded = 0.0f;   ///< estimated solid angle ignoring occlusion, sr
    float perArea = 0.0f;      ///< estimated Σ w·Ω·V / Σ w·a over the node, sr/m²
    glm::vec3 directionSum{0.0f};  ///< Σ w·Ω·V·ω over the samples
    // What the link reads of the part it sees, each sample counted by its share times the
    // cache's LinkReadWeight k of its direction, in the units of perArea:
    glm::vec3 colourSum{0.0f};     ///< Σ w·Ω·V·k·κ over the samples
    glm::vec3 positionSum{0.0f};   ///< Σ w·Ω·V·k·x over the samples
    glm::vec3 reference{0.0f};     ///< a point of the node, which the next three are about
    double shareSum = 0.0;         ///< Σ w·Ω·V·k, in double
    glm::dvec3 localSum{0.0};      ///< Σ w·Ω·V·k·(x − reference)
    double localSquareSum = 0.0;   ///< Σ w·Ω·V·k·|x − reference|²
    uint32_t sampleBegin = 0;  ///< its visible samples in the per-cache sample list
    uint32_t sampleCount = 0;
    double visibleArea = 0.0;  ///< estimated Σ w·a of the surfels the cache sees, m²
    uint32_t firstVisible = UINT32_MAX;     ///< leaf-order range of the visible samples' surfels
    uint32_t lastVisible = 0;
    float priority = 0.0f;     ///< refinement order, larger first: Ω·r, or Ω (LinkCut)
    bool exact = false;        ///< every surfel of the node was tested
    uint32_t readNode = 0;     ///< the node whose flux the link reads (see CacheLinker::localise)
    float readScale = 1.0f;    ///< Σ w·a of the node over that of readNode
};

/// Per-thread scratch, reused across caches to avoid allocation in the hot loop.
struct Scratch {
    std::vector<NodeEstimate> estimates;
    std::vector<VisibleSample> samples;
    std::vector<uint32_t> near;  ///< the cache's near surfels (CacheLinker::findNear), ascending
    std::vector<uint32_t> stack;
    std::vector<double> targets;  ///< CacheLinker::estimate's draws
    std::vector<uint32_t> drawn;
};

/// Surfels within this many of their radii of a cache are counted exactly in every estimate
/// (CacheLinker::estimate).
constexpr float kExactRadii = 6.0f;

class CacheLinker {
public:
    /// `weights`: the flux weight of every surfel (leaf order).
    CacheLinker(const EmbreeScene& rays, const std::vector<Surfel>& surfels,
                const std::vector<Node>& nodes, const LinkParams& params,
                const std::vector<float>& weights)
        : mRays(rays), mSurfels(surfels), mNodes(nodes), mParams(params), mWeights(weights),
          mCells(surfelCells(rays, surfels)), mReadWeight(params.bands),
          mPrefix(surfels.size() + 1, 0.0), mColourPrefix(surfels.size() + 1, glm::dvec3(0.0)),
          mPositionPrefix(surfels.size() + 1, glm::dvec3(0.0)),
          mSquarePrefix(surfels.size() + 1, 0.0) {
        for (size_t s = 0; s < surfels.size(); ++s) {
            const double wa = double(weights[s]) * surfels[s].area;
            mPrefix[s + 1] = mPrefix[s] + wa;
            mColourPrefix[s + 1] = mColourPrefix[s] + glm::dvec3(fluxColour(surfels[s])) * wa;
            mPositionPrefix[s + 1] = mPositionPrefix[s] + glm::dvec3(surfels[s].position) * wa;
            const glm::dvec3 x(surfels[s].position);
            mSquarePrefix[s + 1] = mSquarePrefix[s] + glm::dot(x, x) * wa;
            mMaxRadius = std::max(mMaxRadius, surfels[s].radius);
        }
    }

    /// Fills the nL links of cache `c` starting at `out`; returns rays cast.
    uint64_t link(uint32_t cacheIndex, const Cache& cache, Scratch& scratch,
                  std::vector<uint32_t>& chosen) const {
        scratch.estimates.clear();
        scratch.samples.clear();
        chosen.clear();
        uint64_t rays = 0;
        Rng rng(mParams.seed, cacheIndex);
        findNear(cache.position, scratch);

        auto evaluate = [&](uint32_t node) {
            NodeEstimate e = estimate(node, cache, mParams.samplesPerNode, rng, scratch, rays);
            scratch.estimates.push_back(e);
            return static_cast<uint32_t>(scratch.estimates.size() - 1);
        };
        // Max-heap on priority; ties broken by node index for determinism.
        auto lower = [&](uint32_t a, uint32_t b) {
            const NodeEstimate& x = scratch.estimates[a];
            const NodeEstimate& y = scratch.estimates[b];
            return x.priority != y.priority ? x.priority < y.priority : x.node > y.node;
        };
        std::priority_queue<uint32_t, std::vector<uint32_t>, decltype(lower)> open(lower);
        std::vector<uint32_t> closed;  // leaves: cannot be refined
        uint32_t linkable = 0;         // estimates in the cut with visible solid angle

        auto admit = [&](uint32_t e) {
            const NodeEstimate& est = scratch.estimates[e];
            if (est.visible > 0.0f) ++linkable;
            // A node whose every surfel is hidden is dropped: senders the cache cannot see
            // are never linked. Sampled nodes without a visible sample stay open while they
            // may still hide visible parts.
            if (est.visible <= 0.0f && est.exact) return;
            if (mNodes[est.node].left == kNoNode) {
                if (est.visible > 0.0f) closed.push_back(e);
            } else {
                open.push(e);
            }
        };

        admit(evaluate(static_cast<uint32_t>(mNodes.size() - 1)));
        while (linkable < mParams.linksPerCache && !open.empty()) {
            uint32_t top = open.top();
            open.pop();
            if (scratch.estimates[top].visible > 0.0f) --linkable;
            const Node& node = mNodes[scratch.estimates[top].node];
            admit(evaluate(node.left));
            admit(evaluate(node.right));
        }
        while (!open.empty()) {
            if (scratch.estimates[open.top()].visible > 0.0f) closed.push_back(open.top());
            open.pop();
        }
        // The cut was chosen by the estimates themselves, so it keeps the nodes whose estimates
        // came out low (winner's curse): re-estimating the sampled nodes with fresh rays makes
        // the final values unbiased. A node whose fresh samples all miss is not linked. The
        // fresh estimate is what the cache keeps, so it draws more rays: with 16 rays a node's
        // visible solid angle is off by tens of per cent per cache, and neighbouring caches
        // that drew differently show as blotches (docs/accuracy.md). Only the nL linked nodes
        // draw them, and a node with fewer surfels is exact.
        Rng fresh(mParams.seed ^ 0xA5A5A5A5A5A5A5A5ull, cacheIndex);
        chosen.clear();
        for (uint32_t e : closed) {
            if (scratch.estimates[e].exact) {
                chosen.push_back(e);
                continue;
            }
            NodeEstimate again = estimate(scratch.estimates[e].node, cache,
                                          mParams.finalSamplesPerNode, fresh, scratch, rays);
            if (again.visible <= 0.0f) continue;
            // Both sample sets bound the part the cache sees.
            again.firstVisible = std::min(again.firstVisible, scratch.estimates[e].firstVisible);
            again.lastVisible = std::max(again.lastVisible, scratch.estimates[e].lastVisible);
            scratch.estimates.push_back(again);
            chosen.push_back(static_cast<uint32_t>(scratch.estimates.size() - 1));
        }
        for (uint32_t e : chosen) localise(scratch.estimates[e]);
        // Links sorted by node index: neighbouring caches then read nodes in a similar order.
        std::sort(chosen.begin(), chosen.end(), [&](uint32_t a, uint32_t b) {
            return scratch.estimates[a].readNode < scratch.estimates[b].readNode;
        });
        return rays;
    }

    const NodeEstimate& estimateOf(const Scratch& scratch, uint32_t e) const {
        return scratch.estimates[e];
    }

    /// The tint of a localised estimate's link: per channel, the colour of the part the cache
    /// sees, Σ w·Ω·V·k·κ / Σ w·Ω·V·k, over that of the read node, Σ w·κ·a / Σ w·a. The read
    /// node's flux then reaches the cache as the flux of what it sees would (surfel_exposure.h
    /// fluxColour): a cache beside a red rug on a white floor reads the rug's red. Neutral
    /// under LinkReads::Node, and in a channel the read node has no colour in (its flux there
    /// has no known spread).
    glm::vec3 tintOf(const NodeEstimate& e) const {
        glm::vec3 tint(1.0f);
        if (mParams.reads == LinkReads::Node || !(e.shareSum > 0.0)) return tint;
        const Node& read = mNodes[e.readNode];
        const size_t first = read.firstSurfel, last = read.firstSurfel + read.surfelCount;
        const double area = mPrefix[last] - mPrefix[first];
        const glm::dvec3 readColour = (mColourPrefix[last] - mColourPrefix[first]) / area;
        const glm::vec3 seenColour = e.colourSum / float(e.shareSum);
        for (int c = 0; c < 3; ++c)
            if (readColour[c] > 1e-6) tint[c] = float(seenColour[c] / readColour[c]);
        return tint;
    }

    /// The offset of a localised estimate's link: the centroid of the part the cache sees,
    /// Σ w·Ω·V·k·x / Σ w·Ω·V·k (k: LinkReadWeight), from the read node's flux centroid,
    /// Σ w·a·x / Σ w·a (metres). The runtime scales the read node's flux by its linear spread
    /// along this offset (render/node_spread.h). Zero for a surfel, and under LinkReads::Node,
    /// whose links read the node's mean.
    glm::vec3 offsetOf(const NodeEstimate& e) const {
        const Node& read = mNodes[e.readNode];
        if (mParams.reads == LinkReads::Node || !(e.shareSum > 0.0) || read.surfelCount == 1)
            return glm::vec3(0.0f);
        const size_t first = read.firstSurfel, last = read.firstSurfel + read.surfelCount;
        const glm::dvec3 centroid =
            (mPositionPrefix[last] - mPositionPrefix[first]) / (mPrefix[last] - mPrefix[first]);
        return glm::vec3(glm::dvec3(e.positionSum) / e.shareSum - centroid);
    }

    /// The spread share ρ of a link: the trace of the covariance of the part the cache sees
    /// (its visible samples, weights w·Ω·V·k) over that of its read node (weights w·a), ≤ 1. The
    /// runtime's exponential spread reads a link of ρ = 1 at the node's mean and one of ρ = 0
    /// at the spread's value at the part's centroid (render/node_spread.h). 1 under
    /// LinkReads::Node, whose links read the node's mean.
    float spreadShareOf(const NodeEstimate& e) const {
        if (mParams.reads == LinkReads::Node) return 1.0f;
        if (!(e.shareSum > 0.0)) return 0.0f;
        const glm::dvec3 mean = e.localSum / e.shareSum;
        const double part = e.localSquareSum / e.shareSum - glm::dot(mean, mean);
        const Node& read = mNodes[e.readNode];
        const size_t first = read.firstSurfel, last = read.firstSurfel + read.surfelCount;
        const double weight = mPrefix[last] - mPrefix[first];
        if (!(weight > 0.0)) return 0.0f;
        const glm::dvec3 centroid = (mPositionPrefix[last] - mPositionPrefix[first]) / weight;
        const double node = (mSquarePrefix[last] - mSquarePrefix[first]) / weight -
                            glm::dot(centroid, centroid);
        if (!(node > 0.0)) return 1.0f;  // a point: every part spreads as the node
        return float(std::clamp(part / node, 0.0, 1.0));
    }

private:
    double weightedArea(uint32_t node) const {
        const Node& n = mNodes[node];
        return mPrefix[n.firstSurfel + n.surfelCount] - mPrefix[n.firstSurfel];
    }

    /// With LinkReads::Visible the link reads the flux of the smallest descendant of its node
    /// that holds every visible sample (of both estimates) and at least the weighted area the
    /// fresh samples found visible, (visible samples ÷ samples)·Σ w·a: a cache that sees one
    /// side of a cluster (one face of a thin wall, the floor beside a sofa) reads that side's
    /// light instead of the cluster's mean. The factor keeps the node's visible Σ w·Ω over
    /// the descendant's Σ w·a, so the flux the node model spreads there is read the same way.
    void localise(NodeEstimate& e) const {
        e.readNode = e.node;
        e.readScale = 1.0f;
        if (mParams.reads == LinkReads::Node) return;
        const double whole = weightedArea(e.node);
        const double needed = e.exact ? 0.0 : e.visibleArea;
        uint32_t n = e.node;
        for (;;) {
            const Node& node = mNodes[n];
            if (node.left == kNoNode) break;
            uint32_t next = kNoNode;
            for (uint32_t child : {node.left, node.right}) {
                const Node& c = mNodes[child];
                if (c.firstSurfel <= e.firstVisible && e.lastVisible < c.firstSurfel + c.surfelCount)
                    next = child;
            }
            if (next == kNoNode || weightedArea(next) < needed) break;
            n = next;
        }
        e.readNode = n;
        e.readScale = float(whole / weightedArea(n));
    }

    /// Fills scratch.near with the surfels within kExactRadii of their radius of `position`, in
    /// ascending order: the hierarchy is walked from the root, skipping nodes whose bounding
    /// sphere lies farther.
    void findNear(const glm::vec3& position, Scratch& scratch) const {
        std::vector<uint32_t>& near = scratch.near;
        std::vector<uint32_t>& stack = scratch.stack;
        near.clear();
        stack.assign(1, static_cast<uint32_t>(mNodes.size() - 1));
        while (!stack.empty()) {
            const uint32_t n = stack.back();
            stack.pop_back();
            const Node& node = mNodes[n];
            const float reach = node.radius + kExactRadii * mMaxRadius;
            const glm::vec3 v = node.center - position;
            if (glm::dot(v, v) >= reach * reach) continue;
            if (node.left == kNoNode) {
                const Surfel& s = mSurfels[n];
                const glm::vec3 u = s.position - position;
                const float r = kExactRadii * s.radius;
                if (glm::dot(u, u) < r * r) near.push_back(n);
                continue;
            }
            stack.push_back(node.right);
            stack.push_back(node.left);
        }
        std::sort(near.begin(), near.end());
    }

    /// Estimates a node from up to k of its surfels: all of them when it has at most k (exact),
    /// else its surfels near the cache exactly (Scratch::near) and k draws in proportion to w·a
    /// (stratified over the node's contiguous range of the prefix sums), one occlusion ray each,
    /// a draw that lands on a near surfel counting nothing. Drawn by weight, sample j estimates
    /// the rest of Σ w·Ω·V / Σ w·a by Ω_j·V_j / a_j with bounded variance however uneven the
    /// weights; with uniform weights n·Ω_j is the usual estimate of the solid angle, which the
    /// drawn samples also give for the priority and the cone (that of the node's weighted part).
    /// Near surfels are what makes the draw heavy-tailed: one beside the cache subtends
    /// steradians, and a draw that happens to land on it counts it n/k times. Counted exactly,
    /// in the living room the light-map caches' read nodes follow what they see (node model
    /// 1.07 → 0.99 of the exact gather) and the grid caches' cuts cover it (0.937 → 0.965).
    NodeEstimate estimate(uint32_t nodeIndex, const Cache& cache, uint32_t k, Rng& rng,
                          Scratch& scratch, uint64_t& rays) const {
        std::vector<VisibleSample>& samples = scratch.samples;
        const Node& node = mNodes[nodeIndex];
        NodeEstimate e;
        e.node = nodeIndex;
        e.reference = mSurfels[node.firstSurfel].position;
        e.sampleBegin = static_cast<uint32_t>(samples.size());
        e.exact = node.surfelCount <= k;
        const uint32_t taken = std::min(node.surfelCount, k);
        const double begin = mPrefix[node.firstSurfel];
        const double weightedArea = mPrefix[node.firstSurfel + node.surfelCount] - begin;
        // One visible surfel: its exact or drawn contribution (`omega` sr of solid angle,
        // `share` of Σ w·Ω·V / Σ w·a, `area` of the visible Σ w·a).
        auto add = [&](uint32_t s, const SurfelView& view, float omega, float share, double area) {
            e.visible += omega;
            e.visibleArea += area;
            e.firstVisible = std::min(e.firstVisible, s);
            e.lastVisible = std::max(e.lastVisible, s);
            e.perArea += share;
            e.directionSum += share * view.direction;
            const float aimed = share * mReadWeight(cache, view.direction);
            e.colourSum += aimed * fluxColour(mSurfels[s]);
            e.positionSum += aimed * mSurfels[s].position;
            const glm::dvec3 local = glm::dvec3(mSurfels[s].position) - glm::dvec3(e.reference);
            e.shareSum += aimed;
            e.localSum += double(aimed) * local;
            e.localSquareSum += double(aimed) * glm::dot(local, local);
            samples.push_back({view.direction, share});
        };
        // Exact: w_j·Ω_j / Σ w·a and Ω_j.
        auto addExact = [&](uint32_t s) {
            const SurfelView view = viewSurfel(mRays, cache, mSurfels[s], mCells.of(s));
            rays += view.rays;
            if (view.solidAngle <= 0.0f) return;  // faces away or lies behind the cache
            e.unoccluded += view.solidAngle;
            const double wa = double(mWeights[s]) * mSurfels[s].area;
            if (view.visible)
                add(s, view, view.solidAngle,
                    float(double(mWeights[s]) * view.solidAngle / weightedArea), wa);
        };
        if (e.exact) {
            for (uint32_t s = node.firstSurfel; s < node.firstSurfel + node.surfelCount; ++s)
                addExact(s);
        } else {
            const auto nearBegin =
                std::lower_bound(scratch.near.begin(), scratch.near.end(), node.firstSurfel);
            const auto nearEnd = std::lower_bound(nearBegin, scratch.near.end(),
                                                  node.firstSurfel + node.surfelCount);
            for (auto it = nearBegin; it != nearEnd; ++it) addExact(*it);
            // Draw j is the surfel s whose [prefix[s], prefix[s + 1]) holds its target (the
            // last one for a target at the end). The draws' binary searches over the node's
            // prefix sums run in lockstep, branch-free, so that their cache misses overlap,
            // and the surfels they find are prefetched before any is viewed: drawn from a
            // large node they lie far apart in memory, and the bake waited on them.
            std::vector<double>& targets = scratch.targets;
            std::vector<uint32_t>& drawn = scratch.drawn;
            targets.resize(taken);
            drawn.assign(taken, node.firstSurfel);
            for (uint32_t j = 0; j < taken; ++j)
                targets[j] = begin + (j + rng.uniform()) / taken * weightedArea;
            for (uint32_t n = node.surfelCount; n > 1;) {
                const uint32_t half = n / 2;
                for (uint32_t j = 0; j < taken; ++j)
                    drawn[j] += mPrefix[drawn[j] + half] <= targets[j] ? half : 0u;
                n -= half;
            }
            for (uint32_t s : drawn) __builtin_prefetch(&mSurfels[s]);
            for (uint32_t s : drawn) {
                if (std::binary_search(nearBegin, nearEnd, s)) continue;
                const Surfel& surfel = mSurfels[s];
                const SurfelView view = viewSurfel(mRays, cache, surfel, mCells.of(s));
                rays += view.rays;
                if (view.solidAngle <= 0.0f) continue;
                // Drawn: Ω_j / (k·a_j) and n·Ω_j / k; each draw stands for Σ w·a / k.
                const float omega = view.solidAngle * float(node.surfelCount) / float(taken);
                e.unoccluded += omega;
                if (view.visible)
                    add(s, view, omega, view.solidAngle / (float(taken) * surfel.area),
                        weightedArea / taken);
            }
        }
        e.sampleCount = static_cast<uint32_t>(samples.size()) - e.sampleBegin;
        // The refinement order is a bound on the error of the node's model: a link reads its
        // node's flux as spread by the weights and a linear spread (render/node_spread.h), which
        // light varying over the node at a rate g beyond the model (a sunlit patch, a shadow's
        // edge) misses by up to g·r at a distance r from where the model is right, so the link
        // is off by up to Ω·g·r over the Ω it sees. g depends on the lights, unknown here, so
        // it is the same for every node, and the node with the largest Ω·r (its bounding
        // radius) is refined first. Paper 000's order, Ω alone, refines a small node beside
        // the cache, which its model already matches, before a large one across the room.
        // An unlucky sample set may miss the visible part of a node (e.g. a few wall surfels
        // in a node that is mostly coplanar with a light-map cache). Such nodes keep the
        // prior that 1/(k+1) of their bounding sphere's solid angle might be visible, so
        // nodes near the cache are still refined until their samples are exact.
        float omega = e.visible;
        if (!(e.visible > 0.0f || e.exact)) {
            glm::vec3 toCentre = node.center - cache.position;
            float d2 = glm::dot(toCentre, toCentre);
            float r2 = node.radius * node.radius;
            float bound = d2 <= r2 ? 4.0f * kPi
                                   : 2.0f * kPi * r2 / (d2 * (1.0f + std::sqrt(1.0f - r2 / d2)));
            omega = bound / static_cast<float>(k + 1);
        }
        e.priority = mParams.cut == LinkCut::ErrorBound ? omega * node.radius : omega;
        return e;
    }

    const EmbreeScene& mRays;
    const std::vector<Surfel>& mSurfels;
    const std::vector<Node>& mNodes;
    const LinkParams& mParams;
    const std::vector<float>& mWeights;
    SurfelCells mCells;  ///< each surfel's patch of surface, for caches near it
    LinkReadWeight mReadWeight;
    std::vector<double> mPrefix;  ///< Σ w·a over the surfels before each (leaf order)
    std::vector<glm::dvec3> mColourPrefix;  ///< Σ w·κ·a over the surfels before each
    std::vector<glm::dvec3> mPositionPrefix;  ///< Σ w·a·x over the surfels before each
    std::vector<double> mSquarePrefix;        ///< Σ w·a·|x|² over the surfels before each
    float mMaxRadius = 0.0f;                  ///< the largest surfel radius, m
};

}  // namespace

float discSolidAngle(float distance, float radius, float cosTheta) {
    // On-axis disc: 2π(1 − d/√(d² + r²)), written as 2π r² / (√(d²+r²)(√(d²+r²) + d))
    // to stay accurate when the disc is far away.
    float h = std::sqrt(distance * distance + radius * radius);
    return 2.0f * kPi * radius * radius / (h * (h + distance)) * cosTheta;
}

namespace {

/// Solid angle of a disc (centre c, unit normal n, radius r) from p, second-order accurate
/// off its axis; 0 when it faces away or, given hemisphereNormal, lies behind that plane.
float offAxisDiscSolidAngle(const glm::vec3& p, const glm::vec3& c, const glm::vec3& n, float r,
                            const glm::vec3* hemisphereNormal) {
    const glm::vec3 v = c - p;
    const float d2 = glm::dot(v, v);
    if (!(d2 > 0.0f)) return 0.0f;
    const float d = std::sqrt(d2);
    const float cosTheta = -glm::dot(n, v) / d;
    if (cosTheta <= 0.0f) return 0.0f;
    if (hemisphereNormal && glm::dot(*hemisphereNormal, v) <= 0.0f) return 0.0f;
    // The disc's solid angle is ∫ h/|x|³ over it (h = d·cosθ, x from p to the disc's points).
    // To second order in r that is πr²·cosθ/d²·(1 + r²(9 − 15cos²θ)/(8d²)): the mean over the
    // disc of h(ρ² + h²)^(−3/2) adds r²/8 times its plane Laplacian, (9ρ² − 6h²)/s^(7/2). The
    // on-axis formula times cosθ is πr²·cosθ/d²·(1 − 6r²/(8d²)); their ratio is the factor
    // 1 + 15r²(1 − cos²θ)/(8d²), exact on the axis. Where the expansion fails (d ≲ r) the
    // result stays below the disc's largest solid angle at height h, the one on its axis.
    const float sin2 = std::max(0.0f, 1.0f - cosTheta * cosTheta);
    const float h = d * cosTheta;
    return std::min(discSolidAngle(d, r, cosTheta) * (1.0f + 15.0f * r * r * sin2 / (8.0f * d2)),
                    discSolidAngle(h, r, 1.0f));
}

/// A disc counts as near a viewer within this many of its radii.
constexpr float kNearRadii = 3.0f;

/// Calls fn(centre, radius) for the 32 equal-area parts of a disc (centre c, unit normal n,
/// radius r): discs of radius r/√32 centred on a sunflower spiral.
template <class Fn>
void forDiscParts(const glm::vec3& c, const glm::vec3& n, float r, Fn&& fn) {
    constexpr uint32_t kParts = kDiscParts;
    glm::vec3 t, b;
    orthonormalBasis(n, t, b);
    const float partRadius = r / std::sqrt(float(kParts));
    const float golden = kPi * (3.0f - std::sqrt(5.0f));
    for (uint32_t i = 0; i < kParts; ++i) {
        const float rho = r * std::sqrt((float(i) + 0.5f) / float(kParts));
        const float phi = golden * float(i);
        fn(c + rho * (std::cos(phi) * t + std::sin(phi) * b), partRadius);
    }
}

/// The disc's solid angle from p: beyond kNearRadii radii the second-order disc of
/// offAxisDiscSolidAngle (within 4 % of the integral there); nearer, the sum over its parts
/// (forDiscParts), each taken the same way, down to `splits` levels.
float splitDiscSolidAngle(const glm::vec3& p, const glm::vec3& c, const glm::vec3& n, float r,
                          const glm::vec3* hemisphereNormal, int splits) {
    const glm::vec3 v = c - p;
    if (splits == 0 || glm::dot(v, v) >= kNearRadii * kNearRadii * r * r)
        return offAxisDiscSolidAngle(p, c, n, r, hemisphereNormal);
    float sum = 0.0f;
    forDiscParts(c, n, r, [&](const glm::vec3& centre, float radius) {
        sum += splitDiscSolidAngle(p, centre, n, radius, hemisphereNormal, splits - 1);
    });
    return sum;
}

}  // namespace

float surfelSolidAngle(const glm::vec3& from, const Surfel& surfel,
                       const glm::vec3* hemisphereNormal) {
    // Two levels: a viewer within three radii of the surfel sees 32 parts, and within three of
    // a part's radii that part's own 32. The parts' gaps still show from closer than about
    // half a radius above the surfel, but average out over where the viewer is, as the gaps
    // between the surfels themselves do.
    return splitDiscSolidAngle(from, surfel.position, surfel.normal, surfel.radius,
                               hemisphereNormal, 2);
}

SurfelView viewSurfel(const EmbreeScene& rays, const Cache& cache, const Surfel& surfel,
                      std::span<const glm::vec3> cell) {
    SurfelView view;
    const glm::vec3 v = surfel.position - cache.position;
    const float d2 = glm::dot(v, v);
    if (!(d2 > 0.0f)) return view;
    const float d = std::sqrt(d2);
    const glm::vec3 w = v / d;
    if (-glm::dot(surfel.normal, w) <= 0.0f) return view;
    const glm::vec3* hemisphere = cache.kind == gpu::kCacheKindLightmap ? &cache.normal : nullptr;
    if (hemisphere && glm::dot(*hemisphere, w) <= 0.0f) return view;
    view.direction = w;
    const float epsilon = rays.epsilon();
    if (d2 >= kNearRadii * kNearRadii * surfel.radius * surfel.radius) {
        view.solidAngle = surfelSolidAngle(cache.position, surfel, hemisphere);
        // The ray stops just short of the surfel's own surface.
        const float tFar = d * (1.0f - 1e-4f) - 4.0f * epsilon;
        view.visible = !(tFar > epsilon && rays.occluded(cache.position, w, epsilon, tFar));
        view.rays = 1;
        return view;
    }
    // Near the cache a disc of the surfel's area no longer stands for its patch of surface: it
    // overhangs the patch's edges (a floor surfel's disc beyond the wall, a chair slat's far
    // beyond the slat) and parts of it may be hidden where its centre is not. Each of its
    // parts counts only where a ray towards the part's centre finds a surface there, parallel
    // to the surfel's. Without this test a light-map cache on a chair in the living room,
    // 7 mm off the plane of a lamp-lit surfel of the same chair, read 2.5× the light a path
    // tracer finds there.
    glm::vec3 seen(0.0f);  // Σ Ω·direction over the parts seen
    auto part = [&](const glm::vec3& centre, float radius) {
        const float omega =
            splitDiscSolidAngle(cache.position, centre, surfel.normal, radius, hemisphere, 1);
        if (!(omega > 0.0f)) return;
        ++view.rays;
        const glm::vec3 toPart = centre - cache.position;
        const float distance = glm::length(toPart);
        const float tolerance = 0.5f * radius + 4.0f * epsilon;
        const auto hit =
            rays.intersect(cache.position, toPart / distance, epsilon, distance + tolerance);
        if (!hit || hit->t < distance - tolerance ||
            std::abs(glm::dot(hit->geometricNormal, surfel.normal)) < 0.7f)
            return;
        view.solidAngle += omega;
        seen += omega * (toPart / distance);
        view.visible = true;
    };
    if (cell.empty()) {
        forDiscParts(surfel.position, surfel.normal, surfel.radius, part);
    } else {
        // Each point of the cell stands for a square of half a radius (surfelCells).
        const float radius = 0.5f * surfel.radius / std::sqrt(kPi);
        for (const glm::vec3& p : cell) part(p, radius);
    }
    // The parts' mean direction: a near patch seen obliquely lies off its centre's direction.
    if (glm::dot(seen, seen) > 0.0f) view.direction = glm::normalize(seen);
    return view;
}

LinkReadWeight::LinkReadWeight(uint32_t bands)
    : mBands(std::clamp<int>(int(bands), 1, kMaxShBands)) {
    for (int l = 0; l < mBands; ++l)
        mCoefficients[l] = clampedCosineZonal(l) * float(2 * l + 1) / (4.0f * kPi);
}

namespace {

/// Σ_{l < bands} w_l·P_l(x), the Legendre polynomials by Bonnet's recurrence.
template <typename T, typename W>
T legendreSeries(const W* weights, int bands, T x) {
    T sum = 0, legendre = 1, previous = 0;  // P_l(x), P_{l−1}(x)
    for (int l = 0; l < bands; ++l) {
        sum += T(weights[l]) * legendre;
        const T next = (T(2 * l + 1) * x * legendre - T(l) * previous) / T(l + 1);
        previous = legendre;
        legendre = next;
    }
    return sum;
}

}  // namespace

float LinkReadWeight::operator()(const Cache& cache, const glm::vec3& direction) const {
    if (cache.kind != gpu::kCacheKindLightmap) return 1.0f;
    const float x = glm::dot(cache.normal, direction);
    return std::max(legendreSeries(mCoefficients.data(), mBands, x), 0.0f);
}

double LinkReadWeight::kernel(double x) const {
    return legendreSeries(mCoefficients.data(), mBands, x);
}

std::array<double, kMaxShBands> LinkReadWeight::coneWeights(double oneMinusCosAlpha) const {
    std::array<double, kMaxShBands> weights{};
    coneZonalBands(mBands, oneMinusCosAlpha, weights.data());
    const double band0 = weights[0];
    for (int l = 0; l < mBands; ++l)
        weights[l] = band0 > 0.0 ? double(mCoefficients[l]) * weights[l] / band0
                                 : double(mCoefficients[l]);
    return weights;
}

double LinkReadWeight::coneKernel(double x, double oneMinusCosAlpha) const {
    return legendreSeries(coneWeights(oneMinusCosAlpha).data(), mBands, x);
}

glm::vec3 alongNormalDirection(const LinkReadWeight& weight, const glm::vec3& normal,
                               const glm::vec3& direction, float oneMinusCosAlpha, double target) {
    const double x0 = std::clamp(double(glm::dot(normal, direction)), -1.0, 1.0);
    const glm::vec3 across = direction - float(x0) * normal;
    const float acrossLength = glm::length(across);
    // Along n itself there is no plane to tilt in; an over-reading link there is a disc seen
    // face-on, which its cone matches.
    if (!(acrossLength > 1e-6f) || !std::isfinite(target)) return direction;
    const std::array<double, kMaxShBands> cone = weight.coneWeights(oneMinusCosAlpha);
    auto f = [&](double x) { return legendreSeries(cone.data(), weight.bands(), x) - target; };
    const double f0 = f(x0);
    if (f0 == 0.0) return direction;
    // Walk from x0 towards the side where f changes sign, in steps, then bisect: the nearest
    // root, or the end of the range when the target lies beyond the cone's reach. The range
    // keeps a link in front of the cache that was there: [min(x0, 0), 1].
    const double lowest = std::min(x0, 0.0);
    const double towards = (f0 > 0.0) == (f(std::min(x0 + 1e-3, 1.0)) > f0) ? -1.0 : 1.0;
    double a = x0, b = x0;
    bool bracketed = false;
    for (int step = 1; step <= 64; ++step) {
        b = std::clamp(x0 + towards * step / 32.0, lowest, 1.0);
        if ((f(b) > 0.0) != (f0 > 0.0)) {
            bracketed = true;
            break;
        }
        a = b;
        if (b == lowest || b == 1.0) break;
    }
    double x = b;
    if (bracketed) {
        for (int i = 0; i < 40; ++i) {
            const double m = 0.5 * (a + b);
            if ((f(m) > 0.0) == (f0 > 0.0)) a = m; else b = m;
        }
        x = 0.5 * (a + b);
    }
    const double sine = std::sqrt(std::max(0.0, 1.0 - x * x));
    return glm::normalize(float(x) * normal + float(sine) * (across / acrossLength));
}

SurfelCells surfelCells(const EmbreeScene& rays, const std::vector<Surfel>& surfels) {
    SurfelCells cells;
    const size_t nS = surfels.size();
    cells.first.assign(nS + 1, 0);
    if (nS == 0) return cells;
    float radius = 0.0f;
    for (const Surfel& s : surfels) radius = std::max(radius, s.radius);
    // Candidates at (u, v)·r/2 within 2.5 r of the surfel; a surfel nearer to one than its own
    // lies within 5 r of its own, so the grid's 3×3×3 cells of 5 r hold every rival.
    constexpr int kSteps = 5;
    const float reach = 2.0f * kSteps * 0.5f * radius;
    const SurfelGrid grid(surfels, reach);
    const float epsilon = rays.epsilon();
    std::vector<std::vector<glm::vec3>> points(nS);
    parallelFor(
        0, nS,
        [&](size_t i) {
            const Surfel& s = surfels[i];
            // Rivals: the surfels of the same surface (facing its way) within reach.
            std::vector<glm::vec3> rivals;
            grid.forNeighbours(s.position, [&](const SurfelGrid::Entry& e) {
                if (e.index == i || glm::dot(e.normal, s.normal) < 0.7f) return;
                const glm::vec3 d = e.position - s.position;
                if (glm::dot(d, d) < reach * reach) rivals.push_back(e.position);
            });
            glm::vec3 t, b;
            orthonormalBasis(s.normal, t, b);
            const float step = 0.5f * s.radius;
            const float lift = 0.25f * s.radius + 4.0f * epsilon;
            const glm::vec3 from = s.position + lift * s.normal;
            for (int v = -kSteps; v <= kSteps; ++v)
                for (int u = -kSteps; u <= kSteps; ++u) {
                    if (u * u + v * v > kSteps * kSteps) continue;
                    const glm::vec3 offset = (float(u) * step) * t + (float(v) * step) * b;
                    const glm::vec3 q = s.position + offset;
                    // Nearest surfel of the surface, distance out of its plane counting four
                    // times (surfel_exposure.cpp's metric): the top of a slab keeps its own cell.
                    const float mine = glm::dot(offset, offset);
                    bool nearest = true;
                    for (const glm::vec3& r : rivals) {
                        const glm::vec3 d = r - q;
                        const float off = glm::dot(d, s.normal);
                        if (glm::dot(d, d) + 15.0f * off * off < mine) {
                            nearest = false;
                            break;
                        }
                    }
                    if (!nearest) continue;
                    const glm::vec3 to = q + lift * s.normal;
                    const glm::vec3 across = to - from;
                    const float length = glm::length(across);
                    if (length > epsilon && rays.occluded(from, across / length, 0.0f, length))
                        continue;
                    const auto hit = rays.intersect(to, -s.normal, 0.0f, 2.0f * lift);
                    if (!hit || glm::dot(hit->geometricNormal, s.normal) < 0.7f) continue;
                    points[i].push_back(to - hit->t * s.normal);
                }
        },
        64);
    for (size_t i = 0; i < nS; ++i)
        cells.first[i + 1] = cells.first[i] + uint32_t(points[i].size());
    cells.points.reserve(cells.first[nS]);
    for (auto& p : points) cells.points.insert(cells.points.end(), p.begin(), p.end());
    return cells;
}

uint32_t surfelPartsOnSurface(const EmbreeScene& rays, const Surfel& surfel) {
    const float epsilon = rays.epsilon();
    uint32_t on = 0;
    forDiscParts(surfel.position, surfel.normal, surfel.radius, [&](const glm::vec3& centre, float radius) {
        // Lifted as far as viewSurfel's rays tolerate a surface off a part's centre.
        const float lift = 0.5f * radius + 4.0f * epsilon;
        const glm::vec3 from = surfel.position + lift * surfel.normal;
        const glm::vec3 to = centre + lift * surfel.normal;
        const glm::vec3 across = to - from;
        const float length = glm::length(across);
        if (length > epsilon && rays.occluded(from, across / length, 0.0f, length)) return;
        const auto hit = rays.intersect(to, -surfel.normal, 0.0f, 2.0f * lift);
        if (hit && glm::dot(hit->geometricNormal, surfel.normal) >= 0.7f) ++on;
    });
    return on;
}

double discShareOnSurface(const EmbreeScene& rays, const std::vector<Surfel>& surfels,
                          size_t sample) {
    if (surfels.empty()) return 1.0;
    const size_t count = std::min(std::max<size_t>(sample, 1), surfels.size());
    std::vector<uint32_t> on(count);
    parallelFor(0, count, [&](size_t k) {
        on[k] = surfelPartsOnSurface(rays, surfels[k * surfels.size() / count]);
    }, 64);
    uint64_t sum = 0;
    for (uint32_t n : on) sum += n;
    return double(sum) / (double(kDiscParts) * double(count));
}

LinkSet paddingLinks(LinkMode mode, uint32_t linksPerCache, uint32_t bands, size_t caches) {
    LinkSet links;
    links.mode = mode;
    links.linksPerCache = linksPerCache;
    links.bands = mode == LinkMode::Sh ? bands : 0;
    const size_t n = caches * linksPerCache;
    links.tint.assign(n, 0u);  // padding: no light
    links.offset.assign(n * 3, 0u);
    links.spreadShare.assign(n, 0u);
    if (mode == LinkMode::Rtp) {
        links.rtp.assign(n, RtpLink{0, 0.0f, 0, 0.0f});
    } else {
        links.shNodes.assign(n, 0u);
        links.shCoefficients.assign(n * size_t(shCount(int(links.bands))), 0);
    }
    return links;
}

Result<LinkResult> generateLinks(const EmbreeScene& rays, const std::vector<Surfel>& surfels,
                                 const std::vector<Node>& nodes, const std::vector<Cache>& caches,
                                 const LinkParams& params, const std::vector<float>& weights) {
    if (params.linksPerCache == 0)
        return fail(ErrorCode::InvalidInput, "links per cache must be positive, got {}", params.linksPerCache);
    if (params.mode == LinkMode::Sh && (params.bands < 1 || params.bands > kMaxShBands))
        return fail(ErrorCode::InvalidInput, "SH links need 1..{} bands, got {}", kMaxShBands, params.bands);
    if (params.samplesPerNode == 0)
        return fail(ErrorCode::InvalidInput, "samples per node must be positive, got {}", params.samplesPerNode);
    if (params.finalSamplesPerNode == 0)
        return fail(ErrorCode::InvalidInput, "final samples per node must be positive, got {}",
                    params.finalSamplesPerNode);
    if (nodes.empty() || surfels.empty() || nodes.size() != 2 * surfels.size() - 1)
        return fail(ErrorCode::InvalidInput, "hierarchy has {} nodes for {} surfels", nodes.size(), surfels.size());
    if (!weights.empty() && weights.size() != surfels.size())
        return fail(ErrorCode::InvalidInput, "{} flux weights for {} surfels", weights.size(), surfels.size());
    for (size_t i = 0; i < weights.size(); ++i)
        if (!(std::isfinite(weights[i]) && weights[i] > 0.0f))
            return fail(ErrorCode::InvalidInput, "flux weight of surfel {} is {}, must be positive", i, weights[i]);
    const std::vector<float> uniform = weights.empty() ? std::vector<float>(surfels.size(), 1.0f)
                                                       : std::vector<float>{};
    const std::vector<float>& fluxWeight = weights.empty() ? uniform : weights;

    if (params.cacheBegin > std::min(params.cacheEnd, caches.size()))
        return fail(ErrorCode::InvalidInput, "cache range [{}, {}) starts past the {} caches",
                    params.cacheBegin, params.cacheEnd, caches.size());
    const uint32_t nL = params.linksPerCache;
    const size_t first = params.cacheBegin;
    const size_t nC = std::min(params.cacheEnd, caches.size()) - first;  // caches linked here
    const int bands = static_cast<int>(params.bands);
    const int coefficients = shCount(bands);

    LinkResult result;
    result.links = paddingLinks(params.mode, nL, params.bands, nC);
    LinkSet& links = result.links;
    result.visibleSolidAngle.assign(nC * nL, 0.0f);

    CacheLinker linker(rays, surfels, nodes, params, fluxWeight);
    std::atomic<uint64_t> totalRays{0};
    std::atomic<uint32_t> blind{0}, clamped{0};
    std::vector<double> solidAngleSum(nC, 0.0);
    std::vector<uint32_t> used(nC, 0);
    Progress progress("links", nC);
    const LinkReadWeight readWeight(params.bands);
    parallelForChunks(0, nC, [&](size_t begin, size_t end) {
        thread_local Scratch scratch;
        thread_local std::vector<uint32_t> chosen;
        float basis[kMaxShBands * kMaxShBands];
        std::vector<float> sh(coefficients);
        uint64_t rayCount = 0;
        for (size_t c = begin; c < end; ++c) {
            const Cache& cache = caches[first + c];
            rayCount += linker.link(static_cast<uint32_t>(first + c), cache, scratch, chosen);
            if (chosen.empty()) blind.fetch_add(1, std::memory_order_relaxed);
            used[c] = static_cast<uint32_t>(chosen.size());
            for (size_t l = 0; l < chosen.size(); ++l) {
                const NodeEstimate& e = linker.estimateOf(scratch, chosen[l]);
                const size_t slot = c * nL + l;
                result.visibleSolidAngle[slot] = e.visible;
                solidAngleSum[c] += e.visible;
                // Flux → radiance of the visible surfels: B_j/π = Φ·w_j / (π·Σ w·a), paper 000
                // §4.1 with the node's flux spread by the weights instead of evenly.
                // The tint's largest channel scales the factor, the code keeps the rest.
                const EncodedLinkTint tint = encodeLinkTint(linker.tintOf(e));
                links.tint[slot] = tint.code;
                const glm::vec3 offset = linker.offsetOf(e);
                for (int i = 0; i < 3; ++i) links.offset[slot * 3 + i] = floatToHalfClamped(offset[i]);
                links.spreadShare[slot] = encodeSpreadShare(linker.spreadShareOf(e));
                const float toRadiance = tint.scale / kPi;
                if (params.mode == LinkMode::Rtp) {
                    // The cone spans the node's unoccluded solid angle; the factor scales it to
                    // Σ w·Ω·V / Σ w·a.
                    RtpLink& link = links.rtp[slot];
                    link.node = e.readNode;
                    link.factor = e.perArea * e.readScale / e.unoccluded * toRadiance;
                    link.oneMinusCosAlpha = std::min(2.0f, e.unoccluded / (2.0f * kPi));
                    glm::vec3 direction = glm::normalize(e.directionSum);
                    if (params.reads == LinkReads::Visible &&
                        cache.kind == gpu::kCacheKindLightmap && e.exact &&
                        e.sampleCount > 0) {
                        double along = 0.0, total = 0.0;
                        for (uint32_t j = 0; j < e.sampleCount; ++j) {
                            const VisibleSample& s = scratch.samples[e.sampleBegin + j];
                            along += double(s.share) *
                                     readWeight.kernel(glm::dot(cache.normal, s.direction));
                            total += s.share;
                        }
                        if (total > 0.0)
                            direction = alongNormalDirection(readWeight, cache.normal, direction,
                                                             link.oneMinusCosAlpha, along / total);
                    }
                    link.directionOct = encodeOctahedral(direction);
                } else {
                    // Eq. 2 with weights: c_i = 1/(π Σ w·a) Σ_j y_i(ω_j) w_j V_j Ω_j over the
                    // node's visible samples.
                    std::fill(sh.begin(), sh.end(), 0.0f);
                    for (uint32_t j = 0; j < e.sampleCount; ++j) {
                        const VisibleSample& s = scratch.samples[e.sampleBegin + j];
                        shEvaluate(bands, s.direction, basis);
                        for (int i = 0; i < coefficients; ++i) sh[i] += s.share * basis[i];
                    }
                    links.shNodes[slot] = e.readNode;
                    uint16_t* out = &links.shCoefficients[slot * coefficients];
                    for (int i = 0; i < coefficients; ++i) {
                        float value = sh[i] * e.readScale * toRadiance;
                        if (std::abs(value) > 65504.0f) clamped.fetch_add(1, std::memory_order_relaxed);
                        out[i] = floatToHalfClamped(value);
                    }
                }
            }
        }
        totalRays.fetch_add(rayCount, std::memory_order_relaxed);
        progress.advance(end - begin);
    }, 8);
    progress.finish();

    LinkStats& stats = result.stats;
    stats.rays = totalRays.load();
    stats.blindCaches = blind.load();
    stats.clampedCoefficients = clamped.load();
    double sum = 0.0, usedSum = 0.0;
    for (size_t c = 0; c < nC; ++c) {
        sum += solidAngleSum[c];
        usedSum += used[c];
    }
    stats.meanVisibleSolidAngle = nC ? sum / nC : 0.0;
    stats.meanLinksUsed = nC ? usedSum / nC : 0.0;
    return result;
}

}  // namespace pic
