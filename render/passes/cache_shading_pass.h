#pragma once
/// Cache shading on the GPU: each G-buffer pixel lit by the shadow-mapped lights and by the
/// caches (light map bilinear, grid trilinear, paper 000 §3.2), plus emission, per
/// ShadeComponent. CPU twin: render/cpu/cache_shading.h (which traces exact shadow rays where
/// this pass reads shadow maps).

#include <array>
#include <cstdint>
#include <memory>

#include <glm/glm.hpp>

#include "core/cache_textures.h"
#include "gpu/device.h"
#include "gpu/kernel.h"
#include "gpu/resources.h"
#include "render/passes/gbuffer_pass.h"
#include "render/passes/pass.h"
#include "render/passes/shadow_map_pass.h"
#include "shaders/shared/cache_shading.h"

namespace pic::gpu {

/// What the pass reads and writes besides its cache textures.
struct CacheShadingResources {
    const GbufferPass* gbuffer = nullptr;
    const ShadowMapPass* shadows = nullptr;
    const Buffer* shTables = nullptr;  ///< ShTables
    const Buffer* radiance = nullptr;  ///< vec4 per pixel, row-major, row 0 at the top
};

/// Shades the G-buffer into one RGB radiance per pixel; owns the cache textures it reads.
class CacheShadingPass final : public Pass {
public:
    static constexpr PassKind kKind = PassKind::CacheShading;
    /// Builds the kernel for lY = config.bandsY, lC = config.bandsC and allocates the cache
    /// textures of a grid of config.gridDims vertices and a light map of config.lightmapSize
    /// texels, all zero (no cache: the cache term is black until setCaches). Unsupported when
    /// one channel's layers exceed the device's storage-buffer range.
    static Result<std::unique_ptr<Pass>> create(Context& context, const PassConfig& config);

    /// Uploads `textures` as half floats; they must have this pass's band counts and sizes
    /// (the caller checks).
    Result<void> setCaches(const CacheTextures& textures);
    /// Binds the pass to its inputs and output (again whenever one of them was reallocated).
    Result<void> bind(const CacheShadingResources& resources);
    /// Records the shading of every pixel with frame.shading (width, height, component, …).
    void record(VkCommandBuffer cmd, const FrameResources& frame) override;

    /// Bytes of GPU memory held (cache textures).
    VkDeviceSize bytes() const;

private:
    CacheShadingPass(Context& context) : mContext(context) {}
    Context& mContext;
    Kernel mKernel;
    VkDescriptorSet mSet = VK_NULL_HANDLE;
    uint32_t mCountY = 0;
    uint32_t mCountC = 0;
    uint64_t mGridVertices = 0;
    uint64_t mLightmapTexels = 0;
    std::array<Buffer, 3> mGrid;      ///< Y, Co, Cg layers, half
    std::array<Buffer, 3> mLightmap;  ///< Y, Co, Cg layers, half
    Buffer mGridCoverage;             ///< half, 1 = cache, 0 = none
    Buffer mLightmapCoverage;         ///< half, 1 = cache, 0 = none
};

}  // namespace pic::gpu
