#pragma once
/// Light-map copy on the GPU (paper 000 Figure 2 step 5): the caches' half-float SH into the
/// grid and light-map textures (coefficient-major layers per YCoCg channel, layout in
/// core/cache_textures.h). CPU twin: core/cache_textures.h
/// copyCachesToTextures.

#include <array>
#include <memory>

#include "core/bake_data.h"
#include "core/cache_textures.h"
#include "gpu/device.h"
#include "gpu/kernel.h"
#include "gpu/resources.h"
#include "render/passes/pass.h"

namespace pic::gpu {

class LightmapCopyPass final : public Pass {
public:
    static constexpr PassKind kKind = PassKind::LightmapCopy;
    /// Uploads config.bake's grid and light-map index maps and allocates the six texture
    /// buffers.
    static Result<std::unique_ptr<Pass>> create(Context& context, const PassConfig& config);
    /// Binds the caches (half, cache-major) the textures are copied from.
    Result<void> bind(const Buffer& cacheY, const Buffer& cacheCo, const Buffer& cacheCg);
    /// Copies the caches into the grid and the light map (reads nothing of `frame`).
    void record(VkCommandBuffer cmd, const FrameResources& frame) override;
    /// Reads the textures back into `out` (from makeCacheTextures for the same bake).
    Result<void> read(Context& context, CacheTextures& out) const;
    VkDeviceSize bytes() const;

private:
    LightmapCopyPass() = default;
    Kernel mKernel;
    uint32_t mCountY = 0;
    uint32_t mCountC = 0;
    uint32_t mGridVertices = 0;
    uint32_t mLightmapTexels = 0;
    Buffer mGridIndex;
    Buffer mLightmapIndex;
    std::array<Buffer, 3> mGrid;      ///< Y, Co, Cg layers, half
    std::array<Buffer, 3> mLightmap;  ///< Y, Co, Cg layers, half
    VkDescriptorSet mGridSet = VK_NULL_HANDLE;
    VkDescriptorSet mLightmapSet = VK_NULL_HANDLE;
};

}  // namespace pic::gpu
