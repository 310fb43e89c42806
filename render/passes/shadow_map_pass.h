#pragma once
/// Shadow maps (paper 000 Figure 2 step 1): depth maps of the scene from every light, in one
/// 2D-array depth image: 6 cube faces for point lights and spots wider than
/// kMaxPerspectiveSpot, one perspective layer for narrower spots and one orthographic layer
/// over the scene for directional lights. A light whose position, direction, type and cone
/// did not change since the previous set keeps its layers: only changed lights re-render.
/// Three things let lavapipe rasterise fewer triangles: coplanar triangles are merged into
/// larger ones; the closed surfaces of the scene (core/solids.h) that a light sees from outside
/// are drawn without the faces that look away from it; and layers whose texels are wide draw a
/// simplified level of detail whose measured distance from the scene stays within half a
/// texel (which the shadow test's offsets already absorb). The casters are prepared on the
/// CPU by render/shadow_casters.h.
/// Perspective layers may also be smaller than the image's layers (ShadowMapOptions::
/// equalFootprint): each light then renders and samples the top-left side × side texels.

#include <algorithm>
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "core/light_set.h"
#include "core/scene.h"
#include "core/solids.h"
#include "gpu/device.h"
#include "gpu/handle.h"
#include "gpu/resources.h"
#include "render/passes/pass.h"
#include "render/shadow_casters.h"
#include "shaders/shared/shadow_map.h"

namespace pic::gpu {

/// Sides of a shadow-map layer the pass accepts, texels.
inline constexpr uint32_t kMinShadowMapSize = 16;
inline constexpr uint32_t kMaxShadowMapSize = 16384;

/// Spots with a wider outer half-angle get a cube map (a single perspective layer would
/// need a field of view near 180°). Radians.
inline constexpr float kMaxPerspectiveSpot = 1.0472f;  // 60°

/// The faces the one-sided pipeline skips. Solids wind counter-clockwise seen from outside;
/// the light-space matrices are right-handed with y up in clip space, which Vulkan's
/// framebuffer (y down) mirrors, so a face that looks at the light winds clockwise there:
/// Vulkan's back face under VK_FRONT_FACE_COUNTER_CLOCKWISE. Skipped are the front ones.
inline constexpr VkCullModeFlags kCullAwayFromLight = VK_CULL_MODE_FRONT_BIT;

/// Area-weighted points on the scene's surfaces from which a perspective light's typical
/// receiver distance is taken (ShadowMapOptions::equalFootprint).
inline constexpr uint32_t kFootprintSamples = 4096;
/// Smallest side of a layer, and the step sides are rounded up to (texels).
inline constexpr uint32_t kMinShadowSide = 16;

/// The GpuLight record of `light` as lightIrradiance (shaders/lib/lights.glsl) reads it:
/// type, position, direction, range, radiant intensity and cone; the shadow fields zero.
GpuLight gpuLightRecord(const Light& light);

/// The side (texels) of a perspective layer whose texels are `footprint` metres wide at
/// `distance` metres, for a layer `slopeAtOneTexel` wide per metre of depth (2·tan(fov/2)):
/// rounded up to a multiple of kMinShadowSide, within [kMinShadowSide, maxSide].
uint32_t footprintSide(float slopeAtOneTexel, float distance, float footprint, uint32_t maxSide);

/// One level of detail of the casters: its clusters, consecutive in the pass's cluster list.
struct CasterLevel {
    /// Metres the scene's surfaces moved, measured (surfaceDeviation; for level 0, the
    /// merged casters, float rounding where only coplanar triangles merged).
    float error = 0.0f;
    uint32_t firstCluster = 0;
    uint32_t clusterCount = 0;
    uint32_t triangles = 0;
};

class ShadowMapPass final : public Pass {
public:
    static constexpr PassKind kKind = PassKind::ShadowMap;
    /// Uploads config.scene's casters and builds the depth-only pipelines, drawn as
    /// config.shadowMap says. config.shadowMapSize is the side of one layer in texels.
    static Result<std::unique_ptr<Pass>> create(Context& context, const PassConfig& config);

    /// Lays out `lights` on layers, writes their GpuLight records and matrices and marks the
    /// lights whose maps must be rendered. `reallocated` tells whether the depth image was
    /// replaced (descriptor sets that sample it must be rebuilt).
    Result<void> prepare(const LightSet& lights, bool& reallocated);
    /// Renders the layers of the lights prepare() marked, leaving every layer readable by
    /// compute shaders (reads nothing of `frame`).
    void record(VkCommandBuffer cmd, const FrameResources& frame) override;

