#include "render/passes/sky_caches_pass.h"

#include <array>
#include <vector>

#include "core/sh.h"
#include "shaders/shared/sky_caches.h"
#include "spirv/sky_caches_comp.h"

namespace pic::gpu {

Result<std::unique_ptr<Pass>> SkyCachesPass::create(Context& context, const PassConfig& config) {
    PIC_CHECK(config.bake != nullptr);
    const BakeData& bake = *config.bake;
    if (bake.cacheSky.empty())
        return fail(ErrorCode::InvalidInput,
                    "the bake has no sky visibility for its {} caches (baked with --sky-rays 0)",
                    bake.caches.size());
    std::unique_ptr<SkyCachesPass> pass(new SkyCachesPass(context));
    pass->mCacheCount = uint32_t(bake.caches.size());
    pass->mBandsY = int(bake.params.bandsY);
    pass->mBandsC = int(bake.params.bandsC);
    const uint32_t bandsV = uint32_t(skyVisibilityBands(pass->mBandsY));
    PIC_CHECK_EQ(bake.cacheSky.size(), size_t(pass->mCacheCount) * bandsV * bandsV);
    KernelLayout layout;
    layout.bindings.assign(8, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER);
    for (uint32_t b : {0u, 5u, 6u, 7u}) layout.bindings[b] = VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
    layout.bindings[1] = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
    layout.pushBytes = sizeof(SkyCachesPush);
    layout.specialization = {bake.params.bandsY, bake.params.bandsC, bandsV};
    PIC_TRY_ASSIGN(pass->mKernel, Kernel::create(context, kSpirvSkyCachesComp, layout, "sky_caches"));
    PIC_TRY_ASSIGN(pass->mVisibility,
                   Buffer::createWith(context, std::span<const float>(bake.cacheSky),
                                      VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT,
                                      "cache sky visibility"));
    PIC_TRY_ASSIGN(pass->mVisibilityView, TexelView::create(context, pass->mVisibility,
                                                            VK_FORMAT_R32_SFLOAT, "cache sky"));
    // The shader declares the largest weight block; the buffer holds it whole, zero-padded.
    const size_t rows = size_t(shCount(pass->mBandsY)) + 2 * size_t(shCount(pass->mBandsC));
    PIC_CHECK_LE(rows * bandsV * bandsV, size_t(kMaxSkyWeightVec4s) * 4);
    const VkDeviceSize bytes = kMaxSkyWeightVec4s * sizeof(glm::vec4);
    if (bytes > context.properties().limits.maxUniformBufferRange)
        return fail(ErrorCode::Unsupported,
                    "device {} binds uniform buffers of at most {} bytes; the sky weights need {}",
                    context.properties().deviceName,
                    context.properties().limits.maxUniformBufferRange, bytes);
    const std::vector<float> zeros(kMaxSkyWeightVec4s * 4, 0.0f);
    PIC_TRY_ASSIGN(pass->mWeights,
                   Buffer::createWith(context, std::span<const float>(zeros),
                                      VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, "sky weights"));
    return pass;
}

Result<void> SkyCachesPass::bind(const Buffer& cacheY, const Buffer& cacheCo, const Buffer& cacheCg) {
    PIC_TRY(mKernel.resetSets());
    const std::array<const Buffer*, 3> caches = {&cacheY, &cacheCo, &cacheCg};
    for (size_t c = 0; c < caches.size(); ++c) {
        PIC_TRY_ASSIGN(mCacheViews[c],
                       TexelView::create(mContext, *caches[c], VK_FORMAT_R16_SFLOAT, "caches"));
    }
    const std::array<BindingResource, 8> resources = {
        BindingResource::texels(0, mVisibilityView), BindingResource::storage(1, mWeights),
        BindingResource::storage(2, cacheY),         BindingResource::storage(3, cacheCo),
        BindingResource::storage(4, cacheCg),        BindingResource::texels(5, mCacheViews[0]),
        BindingResource::texels(6, mCacheViews[1]),  BindingResource::texels(7, mCacheViews[2]),
    };
    PIC_TRY_ASSIGN(mSet, mKernel.makeSet(resources));
    return {};
}

Result<void> SkyCachesPass::setWeights(const SkyCacheWeights& weights) {
    PIC_CHECK(weights.bandsY == mBandsY && weights.bandsC == mBandsC);
    std::vector<float> packed;
    packed.reserve(weights.y.size() + weights.co.size() + weights.cg.size());
    for (const std::vector<float>* rows : {&weights.y, &weights.co, &weights.cg})
        packed.insert(packed.end(), rows->begin(), rows->end());
    PIC_CHECK_LE(packed.size() * sizeof(float), size_t(mWeights.size()));
    return mContext.uploadWithNextSubmit(mWeights, packed.data(), packed.size() * sizeof(float));
}

void SkyCachesPass::record(VkCommandBuffer cmd, const FrameResources&) {
    PIC_CHECK(mSet != VK_NULL_HANDLE);
    const SkyCachesPush push{mCacheCount, 0, 0, 0};
    mKernel.dispatch(cmd, mSet, &push, groupsFor(mCacheCount, kSkyCachesGroup));
}

}  // namespace pic::gpu
