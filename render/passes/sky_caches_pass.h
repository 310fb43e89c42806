#pragma once
/// Sky caches on the GPU (core/sky.h): after the last bounce every cache adds the direct sky,
/// its sky visibility from the bake times the update's folded sky (SkyCacheWeights), into the
/// half-float caches. CPU twin: render/cpu/sky_caches.h.

#include <array>
#include <memory>

#include "core/bake_data.h"
#include "core/sky.h"
#include "gpu/device.h"
#include "gpu/kernel.h"
#include "gpu/resources.h"
#include "render/passes/pass.h"

namespace pic::gpu {

class SkyCachesPass final : public Pass {
public:
    static constexpr PassKind kKind = PassKind::SkyCaches;
    /// Uploads the sky visibility of config.bake's caches; InvalidInput when the bake has none
    /// (baked with --sky-rays 0) or no caches.
    static Result<std::unique_ptr<Pass>> create(Context& context, const PassConfig& config);
    /// Binds the caches (half, cache-major) the sky is added to; their usage must allow
    /// uniform texel buffers (VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT).
    Result<void> bind(const Buffer& cacheY, const Buffer& cacheCo, const Buffer& cacheCg);
    /// Uploads the sky of this update with the next submission (made for the bake's lY, lC).
    Result<void> setWeights(const SkyCacheWeights& weights);
    /// Adds the sky to every cache (reads nothing of `frame`).
    void record(VkCommandBuffer cmd, const FrameResources& frame) override;
    VkDeviceSize bytes() const { return mVisibility.size() + mWeights.size(); }

private:
    SkyCachesPass(Context& context) : mContext(context) {}
    Context& mContext;
    Kernel mKernel;
    uint32_t mCacheCount = 0;
    int mBandsY = 0, mBandsC = 0;
    Buffer mVisibility;  ///< float, nC·nV (BakeData::cacheSky)
    TexelView mVisibilityView;
    std::array<TexelView, 3> mCacheViews;  ///< Y, Co, Cg as R16F texels
    Buffer mWeights;     ///< float, (lY² + 2·lC²)·nV
    VkDescriptorSet mSet = VK_NULL_HANDLE;
};

}  // namespace pic::gpu
