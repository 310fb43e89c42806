#include "server/passes/cache_lighting_pass.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "core/color.h"
#include "core/parallel.h"
#include "shaders/shared/cache_lighting.h"
#include "spirv/cache_lighting_comp.h"

namespace pic::gpu {
namespace {

/// Chunks hold a multiple of this many caches, so that every chunk's offset into the link
/// buffers is a multiple of 256 bytes (the largest minStorageBufferOffsetAlignment in use).
constexpr uint32_t kChunkAlignment = 256;

/// Node radiance, RTP links, SH links, caches Y, Co, Cg, SH tables.
constexpr uint32_t kBindingCount = 7;

}  // namespace

GpuRtpLink packRtpLink(const RtpLink& link, float nodeArea) {
    // V = factor·π·A: the bake's factor is V / (π·A) (bake/link_generation.cpp).
    const double visible =
        std::clamp(double(link.factor) * std::numbers::pi * double(nodeArea), 0.0, 1.0);
    auto unorm = uint32_t(std::lround(visible * 65535.0));
    // A real link too faint for unorm16 would read as padding; it keeps the smallest step.
    if (unorm == 0 && link.factor > 0.0f) unorm = 1;
    const uint32_t cone = floatToHalf(std::clamp(link.oneMinusCosAlpha, 0.0f, 2.0f));
    return {link.node, link.directionOct, unorm | (cone << 16)};
}

uint16_t radianceShCoefficient(uint16_t coefficient, float nodeArea) {
    return floatToHalfClamped(
        float(double(halfToFloat(coefficient)) * std::numbers::pi * double(nodeArea)));
}

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
    const VkDeviceSize widest =
        pass->mRtpForm ? sizeof(GpuRtpLink) : sizeof(uint32_t) * shLinkWords(pass->mCountY);
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
    layout.bindings.assign(kBindingCount, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER);
    layout.bindings[kBindingCount - 1] = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;  // SH tables
    layout.pushBytes = sizeof(CacheLightingPush);
    layout.specialization = {bake.params.bandsY, bake.params.bandsC, links.linksPerCache,
                             pass->mRtpForm ? kLinkFormRtp : kLinkFormSh,
                             cachePerSubgroup ? kCachePerSubgroup : kCachePerInvocation};
    layout.maxSets = std::max<uint32_t>(uint32_t(pass->mChunkFirst.size()), 1);
    PIC_TRY_ASSIGN(pass->mKernel,
                   Kernel::create(context, kSpirvCacheLightingComp, layout, "cache_lighting"));

    PIC_TRY_ASSIGN(pass->mUnused, context.createBuffer(16, 0, MemoryUse::Device, "unused links"));
    // The links take the node's radiance Φ / (π·A) rather than its flux (§4.7).
    if (pass->mRtpForm) {
        std::vector<GpuRtpLink> rtp(links.rtp.size());
        parallelFor(
            0, rtp.size(),
            [&](size_t i) {
                const RtpLink& link = links.rtp[i];
                // Padding (factor 0) may name any node; V = 0 marks it.
                rtp[i] = link.factor > 0.0f ? packRtpLink(link, bake.nodes[link.node].area)
                                            : GpuRtpLink{0, 0, 0};
            },
            4096);
        PIC_TRY_ASSIGN(pass->mRtp,
                       context.createBufferWith(std::span<const GpuRtpLink>(rtp), 0, "RTP links"));
        pass->mLinkBytes = nLinks * sizeof(GpuRtpLink);
    } else {
        const uint32_t countY = pass->mCountY;
        const size_t words = shLinkWords(countY);
        std::vector<uint32_t> sh(links.shNodes.size() * words, 0u);
        parallelFor(
            0, links.shNodes.size(),
            [&](size_t slot) {
                const uint32_t node = links.shNodes[slot];
                const float area = node == kNoNode ? 0.0f : bake.nodes[node].area;
                uint32_t* record = sh.data() + slot * words;
                record[0] = node;
                const uint16_t* coefficients = links.shCoefficients.data() + slot * countY;
                for (uint32_t i = 0; i < countY; ++i)
                    record[1 + i / 2] |= uint32_t(radianceShCoefficient(coefficients[i], area))
                                         << (16 * (i % 2));
            },
            4096);
        PIC_TRY_ASSIGN(pass->mSh,
                       context.createBufferWith(std::span<const uint32_t>(sh), 0, "SH links"));
        pass->mLinkBytes = nLinks * words * sizeof(uint32_t);
    }
    return pass;
}

Result<void> CacheLightingPass::bind(const Buffer& nodeRadiance, const Buffer& cacheY,
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
        const std::array<BindingResource, kBindingCount> resources = {
            BindingResource::storage(0, nodeRadiance),
            mRtpForm ? chunkOf(1, mRtp, sizeof(GpuRtpLink)) : BindingResource::storage(1, mUnused),
            mRtpForm ? BindingResource::storage(2, mUnused)
                     : chunkOf(2, mSh, sizeof(uint32_t) * shLinkWords(mCountY)),
            BindingResource::storage(3, cacheY),
            BindingResource::storage(4, cacheCo),
            BindingResource::storage(5, cacheCg),
            BindingResource::storage(6, shTables),
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
