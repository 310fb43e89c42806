#pragma once
/// Pull on the GPU (paper 000 Figure 2 step 3, §4.1): node flux = sum of its children's, one
/// dispatch per hierarchy level, lowest first, and one for the small upper levels together
/// (shaders/shared/pull.h); each inner node's radiance Φ / (π·A) is also
/// written as RGBE8 for cache lighting (§4.7). CPU twin: render/cpu/pull.h.

#include <memory>
#include <vector>

#include "core/bake_data.h"
#include "gpu/device.h"
#include "gpu/kernel.h"
#include "gpu/resources.h"

namespace pic::gpu {

/// 1 / (π·area): the radiance W/(m²·sr) of a Lambertian node per watt of its flux (paper 000
/// §4.1), as the pull scales it.
float radianceScale(float area);

class PullPass {
public:
    /// Uploads each inner node's two children and 1 / (π·area).
    static Result<std::unique_ptr<PullPass>> create(Context& context, const BakeData& bake);
    /// Binds the node flux (vec4 per node; its usage must allow uniform texel buffers) and
    /// node radiance (RGBE8 per node) buffers, whose leaves surfel lighting writes.
    Result<void> bind(Context& context, const Buffer& nodeFlux, const Buffer& nodeRadiance);
    /// Records every level with a barrier after each (the tail's levels with one between
    /// them inside its workgroup), so a level reads finished children.
    void record(VkCommandBuffer cmd);
    VkDeviceSize bytes() const { return mInnerNodes.size(); }

private:
    PullPass() = default;
    Kernel mLevel;  ///< the shader specialised to kPullModeLevel
    Kernel mTail;   ///< and to kPullModeTail
    VkDescriptorSet mLevelSet = VK_NULL_HANDLE;
    VkDescriptorSet mTailSet = VK_NULL_HANDLE;
    uint32_t mTailLevel = 0;    ///< levels [mTailLevel, end) are the tail's
    Buffer mLevelOffsetBuffer;  ///< the bake's level offsets
    Buffer mInnerNodes;    ///< PullNode per inner node (none for a single surfel)
    TexelView mInnerView;  ///< mInnerNodes as RGBA32UI texels
    TexelView mFluxView;   ///< the node flux as RGBA32F texels
    uint32_t mSurfelCount = 0;
    std::vector<uint32_t> mLevelOffsets;
};

}  // namespace pic::gpu
