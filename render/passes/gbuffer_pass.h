#pragma once
/// The thin client's G-buffer pass: the camera's view of the scene rasterised into four
/// RGBA32F targets (layout in shaders/shared/gbuffer.h): position and light-map UV, the
/// geometric normal facing the camera, albedo with a hit flag, and scaled emission. The CPU
/// twin is the primary ray of render/cpu/cache_shading.cpp: each pixel holds what that ray's
/// hit holds, at the pixel centre.

#include <array>
#include <cstdint>
#include <memory>
#include <span>

#include <glm/glm.hpp>

#include "core/light_set.h"
#include "core/scene.h"
#include "gpu/device.h"
#include "gpu/handle.h"
#include "gpu/resources.h"
#include "render/passes/pass.h"
#include "shaders/shared/gbuffer.h"

namespace pic::gpu {

/// Format of the G-buffer's colour targets.
inline constexpr VkFormat kGbufferFormat = VK_FORMAT_R32G32B32A32_SFLOAT;

/// The camera's clip-from-world matrix for a width × height image: the pixel centre (x + ½,
/// y + ½) of Vulkan's framebuffer (row 0 at the top) lies on CameraRays::direction(x + ½,
/// y + ½), and depth is reversed (1 at `near` metres, 0 at infinity) so that float depth
/// stays precise far away. The camera must be valid (see Renderer::render).
glm::mat4 clipFromWorldOf(const Camera& camera, uint32_t width, uint32_t height, float near);

/// Both raster stages' push constants for the camera's width × height view: clipFromWorldOf,
/// the eye, and how its rays turn per pixel (CameraRays), from which the fragment shader
/// measures texture footprints exactly as the CPU twin does. For one subsample of a pixel,
/// `offset` (in [0, 1)², core/camera.h subsampleOffset) moves the image so that each pixel
/// centre sees CameraRays::direction(x + offset.x, y + offset.y), and `footprintScale`
/// shrinks the texture footprint to the subsample's share of the pixel (1/√n of its sides).
GbufferPush gbufferPushOf(const Camera& camera, uint32_t width, uint32_t height, float near,
                          glm::vec2 offset = glm::vec2(0.5f), float footprintScale = 1.0f);

/// Rasterises the G-buffer of one camera view per frame; the targets are resized on demand.
class GbufferPass final : public Pass {
public:
    static constexpr PassKind kKind = PassKind::Gbuffer;
    /// Uploads config.scene's triangles (3 corners each, with config.triangleUvs as their
    /// light-map UVs, kNotLightmapped for grid-shaded triangles), materials and textures with their
    /// mip chains (as the scene holds them: core/texture.h buildMipChain), and builds the raster
    /// pipeline. InvalidInput for a scene whose triangles, materials or textures do not index each
    /// other or whose texels do not fill a texture's or a mip level's size; Unsupported when its
    /// textures or triangle records exceed one storage buffer.
    static Result<std::unique_ptr<Pass>> create(Context& context, const PassConfig& config);

    /// Sizes the targets for width × height (new images when the size changed: `reallocated`
    /// says so, and descriptor sets that sample them must be rebuilt) and writes the emissive
    /// scales of `lights` per material.
    Result<void> prepare(uint32_t width, uint32_t height, const LightSet& lights,
                         bool& reallocated);
    /// Records the raster pass with frame.gbuffer and leaves every target readable by compute
    /// shaders.
    void record(VkCommandBuffer cmd, const FrameResources& frame) override;

    /// Colour target i < kGbufferTargets (shaders/shared/gbuffer.h).
    const RenderTarget& target(uint32_t i) const { return mTargets[i]; }
    uint32_t width() const { return mWidth; }
    uint32_t height() const { return mHeight; }
    /// Bytes of GPU memory held (geometry, materials, textures, targets).
    VkDeviceSize bytes() const;

private:
    GbufferPass(Context& context, const Scene& scene) : mContext(context), mScene(scene) {}
    Result<void> createPipeline();

    Context& mContext;
    const Scene& mScene;
    uint32_t mVertexCount = 0;
    Buffer mVertices;       ///< GbufferVertex per triangle corner
    Buffer mTriangles;      ///< GbufferTriangle
    Buffer mMaterials;      ///< GbufferMaterial
    Buffer mTextures;       ///< GbufferTexture
    Buffer mLevels;         ///< GbufferTextureLevel, every texture's mip levels
    Buffer mTexels;         ///< vec4, every level's texels
    Buffer mEmissiveScale;  ///< float per material
    std::array<RenderTarget, kGbufferTargets> mTargets;
    RenderTarget mDepth;
    uint32_t mWidth = 0;
    uint32_t mHeight = 0;
    DescriptorSetLayout mSetLayout;
    DescriptorPool mPool;
    VkDescriptorSet mSet = VK_NULL_HANDLE;  ///< from mPool
    PipelineLayout mPipelineLayout;
    Pipeline mPipeline;
};

}  // namespace pic::gpu
