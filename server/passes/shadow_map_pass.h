#pragma once
/// Shadow maps (paper 000 Figure 2 step 1): depth maps of the scene from every light, in one
/// 2D-array depth image: 6 cube faces for point lights and spots wider than
/// kMaxPerspectiveSpot, one perspective layer for narrower spots and one orthographic layer
/// over the scene for directional lights. A light whose position, direction, type and cone
/// did not change since the previous set keeps its layers: only changed lights re-render.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "core/light_set.h"
#include "core/scene.h"
#include "server/gpu/context.h"
#include "shaders/shared/shadow_map.h"

namespace pic::gpu {

/// Spots with a wider outer half-angle get a cube map (a single perspective layer would
/// need a field of view near 180°). Radians.
inline constexpr float kMaxPerspectiveSpot = 1.0472f;  // 60°

/// Spatially close triangles, consecutive in the pass's index buffer: the unit of frustum
/// culling, so that a cube face rasterises only the part of the scene it can see.
struct TriangleCluster {
    uint32_t firstTriangle = 0;
    uint32_t triangleCount = 0;
    Aabb bounds;
};

/// Triangles per cluster: small enough that a cube face skips most of a room, large enough
/// that one layer needs few draws.
inline constexpr uint32_t kShadowClusterTriangles = 512;

/// Splits the scene's triangles into spatially compact clusters of at most `maxTriangles`
/// (median splits of their centroids); `order` receives the triangle indices in cluster order.
std::vector<TriangleCluster> buildTriangleClusters(const Scene& scene, uint32_t maxTriangles,
                                                   std::vector<uint32_t>& order);

/// A run of triangles to draw: [firstTriangle, firstTriangle + triangleCount).
struct TriangleRange {
    uint32_t firstTriangle = 0;
    uint32_t triangleCount = 0;
};

/// The clusters whose bounds can intersect the clip volume of `clipFromWorld` (Vulkan's:
/// −w ≤ x, y ≤ w, 0 ≤ z ≤ w), adjacent ones merged into one range. Conservative: a cluster
/// is dropped only when its box lies wholly outside one of the six planes.
std::vector<TriangleRange> visibleTriangleRanges(std::span<const TriangleCluster> clusters,
                                                 const glm::mat4& clipFromWorld);

class ShadowMapPass {
public:
    /// Uploads the scene's triangles and builds the depth-only pipeline. `size` is the side of
    /// one layer in texels.
    static Result<std::unique_ptr<ShadowMapPass>> create(Context& context, const Scene& scene,
                                                         uint32_t size);
    ~ShadowMapPass();

    /// Lays out `lights` on layers, writes their GpuLight records and matrices and marks the
    /// lights whose maps must be rendered. `reallocated` tells whether the depth image was
    /// replaced (descriptor sets that sample it must be rebuilt).
    Result<void> prepare(const LightSet& lights, bool& reallocated);
    /// Renders the layers of the lights prepare() marked, leaving every layer readable by
    /// compute shaders.
    void record(VkCommandBuffer cmd);

    /// Lights rendered by the last record().
    uint32_t renderedLights() const { return mRenderedLights; }
    /// Triangles drawn by the last record(), over all layers (after frustum culling).
    uint64_t drawnTriangles() const { return mDrawnTriangles; }
    uint32_t size() const { return mSize; }
    const DepthArray& depth() const { return mDepth; }
    const Buffer& lightBuffer() const { return mLights; }     ///< GpuLight[kMaxLights]
    const Buffer& matrixBuffer() const { return mMatrices; }  ///< mat4[6·kMaxLights]
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
        bool dirty = true;
    };

    ShadowMapPass(Context& context) : mContext(context) {}
    LightSlot describe(const Light& light, uint32_t firstLayer,
                       std::vector<glm::mat4>& clipFromWorld) const;

    Context& mContext;
    uint32_t mSize = 0;
    Aabb mBounds;
    std::vector<TriangleCluster> mClusters;
    Buffer mVertices;
    Buffer mIndices;
    Buffer mLights;
    Buffer mMatrices;
    DepthArray mDepth;
    VkPipelineLayout mPipelineLayout = VK_NULL_HANDLE;
    VkPipeline mPipeline = VK_NULL_HANDLE;
    std::vector<LightSlot> mCurrent;
    std::vector<glm::mat4> mClipFromWorld;  ///< per layer
    uint32_t mRenderedLights = 0;
    uint64_t mDrawnTriangles = 0;
};

}  // namespace pic::gpu
