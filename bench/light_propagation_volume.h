#pragma once
/// A light propagation volume (LPV; Kaplanyan 2009, Kaplanyan & Dachsbacher 2010, paper 004 §6)
/// on the CPU: the baseline without precomputation that the sweep charts against pic. Per
/// update, reflective shadow maps (Embree rays from each light) give virtual point lights
/// (VPLs) that are injected into a regular volume as 2-band SH intensity, propagated from cell
/// to cell through the faces of the cells, optionally blocked by a geometry volume, and the
/// volume's radiance is sampled at every cache of a bake, so that pic's own shaders render it.
///
/// Units. A cell holds the intensity I(ω) [W/sr] of the light leaving it in direction ω, as
/// 2-band real SH (core/sh.h basis) per RGB channel. The sum over the propagation steps (the
/// injected light included), divided by the area s² of a cell's face, is the radiance there:
/// a beam of flux Φ crossing a column of cells moves one cell per step, so each cell on its
/// way adds I with ∫I dω = Φ once, and a beam of radiance L over a face of area s² carries
/// Φ = ∫ L dω · s². Caches hold radiance by the direction the light comes FROM
/// (core/cache_values.h), the volume by the direction it travels: band 1 changes sign
/// between the two.
///
/// Choices. Propagation is linear (no clamping of the negative lobes of 2-band SH), so flux
/// is conserved exactly away from the border; the flux through a face is the exact integral of
/// the 2-band intensity over it (Kaplanyan evaluates it once at the face's centre). The
/// geometry volume comes from the bake's surfels, which sample every surface (Kaplanyan
/// injects the RSM texels and the camera's depth buffer, which see only part of the scene).
/// Emissive surfaces are injected from the surfels too (their emitted flux π·L_e·A); their
/// light is propagated but not bounced again. Caches keep the volume's radiance over the whole
/// sphere, light-map caches too, so that shading from them is LPV's own lookup.

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "core/bake_data.h"
#include "core/cache_values.h"
#include "core/error.h"
#include "core/light_set.h"
#include "core/scene.h"
#include "rays/embree_scene.h"

namespace pic {

/// Light propagation volume settings.
struct LpvParams {
    uint32_t resolution = 32;  ///< cells along the longest axis of the scene's bounds (cubic cells)
    uint32_t iterations = 16;  ///< propagation steps
    uint32_t rsmSize = 256;    ///< reflective shadow map texels per side per light (VPLs = rsmSize² per
                               ///< light, six faces for a point light)
    bool occlusion = true;     ///< a geometry volume blocks propagation (Kaplanyan's fuzzy occlusion)
};

/// What the last update did, for tests and benchmarks.
struct LpvStats {
    uint64_t vpls = 0;                ///< VPLs injected (RSM texels that hit a lit surface, plus
                                      ///< emissive surfels)
    glm::dvec3 vplFlux{0.0};          ///< Σ of their flux Φ, W per channel
    glm::dvec3 injectedFlux{0.0};     ///< ∫ I dω of the injected volume summed over cells, W
    double rsmMs = 0.0;               ///< reflective shadow maps and emitters
    double injectMs = 0.0;
    double propagateMs = 0.0;
    double sampleMs = 0.0;            ///< sampling at the caches and conversion to YCoCg
};

namespace lpv {

/// SH coefficients per channel (2 bands) and floats per cell (RGB).
inline constexpr int kCoefficients = 4;
inline constexpr int kCellFloats = 3 * kCoefficients;

/// 2-band SH of the clamped cosine max(0, n·ω) about unit n: (π·y_0^0, 2π/3·y_1^m(n)), i.e.
/// (√π/2, √(π/3)·(n.y, n.z, n.x)) in core/sh.h's basis.
std::array<float, kCoefficients> clampedCosineLobe(const glm::vec3& normal);

/// One of the 5 faces of a destination cell through which light from the centre of a
/// neighbouring source cell leaves it (all but the face the two cells share). Cell units:
/// the source centre is the origin, the destination centre is at 1 along the axis of travel.
struct Face {
    glm::vec3 direction{0.0f};   ///< unit, source centre → centre of the face
    glm::vec3 normal{0.0f};      ///< outward unit normal of the face, an axis (the lobe the
                                 ///< flux through it is re-emitted in from the destination centre)
    double solidAngle = 0.0;     ///< sr, the face seen from the source centre
    /// ∫_face y_i(ω) dω: the flux through the face of a 2-band intensity c is Σ c_i·this_i,
    /// exactly (Kaplanyan's one-point rule c·y(direction)·solidAngle approximates it).
    std::array<float, kCoefficients> basisIntegral{};
    std::array<float, kCoefficients> directionBasis{};  ///< y_i(direction), for occlusion
};

/// Faces of the destination for each direction of travel k: +x, −x, +y, −y, +z, −z; face 0
/// is straight ahead, 1-4 the sides. Computed once (closed forms: Van Oosterom-Strackee for
/// the solid angle, Arvo's edge sum for the vector ∫ω dω).
const std::array<std::array<Face, 5>, 6>& propagationFaces();

/// Solid angle of planar polygon `corners` (convex, in order) seen from the origin.
double polygonSolidAngle(std::span<const glm::dvec3> corners);

/// ∫ ω dω over planar polygon `corners` (convex, in order) seen from the origin.
glm::dvec3 polygonDirectionIntegral(std::span<const glm::dvec3> corners);

/// A virtual point light: flux Φ leaving a surface in the clamped-cosine distribution
/// I(ω) = Φ/π·max(0, n·ω) about the normal n.
struct Vpl {
    uint32_t cell = 0;       ///< the cell it is injected into
    glm::vec3 normal{0.0f};  ///< unit
    glm::vec3 flux{0.0f};    ///< W per channel
};

/// The volumes: light (cells) and geometry (cell corners), the propagation and the lookups.
class Volume {
public:
    /// dims cells of size cellSize (metres) from origin; every dim >= 1.
    Volume(const glm::vec3& origin, float cellSize, const glm::uvec3& dims);

