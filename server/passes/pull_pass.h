#pragma once
/// Pull on the GPU (paper 000 Figure 2 step 3, §4.1): node flux = sum of its children's, one
/// dispatch per hierarchy level, lowest first. CPU twin: server/cpu/pull.h.

#include <memory>
#include <vector>

#include "core/bake_data.h"
#include "server/gpu/kernel.h"

namespace pic::gpu {

class PullPass {
public:
    /// Uploads each inner node's two children.
    static Result<std::unique_ptr<PullPass>> create(Context& context, const BakeData& bake);
    /// Binds the node flux buffer (vec4 per node, leaves written by surfel lighting).
    Result<void> bind(const Buffer& nodeFlux);
    /// Records every level with a barrier after each, so a level reads finished children.
    void record(VkCommandBuffer cmd);
    VkDeviceSize bytes() const { return mChildren.size(); }

private:
    PullPass() = default;
    Kernel mKernel;
    VkDescriptorSet mSet = VK_NULL_HANDLE;
    Buffer mChildren;
    uint32_t mSurfelCount = 0;
    std::vector<uint32_t> mLevelOffsets;
};

}  // namespace pic::gpu
