#include "server/passes/cache_lighting_pass.h"

#include <algorithm>
#include <array>

#include "shaders/shared/cache_lighting.h"
#include "spirv/cache_lighting_comp.h"

namespace pic::gpu {
namespace {

/// Chunks hold a multiple of this many caches, so that every chunk's offset into the link
/// buffers is a multiple of 256 bytes (the largest minStorageBufferOffsetAlignment in use).
constexpr uint32_t kChunkAlignment = 256;

}  // namespace

Result<std::unique_ptr<CacheLightingPass>> CacheLightingPass::create(Context& context,
                                                                     const BakeData& bake,
                                                                     bool cachePerSubgroup) {
    std::unique_ptr<CacheLightingPass> pass(new CacheLightingPass());
    // Per subgroup: as many caches per workgroup as it has subgroups of the default size (the
    // shader strides over any the device leaves, should it launch fewer).
    pass->mCachesPerGroup = cachePerSubgroup
        ? std::max<uint32_t>(kCacheLightingGroup / context.subgroupSize(), 1)
        : kCacheLightingGroup;
    const LinkSet& links = bake.links;
    pass->mRtpForm = links.mode == LinkMode::Rtp;
    pass->mCacheCount = uint32_t(bake.caches.size());
    pass->mLinksPerCache = links.linksPerCache;
    pass->mCountY = bake.params.bandsY * bake.params.bandsY;
    const VkDeviceSize nLinks = VkDeviceSize{pass->mCacheCount} * links.linksPerCache;

    // The widest per-link binding decides how many caches a chunk may hold.
    const VkDeviceSize widest = pass->mRtpForm ? sizeof(RtpLink)
                                               : std::max<VkDeviceSize>(4, 2 * pass->mCountY);
    const VkDeviceSize perCache = std::max<VkDeviceSize>(widest * links.linksPerCache, 1);
    const VkDeviceSize maxRange = context.properties().limits.maxStorageBufferRange;
    VkDeviceSize chunk = (maxRange / perCache) / kChunkAlignment * kChunkAlignment;
    if (chunk == 0)
        return fail(ErrorCode::Unsupported,
                    "{} links per cache need {} bytes per cache, too many for {} caches within "
                    "one storage binding of {} bytes",
                    links.linksPerCache, perCache, kChunkAlignment, maxRange);
    for (uint32_t first = 0; first < pass->mCacheCount; first += uint32_t(chunk)) {
        pass->mChunkFirst.push_back(first);
        pass->mChunkCount.push_back(std::min<uint32_t>(uint32_t(chunk), pass->mCacheCount - first));
    }

    KernelLayout layout;
    layout.bindings.assign(8, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER);
    layout.bindings[7] = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;  // SH tables
    layout.pushBytes = sizeof(CacheLightingPush);
    layout.specialization = {bake.params.bandsY, bake.params.bandsC, links.linksPerCache,
                             pass->mRtpForm ? kLinkFormRtp : kLinkFormSh,
                             cachePerSubgroup ? kCachePerSubgroup : kCachePerInvocation};
    layout.maxSets = std::max<uint32_t>(uint32_t(pass->mChunkFirst.size()), 1);
    PIC_TRY_ASSIGN(pass->mKernel,
                   Kernel::create(context, kSpirvCacheLightingComp, layout, "cache_lighting"));

    PIC_TRY_ASSIGN(pass->mUnused, context.createBuffer(16, 0, MemoryUse::Device, "unused links"));
    if (pass->mRtpForm) {
        PIC_TRY_ASSIGN(pass->mRtp, context.createBufferWith(std::span<const RtpLink>(links.rtp), 0,
                                                            "RTP links"));
        pass->mLinkBytes = nLinks * sizeof(RtpLink);
    } else {
        PIC_TRY_ASSIGN(pass->mShNodes, context.createBufferWith(
                                           std::span<const uint32_t>(links.shNodes), 0, "SH link nodes"));
        PIC_TRY_ASSIGN(pass->mShCoefficients,
                       context.createBufferWith(std::span<const uint16_t>(links.shCoefficients), 0,
                                                "SH link coefficients"));
        pass->mLinkBytes = nLinks * (4 + 2 * pass->mCountY);
    }
    return pass;
}

Result<void> CacheLightingPass::bind(const Buffer& nodeFlux, const Buffer& cacheY,
                                     const Buffer& cacheCo, const Buffer& cacheCg,
                                     const Buffer& shTables) {
    mSets.clear();
    PIC_TRY(mKernel.resetSets());
    const VkDeviceSize nL = mLinksPerCache;
    for (size_t k = 0; k < mChunkFirst.size(); ++k) {
        const VkDeviceSize links = VkDeviceSize{mChunkFirst[k]} * nL;
        const VkDeviceSize count = VkDeviceSize{mChunkCount[k]} * nL;
        const auto chunkOf = [&](uint32_t binding, const Buffer& b, VkDeviceSize stride) {
            return BindingResource::storage(binding, b, links * stride, count * stride);
        };
        // The other link form's bindings hold a small placeholder.
        const std::array<BindingResource, 8> resources = {
            BindingResource::storage(0, nodeFlux),
            mRtpForm ? chunkOf(1, mRtp, sizeof(RtpLink)) : BindingResource::storage(1, mUnused),
            mRtpForm ? BindingResource::storage(2, mUnused) : chunkOf(2, mShNodes, 4),
            mRtpForm ? BindingResource::storage(3, mUnused)
                     : chunkOf(3, mShCoefficients, 2 * VkDeviceSize{mCountY}),
            BindingResource::storage(4, cacheY),
            BindingResource::storage(5, cacheCo),
            BindingResource::storage(6, cacheCg),
            BindingResource::storage(7, shTables),
        };
        PIC_TRY_ASSIGN(VkDescriptorSet set, mKernel.makeSet(resources));
        mSets.push_back(set);
    }
    return {};
}

void CacheLightingPass::record(VkCommandBuffer cmd) {
    // Chunks write disjoint caches: no barrier between them.
    for (size_t k = 0; k < mSets.size(); ++k) {
        const CacheLightingPush push{mChunkFirst[k], mChunkCount[k], 0, 0};
        mKernel.dispatch(cmd, mSets[k], &push, groupsFor(push.cacheCount, mCachesPerGroup));
    }
}

}  // namespace pic::gpu
