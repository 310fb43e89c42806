#include "render/passes/pull_pass.h"

#include <array>
#include <numbers>

#include <glm/glm.hpp>

#include "shaders/shared/pull.h"
#include "spirv/pull_comp.h"

namespace pic::gpu {

float radianceScale(float area) {
    return float(1.0 / (std::numbers::pi * double(area)));
}

Result<std::unique_ptr<PullPass>> PullPass::create(Context& context, const BakeData& bake) {
    std::unique_ptr<PullPass> pass(new PullPass());
    const size_t nS = bake.surfels.size();
    pass->mSurfelCount = uint32_t(nS);
    pass->mLevelOffsets = bake.levelOffsets;
    // The tail: the longest run of levels up to the root that each hold at most
    // kPullTailNodes nodes (level k ≥ 1 is nodes [levelOffsets[k − 1], levelOffsets[k])).
    const std::vector<uint32_t>& offsets = bake.levelOffsets;
    pass->mTailLevel = uint32_t(offsets.size());
    while (pass->mTailLevel > 1 &&
           offsets[pass->mTailLevel - 1] - offsets[pass->mTailLevel - 2] <= kPullTailNodes)
        --pass->mTailLevel;
    KernelLayout layout;
    layout.bindings = {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER,
                       VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER,
                       VK_DESCRIPTOR_TYPE_STORAGE_BUFFER};
    layout.pushBytes = sizeof(PullPush);
    layout.specialization = {kPullModeLevel};
    PIC_TRY_ASSIGN(pass->mLevel, Kernel::create(context, kSpirvPullComp, layout, "pull (level)"));
    layout.specialization = {kPullModeTail};
    PIC_TRY_ASSIGN(pass->mTail, Kernel::create(context, kSpirvPullComp, layout, "pull (tail)"));
    // Only the children and the area matter to the pull: 16 bytes per inner node instead of
    // the 64-byte Node.
    std::vector<PullNode> inner(bake.nodes.size() - nS);
    for (size_t n = nS; n < bake.nodes.size(); ++n) {
        const Node& node = bake.nodes[n];
        inner[n - nS] = {node.left, node.right, radianceScale(node.area), 0};
    }
    if (inner.empty()) return pass;  // a single surfel: nothing to pull
    PIC_TRY_ASSIGN(pass->mInnerNodes,
                   Buffer::createWith(context, std::span<const PullNode>(inner),
                                      VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT, "pull nodes"));
    PIC_TRY_ASSIGN(pass->mInnerView, TexelView::create(context, pass->mInnerNodes,
                                                       VK_FORMAT_R32G32B32A32_UINT, "pull nodes"));
    PIC_TRY_ASSIGN(
        pass->mLevelOffsetBuffer,
        Buffer::createWith(context, std::span<const uint32_t>(offsets), 0, "level offsets"));
    return pass;
}

Result<void> PullPass::bind(Context& context, const Buffer& nodeFlux, const Buffer& nodeRadiance) {
    if (!mInnerNodes.handle()) return {};
    PIC_TRY(mLevel.resetSets());
    PIC_TRY(mTail.resetSets());
    PIC_TRY_ASSIGN(mFluxView, TexelView::create(context, nodeFlux, VK_FORMAT_R32G32B32A32_SFLOAT,
                                                "node flux"));
    const std::array<BindingResource, 5> resources = {
        BindingResource::storage(0, nodeFlux), BindingResource::texels(1, mInnerView),
        BindingResource::storage(2, nodeRadiance), BindingResource::texels(3, mFluxView),
        BindingResource::storage(4, mLevelOffsetBuffer)};
    PIC_TRY_ASSIGN(mLevelSet, mLevel.makeSet(resources));
    PIC_TRY_ASSIGN(mTailSet, mTail.makeSet(resources));
    return {};
}

void PullPass::record(VkCommandBuffer cmd) {
    // Level k ≥ 1 is nodes [levelOffsets[k − 1], levelOffsets[k]).
    for (uint32_t level = 1; level < mTailLevel; ++level) {
        const PullPush push{mLevelOffsets[level - 1], mLevelOffsets[level], mSurfelCount, 0};
        mLevel.dispatch(cmd, mLevelSet, &push, groupsFor(push.end - push.first, kPullGroup));
        // This level's sums are written before the next level reads them.
        computeBarrier(cmd);
    }
    if (mTailLevel < mLevelOffsets.size()) {
        const PullPush push{mTailLevel, uint32_t(mLevelOffsets.size()), mSurfelCount, 0};
        mTail.dispatch(cmd, mTailSet, &push, 1);
        computeBarrier(cmd);
    }
}

}  // namespace pic::gpu
