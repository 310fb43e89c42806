#pragma once
/// Link generation (paper 000 §4.5-4.6): for every cache, a cut of nL hierarchy nodes refined
/// top-down by visible solid angle times node radius, a bound on the error of a node's model
/// (paper 000 refines by visible solid angle alone), with Embree occlusion rays; stored
/// SH-projected (eq. 2) or runtime-projected (direction, cone, scalar factor), each with a
/// colour tint.

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "core/bake_data.h"
#include "core/error.h"
#include "core/sh.h"
#include "rays/embree_scene.h"

namespace pic {

struct LinkParams {
    uint32_t linksPerCache = 128;  ///< nL
    LinkMode mode = LinkMode::Rtp;
    uint32_t bands = 3;            ///< SH bands per link in SH mode
    uint32_t samplesPerNode = 16;  ///< visibility rays per node estimate while choosing the cut
    uint32_t finalSamplesPerNode = 64;  ///< rays of a linked node's fresh, final estimate
    LinkReads reads = LinkReads::Visible;
    LinkCut cut = LinkCut::ErrorBound;
    uint64_t seed = 1;
    /// Links caches [cacheBegin, min(cacheEnd, nC)) only (one shard of a bake); the LinkSet
    /// and visibleSolidAngle then hold that many caches. A cache's links depend on its index,
    /// not on the range.
    size_t cacheBegin = 0;
    size_t cacheEnd = SIZE_MAX;
};

/// Per-link diagnostics that the bake file does not keep (for tests and statistics).
struct LinkStats {
    double meanVisibleSolidAngle = 0.0;  ///< sr, mean over caches of Σ links' visible solid angle
    double meanLinksUsed = 0.0;          ///< non-padding links per cache
    uint64_t rays = 0;                   ///< occlusion rays cast
    uint32_t blindCaches = 0;            ///< caches that see no surfel at all
    uint32_t clampedCoefficients = 0;    ///< SH coefficients beyond the half-float range
};

/// Everything generateLinks returns.
struct LinkResult {
    LinkSet links;
    LinkStats stats;
    std::vector<float> visibleSolidAngle;  ///< per link (nC·nL of the range), sr; 0 for padding
};

/// The links of `caches` caches, every one padding (node 0, no light): what generateLinks
/// fills, and what a sharded bake's parts are placed into. `bands` counts in SH mode only.
LinkSet paddingLinks(LinkMode mode, uint32_t linksPerCache, uint32_t bands, size_t caches);

/// Builds the links of every cache against the hierarchy (surfels in leaf order). A link reads
/// the flux Φ_r of a node r as spread over its surfels by `weights` (bake/surfel_exposure.h:
/// one per surfel; empty for uniform): the radiance it carries from visible surfel j is
/// Φ_r·w_j / (π·Σ_r w·a), so its factor is Σ_visible w_j·Ω_j / (π·Σ_r w·a). r is the node of
/// the cache's cut (LinkReads::Node, paper 000) or its smallest descendant that holds the part
/// the cache sees (LinkReads::Visible); the links of a cache then need not form a cut. With
/// LinkReads::Visible each link also has a tint (LinkSet::tint): per channel, the colour κ
/// (surfel_exposure.h fluxColour) of the surfels it sees over the read node's, Σ w·κ·a / Σ w·a,
/// so that the node's flux reaches the cache in the colour of what it sees, and an RTP link of a
/// light-map cache whose node's visibility is counted exactly turns its cone towards where the
/// cache's normal gathers that node's light (alongNormalDirection).
Result<LinkResult> generateLinks(const EmbreeScene& rays, const std::vector<Surfel>& surfels,
                                 const std::vector<Node>& nodes, const std::vector<Cache>& caches,
                                 const LinkParams& params, const std::vector<float>& weights = {});

/// The parts a surfel's disc is split into near a viewer (viewSurfel).
inline constexpr uint32_t kDiscParts = 32;

/// How a cache sees one surfel: the unit direction to it, its disc's solid angle (0 when it
/// faces away from the cache or lies behind a light-map cache's surface) and whether an
/// occlusion ray reaches it. Within three radii of the cache, only the parts of the disc where
/// a ray finds the surfel's surface count (one ray per part), so a disc overhanging its patch's
/// edges or partly hidden counts what is there; given the surfel's `cell` (SurfelCells), its
/// points are the parts instead, each a square of half a radius. There the direction is the
/// mean of the parts seen, weighted by their solid angles. The one test that link generation
/// and its diagnostics share.
struct SurfelView {
    glm::vec3 direction{0.0f};
    float solidAngle = 0.0f;  ///< sr, ignoring occlusion
    bool visible = false;     ///< solidAngle > 0 and nothing blocks the segment
    uint32_t rays = 0;        ///< rays cast: one, one per part of the disc near it, or none
};
SurfelView viewSurfel(const EmbreeScene& rays, const Cache& cache, const Surfel& surfel,
                      std::span<const glm::vec3> cell = {});

/// The patch of surface each surfel stands for near a viewer, as points on it: its Voronoi
/// cell on its own surface. Discs of equal area leave gaps and overlap where surfels lie
/// unevenly (two surfels 4 radii apart along a room's corner leave the corner bare between
/// them), which a cache beside them sees as missing or doubled light; the cells tile the
/// surfaces. Candidate points on a grid of half a radius over ±2.5 radii about the surfel
/// are kept where they lie on its surface (a ray across from above its centre passes nothing
/// and one down finds a surface facing its way) and no other surfel of that surface is nearer.
struct SurfelCells {
    std::vector<uint32_t> first;    ///< per surfel, into points; one more entry at the end
    std::vector<glm::vec3> points;  ///< on the surface, metres