    glm::vec3 origin() const { return mOrigin; }
    float cellSize() const { return mCellSize; }
    glm::uvec3 dims() const { return mDims; }
    size_t cellCount() const { return size_t(mDims.x) * mDims.y * mDims.z; }
    size_t cellIndex(uint32_t x, uint32_t y, uint32_t z) const {
        return x + size_t(mDims.x) * (y + size_t(mDims.y) * z);
    }
    /// The cell containing `position` (clamped into the volume).
    uint32_t cellOf(const glm::vec3& position) const;

    /// Sets the geometry volume from surface samples (position, unit front normal, area m²):
    /// per corner cell, blocking B(ω) = Σ A/s²·max(0, −n·ω) of light travelling along ω
    /// (the light that runs into the front of a surface), then its mean on every face.
    void setBlockers(std::span<const glm::vec3> positions, std::span<const glm::vec3> normals,
                     std::span<const float> areas);

    /// Empties the light volume.
    void clearLight();
    /// Adds VPLs in order (deterministic).
    void inject(std::span<const Vpl> vpls);
    /// ∫ I dω summed over the cells of the light volume as it is now, W per channel.
    glm::dvec3 totalFlux() const;
    /// Runs `iterations` propagation steps from the injected light and keeps the sum of the
    /// injected light and all steps; `occlusion`: light is blocked by the geometry volume from
    /// the second step on (the first would shadow the VPLs' own surfaces). Deterministic.
    void propagate(uint32_t iterations, bool occlusion);
    /// The intensity SH of the last step (after inject: the injected one), channel-major.
    std::span<const float> current() const { return mCurrent; }
    /// The accumulated intensity SH of every cell (W/sr), channel-major.
    std::span<const float> accumulated() const { return mAccumulated; }

    /// Incident radiance at `position` (W/(m²·sr)) from the accumulated volume, trilinear
    /// between cell centres (clamped at the border), as RGB 2-band SH by the direction light
    /// comes from (core/cache_values.h convention): rgb[c][i].
    void sampleRadiance(const glm::vec3& position, float rgb[3][kCoefficients]) const;

    uint64_t memoryBytes() const;

private:
    glm::vec3 mOrigin;
    float mCellSize;
    glm::uvec3 mDims;
    std::vector<float> mCurrent;      ///< cells × kCellFloats
    std::vector<float> mNext;         ///< cells × kCellFloats
    std::vector<float> mAccumulated;  ///< cells × kCellFloats
    /// Blocking SH on the lower face of each cell along each axis: cells × 3 × 4 (empty: none).
    std::vector<float> mFaceBlocking;
};

}  // namespace lpv

/// A light propagation volume over a baked scene whose output is the bake's cache values.
class LightPropagationVolume {
public:
    /// InvalidInput naming the value for resolution < 2 or > 256, iterations 0 or > 4096,
    /// rsmSize 0 or > 4096, a bake of another scene, or a scene without bounds.
    static Result<std::unique_ptr<LightPropagationVolume>> create(const Scene&, const EmbreeScene&,
                                                                  const BakeData&,
                                                                  const LpvParams&);
    /// Relights: reflective shadow maps → injection → propagation → the volume's radiance
    /// sampled at every cache of the bake.
    Result<const CacheValues*> update(const LightSet& lights);
    /// Bytes it holds at runtime (volumes, RSM, values).
    uint64_t memoryBytes() const;
    /// What the last update did.
    const LpvStats& stats() const { return mStats; }
    /// The volume (for tests).
    const lpv::Volume& volume() const { return mVolume; }

private:
    LightPropagationVolume(const Scene&, const EmbreeScene&, const BakeData&, const LpvParams&,
                           lpv::Volume volume);
    /// Writes the VPLs of one light's reflective shadow map to mVpls from `first` on and
    /// returns how many entries it took.
    size_t renderShadowMap(const Light& light, size_t first);
    /// Texels of a light's reflective shadow map.
    size_t shadowMapTexels(const Light& light) const;

    const Scene* mScene;
    const EmbreeScene* mRays;
    const BakeData* mBake;
    LpvParams mParams;
    lpv::Volume mVolume;
    /// One entry per RSM texel of the last update, then one per emissive surfel; entries of
    /// zero flux (texels that miss or see no light) are not injected.
    std::vector<lpv::Vpl> mVpls;
    CacheValues mValues;
    LpvStats mStats;
};

}  // namespace pic
