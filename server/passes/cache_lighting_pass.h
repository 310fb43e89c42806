#pragma once
/// Cache lighting on the GPU (paper 000 Figure 2 step 4, eq. 3, §4.6, §4.8): each cache's
/// incident radiance from its nL links, YCoCg with lY / lC bands, half floats. Links stay in
/// the bake's order, sequential per cache; they are bound in chunks of caches so that no
/// binding exceeds the device's maxStorageBufferRange (128 MiB on lavapipe). CPU twin:
/// server/cpu/cache_lighting.h.

#include <memory>
#include <vector>

#include "core/bake_data.h"
#include "server/gpu/kernel.h"

namespace pic::gpu {

class CacheLightingPass {
public:
    /// Uploads the links (RTP: 16 bytes each; SH: node index + lY² half coefficients).
    /// `cachePerSubgroup`: a subgroup shares each cache's links (GPUs), else an invocation
    /// walks them (CPU devices); shaders/shared/cache_lighting.h says why.
    static Result<std::unique_ptr<CacheLightingPass>> create(Context& context, const BakeData& bake,
                                                             bool cachePerSubgroup);
    /// Binds node flux (vec4 per node), the output caches (half) and the SH tables.
    Result<void> bind(const Buffer& nodeFlux, const Buffer& cacheY, const Buffer& cacheCo,
                      const Buffer& cacheCg, const Buffer& shTables);
    void record(VkCommandBuffer cmd);
    /// Link bytes read per update.
    VkDeviceSize linkBytes() const { return mLinkBytes; }
    VkDeviceSize bytes() const { return mRtp.size() + mShNodes.size() + mShCoefficients.size(); }
    uint32_t chunks() const { return uint32_t(mChunkFirst.size()); }

private:
    CacheLightingPass() = default;
    Kernel mKernel;
    bool mRtpForm = true;
    uint32_t mCachesPerGroup = 1;  ///< caches one workgroup lights
    uint32_t mCacheCount = 0;
    uint32_t mLinksPerCache = 0;
    uint32_t mCountY = 0;
    VkDeviceSize mLinkBytes = 0;
    Buffer mRtp;             ///< RtpLink per link (RTP)
    Buffer mShNodes;         ///< uint per link (SH)
    Buffer mShCoefficients;  ///< lY² halves per link (SH)
    Buffer mUnused;          ///< bound where the other link form's buffers go
    std::vector<uint32_t> mChunkFirst;
    std::vector<uint32_t> mChunkCount;
    std::vector<VkDescriptorSet> mSets;
};

}  // namespace pic::gpu