    std::span<const glm::vec3> of(size_t surfel) const {
        return {points.data() + first[surfel], points.data() + first[surfel + 1]};
    }
};
SurfelCells surfelCells(const EmbreeScene& rays, const std::vector<Surfel>& surfels);

/// How much a visible direction ω counts in what a link reads of its node (the part's
/// centroid that the node's spread is read at, its spread share and its tint). A light-map
/// cache is shown, and read by the bounces on its surface, as its irradiance along its normal
/// n through the lY bands, so ω counts by that irradiance's kernel
/// k(n·ω) = Σ_{l<lY} K_l·(2l + 1)/(4π)·P_l(n·ω) (K_l the clamped cosine's zonal coefficients;
/// ∫ L(ω)·k(n·ω) dω is the irradiance of L's lY-band projection, by the addition theorem),
/// clamped at 0. A grid cache is seen from every direction: each counts 1. Weighted by the
/// solid angle alone, the part's centroid lies nearer the cache than the light its normal
/// gathers: in two_floors a floor or wall light-map cache read 0.982 of its surfels'
/// irradiance along the normal where band 0 was right.
class LinkReadWeight {
public:
    explicit LinkReadWeight(uint32_t bands);  ///< lY, clamped to [1, kMaxShBands]
    float operator()(const Cache& cache, const glm::vec3& direction) const;
    /// k(x) unclamped, x = n·ω.
    double kernel(double x) const;
    /// The mean of k(n·ω) over the cone of half-angle α (u = 1 − cos α) around a direction d
    /// with n·d = x: Σ_l K_l·(2l + 1)/(4π)·K_l(α)/K_0(α)·P_l(x) (the addition theorem), what an
    /// RTP link adds along n per unit of its band 0.
    double coneKernel(double x, double oneMinusCosAlpha) const;
    /// coneKernel's Legendre weights, K_l·(2l + 1)/(4π)·K_l(α)/K_0(α) for l < bands().
    std::array<double, kMaxShBands> coneWeights(double oneMinusCosAlpha) const;
    int bands() const { return mBands; }

private:
    int mBands;
    std::array<float, kMaxShBands> mCoefficients{};  ///< K_l·(2l + 1)/(4π)
};

/// The direction of an RTP link of a light-map cache with normal n: the cone around `direction`
/// of half-angle α (u = 1 − cos α) stands for the node's visible part, and where that part is
/// no circle (a strip of the wall beside the cache, seen at grazing angles) its mean of the
/// kernel k(n·ω) along n (`target`, LinkReadWeight::kernel over the visible samples, weighted
/// as band 0) differs from the cone's: k is convex in n·ω, so a round cone spread across the
/// horizon reads more than a strip along it. Tilted in the plane of n and `direction` to the
/// n·d whose coneKernel is `target` (the nearest such n·d in [min(n·direction, 0), 1], or that
/// range's end where the target lies beyond the cone's reach), the link adds what its samples
/// see along n in every band up to lY; band 0 does not move. `direction` along n, or a target
/// that is not finite, stays as it is.
glm::vec3 alongNormalDirection(const LinkReadWeight& weight, const glm::vec3& normal,
                               const glm::vec3& direction, float oneMinusCosAlpha, double target);

/// How many of the kDiscParts parts of a surfel's disc lie on its own surface: a ray from
/// above its centre to above the part passes nothing, and one down from there meets a surface
/// facing the surfel's way. The rest overhangs an edge, a wall standing on the surface or a
/// hole, where near caches (viewSurfel) find nothing of the surfel.
uint32_t surfelPartsOnSurface(const EmbreeScene& rays, const Surfel& surfel);

/// The share of the surfels' disc area that lies on their own surfaces (surfelPartsOnSurface),
/// over `sample` surfels spread evenly over the list (all when there are fewer): how well
/// discs of their radius stand for the scene's surfaces. 1 for open floors and walls; it
/// falls as surfaces narrower than a disc (steps, slats, pillars) take a larger share.
double discShareOnSurface(const EmbreeScene& rays, const std::vector<Surfel>& surfels,
                          size_t sample = 8192);

/// Solid angle (sr) of a disc of radius r seen from distance d at cosine cosTheta between
/// its normal and the direction to the viewer: the on-axis disc formula scaled by cosTheta.
float discSolidAngle(float distance, float radius, float cosTheta);

/// Solid angle (sr) of a surfel's disc seen from `from`, right off its axis and near it (within
/// 4 % of the integral from half a radius above it): the disc formula above counts a lattice
/// of surfels 0.74 radii below the viewer as 0.72 of their plane. With
/// hemisphereNormal, the parts of the disc behind that plane through `from` are left out.
float surfelSolidAngle(const glm::vec3& from, const Surfel& surfel,
                       const glm::vec3* hemisphereNormal = nullptr);

}  // namespace pic