    /// Lights rendered by the last record().
    uint32_t renderedLights() const { return mRenderedLights; }
    /// Triangles drawn by the last record(), over all layers (after frustum culling).
    uint64_t drawnTriangles() const { return mDrawnTriangles; }
    /// Texels of the layers the last record() rendered (side² each).
    uint64_t renderedTexels() const { return mRenderedTexels; }
    /// Of drawnTriangles(), those drawn with faces looking away from the light skipped.
    uint64_t oneSidedTriangles() const { return mOneSidedTriangles; }
    /// Caster triangles (the scene's, coplanar ones merged) and those of them in solids, at
    /// level of detail 0.
    uint32_t casterTriangles() const { return mLevels.front().triangles; }
    uint32_t solidTriangles() const { return mSolidTriangles; }
    /// The levels of detail, finest (level 0) first.
    std::span<const CasterLevel> levels() const { return mLevels; }
    /// The level each layer was last rendered with.
    std::span<const uint32_t> layerLevels() const { return mLayerLevels; }
    /// The GpuLight records of the lights prepare() laid out, in order.
    std::vector<GpuLight> lightRecords() const;
    /// The records of the layers prepare() laid out (GpuLight::firstLayer indexes them).
    std::span<const GpuShadowLayer> layerRecords() const { return mLayers; }
    uint32_t size() const { return mSize; }
    const DepthArray& depth() const { return mDepth; }
    const Buffer& lightBuffer() const { return mLights; }     ///< GpuLight[kMaxLights]
    const Buffer& layerBuffer() const { return mLayerBuffer; }  ///< GpuShadowLayer[6·kMaxLights]
    uint32_t lightCount() const { return uint32_t(mCurrent.size()); }
    /// Bytes of GPU memory held (geometry, depth image, light records).
    VkDeviceSize bytes() const;

private:
    /// What a light's depth layers depend on.
    struct LightSlot {
        std::string id;
        GpuLight gpu{};
        glm::vec3 position{0.0f};
        glm::vec3 direction{0.0f};
        float outerConeAngle = 0.0f;
        LightType type = LightType::Point;
        uint32_t layers = 0;
        std::array<uint32_t, 6> sides{};  ///< of its layers, in texels
        ShadowEye eye;
        bool dirty = true;
    };

    ShadowMapPass(Context& context) : mContext(context) {}
    /// Binds `pipeline` with layer `layer`'s matrix and geometry and a side × side viewport.
    void bindPipeline(VkCommandBuffer cmd, VkPipeline pipeline, uint32_t layer, uint32_t side) const;
    /// The sides of `light`'s perspective layers (a spot's one layer first; slopeAtOneTexel:
    /// 2·tan(fov/2)): with equalFootprint, each the one whose texels, at the median distance
    /// of the surface samples the light reaches on that layer, are as wide as an
    /// orthographic layer's (kMinShadowSide for a layer that holds none); otherwise mSize.
    std::array<uint32_t, 6> perspectiveSides(const Light& light, float slopeAtOneTexel) const;
    /// Metres per texel of an orthographic layer: its box spans the scene's bounding sphere
    /// with a 1 % margin.
    float orthographicTexel() const { return 1.01f * std::max(mBounds.diagonal(), 1e-3f) / float(mSize); }
    LightSlot describe(const Light& light, uint32_t firstLayer,
                       std::vector<GpuShadowLayer>& layers) const;
    /// The coarsest level whose error layer `layer` of `slot` allows everywhere it looks.
    uint32_t levelFor(const LightSlot& slot, uint32_t layer) const;
    std::span<const TriangleCluster> clustersOf(uint32_t level) const {
        return std::span(mClusters).subspan(mLevels[level].firstCluster, mLevels[level].clusterCount);
    }

    Context& mContext;
    uint32_t mSize = 0;
    Aabb mBounds;
    std::vector<glm::vec3> mSurfaceSamples;  ///< kFootprintSamples (equalFootprint), else none
    std::vector<TriangleCluster> mClusters;  ///< every level's, level by level
    std::vector<CasterLevel> mLevels;
    std::vector<uint32_t> mLayerLevels;
    Buffer mVertices;
    Buffer mIndices;
    Buffer mLights;
    Buffer mLayerBuffer;
    DepthArray mDepth;
    PipelineLayout mPipelineLayout;
    Pipeline mPipeline;          ///< both faces
    Pipeline mOneSidedPipeline;  ///< faces looking towards the light
    uint32_t mSolidTriangles = 0;
    std::vector<LightSlot> mCurrent;
    std::vector<GpuShadowLayer> mLayers;
    uint32_t mRenderedLights = 0;
    uint64_t mDrawnTriangles = 0;
    uint64_t mRenderedTexels = 0;
    uint64_t mOneSidedTriangles = 0;
};

}  // namespace pic::gpu
