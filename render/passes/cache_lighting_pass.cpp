#include "render/passes/cache_lighting_pass.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include <glm/gtc/packing.hpp>

#include "core/color.h"
#include "core/parallel.h"
#include "render/link_irradiance.h"
#include "render/node_spread.h"
#include "shaders/shared/cache_lighting.h"
#include "spirv/cache_lighting_comp.h"

namespace pic::gpu {
namespace {

/// Chunks hold a multiple of this many caches, so that every chunk's offset into the link
/// buffer is a multiple of 256 bytes (the largest minTexelBufferOffsetAlignment in use).
constexpr uint32_t kChunkAlignment = 256;

/// Node light, links, caches Y, Co, Cg, SH tables.
constexpr uint32_t kBindingCount = 8;

/// The uint texel format of `words` 32-bit components.
VkFormat uintTexelFormat(uint32_t words) {
    constexpr std::array<VkFormat, 4> kFormats = {VK_FORMAT_R32_UINT, VK_FORMAT_R32G32_UINT,
                                                  VK_FORMAT_R32G32B32_UINT,
                                                  VK_FORMAT_R32G32B32A32_UINT};
    return kFormats[words - 1];
}

/// The texel (in words, at most `maxWords`) to read a link of `linkWords` words in: of those
/// that divide it and that the device reads as a uniform texel buffer, 4 or 2 words before 3,
/// and a word (R32_UINT, which every device reads) if none does. Lavapipe loads a 2- or
/// 4-word texel with one load per lane but a 3-word one with two and more shuffles: read as
/// three 2-word texels, SH links of lY = 3 (6 words) light the moderate atrium's caches in
/// 0.89 of the time that two 3-word texels take (61 alternated passes). A GPU's loads favour
/// powers of two as well.
uint32_t linkTexelWords(const Context& context, uint32_t linkWords, uint32_t maxWords) {
    for (uint32_t words : {4u, 2u, 3u})
        if (words <= maxWords && linkWords % words == 0 &&
            context.canReadTexels(uintTexelFormat(words)))
            return words;
    return 1;
}

}  // namespace

GpuRtpLink packRtpLink(const RtpLink& link, uint32_t tint, uint32_t point, uint8_t spreadShare,
                       float nodeArea) {
    PIC_CHECK(link.node < (1u << kGpuLinkNodeBits));
    // V = factor·π·A: the bake's factor is V / (π·A) (bake/link_generation.cpp).
    const auto visible = float(double(link.factor) * std::numbers::pi * double(nodeArea));
    uint32_t half = floatToHalfClamped(std::max(visible, 0.0f));
    // A real link too faint for binary16 would read as padding; it keeps the smallest step.
    if (half == 0 && link.factor > 0.0f) half = 1;
    const uint32_t cone = floatToHalf(std::clamp(link.oneMinusCosAlpha, 0.0f, 2.0f));
    // snorm16 → snorm9 per octahedral coordinate, unorm10 → unorm8 per tint channel.
    const auto snorm9 = [](uint32_t snorm16) {
        return uint32_t(std::lround(float(int16_t(uint16_t(snorm16))) * (255.0f / 32767.0f))) &
               0x1FFu;
    };
    const auto unorm8 = [&](int channel) {
        return uint32_t(std::lround(float((tint >> (10 * channel)) & 0x3FFu) * (255.0f / 1023.0f)));
    };
    return {link.node | unorm8(0) << 24,
            snorm9(link.directionOct & 0xFFFFu) | snorm9(link.directionOct >> 16) << 9 |
                uint32_t(std::min<uint32_t>(spreadShare, kSpreadShareSteps)) << 18 | unorm8(1) << 24,
            half | (cone << 16), (point & 0xFFFFFFu) | unorm8(2) << 24};
}

uint16_t radianceShCoefficient(uint16_t coefficient, float nodeArea) {
    return floatToHalfClamped(
        float(double(halfToFloat(coefficient)) * std::numbers::pi * double(nodeArea)));
}

Result<std::unique_ptr<Pass>> CacheLightingPass::create(Context& context,
                                                        const PassConfig& config) {
    PIC_CHECK(config.bake != nullptr && config.spread != nullptr);
    const BakeData& bake = *config.bake;
    const NodeSpread& spread = *config.spread;
    const bool cachePerSubgroup = config.cachePerSubgroup;
    const uint32_t maxTexelWords = config.maxLinkTexelWords;
    std::unique_ptr<CacheLightingPass> pass(new CacheLightingPass());
    // Per subgroup: as many caches per workgroup as it has subgroups of the default size (the
    // shader strides over any the device leaves, should it launch fewer).
    pass->mCachesPerGroup =
        cachePerSubgroup ? std::max<uint32_t>(kCacheLightingGroup / context.subgroupSize(), 1)
                         : kCacheLightingGroup;
    const LinkSet& links = bake.links;
    if (bake.nodes.size() > (size_t{1} << kGpuLinkNodeBits))
        return fail(ErrorCode::Unsupported,
                    "the bake has {} hierarchy nodes ({} surfels); GPU links address at most "
                    "{} nodes ({} surfels): bake fewer surfels or relight on the CPU twin",
                    bake.nodes.size(), bake.surfels.size(), size_t{1} << kGpuLinkNodeBits,
                    size_t{1} << (kGpuLinkNodeBits - 1));
    PIC_CHECK_EQ(spread.centroid.size(), bake.nodes.size());
    // Where each link reads its node's spread, as the CPU twin's unpackLinks decodes it.
    const auto boxPoint = [&](size_t slot, uint32_t node) {
        glm::vec3 offset;
        for (int i = 0; i < 3; ++i) offset[i] = halfToFloat(links.offset[slot * 3 + i]);
        return encodeBoxPoint(spread, node, offset);
    };
    pass->mRtpForm = links.mode == LinkMode::Rtp;
    pass->mCacheCount = uint32_t(bake.caches.size());
    pass->mLinksPerCache = links.linksPerCache;
    pass->mCountY = bake.params.bandsY * bake.params.bandsY;
    const VkDeviceSize nLinks = VkDeviceSize{pass->mCacheCount} * links.linksPerCache;

    // A chunk's links fill at most one texel view.
    const uint32_t linkWords =
        pass->mRtpForm ? sizeof(GpuRtpLink) / sizeof(uint32_t) : shLinkWords(pass->mCountY);
    pass->mTexelWords = linkTexelWords(context, linkWords, maxTexelWords);
    const VkDeviceSize texelsPerCache = std::max<VkDeviceSize>(
        VkDeviceSize{linkWords / pass->mTexelWords} * links.linksPerCache, 1);
    const VkDeviceSize maxTexels = context.properties().limits.maxTexelBufferElements;
    const VkDeviceSize chunk = (maxTexels / texelsPerCache) / kChunkAlignment * kChunkAlignment;
    if (chunk == 0)
        return fail(ErrorCode::Unsupported,
                    "{} links per cache need {} texels per cache, too many for {} caches within "
                    "one texel view of {} texels",
                    links.linksPerCache, texelsPerCache, kChunkAlignment, maxTexels);
    for (uint32_t first = 0; first < pass->mCacheCount; first += uint32_t(chunk)) {
        pass->mChunkFirst.push_back(first);
        pass->mChunkCount.push_back(std::min<uint32_t>(uint32_t(chunk), pass->mCacheCount - first));
    }

    KernelLayout layout;
    layout.bindings.assign(kBindingCount, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER);
    layout.bindings[0] = VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;            // node light
    layout.bindings[1] = VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;            // links
    layout.bindings[5] = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;                  // SH tables
    layout.bindings[6] = VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;            // cache normals
    layout.pushBytes = sizeof(CacheLightingPush);
    layout.specialization = {bake.params.bandsY,
                             bake.params.bandsC,
                             links.linksPerCache,
                             pass->mRtpForm ? kLinkFormRtp : kLinkFormSh,
                             cachePerSubgroup ? kCachePerSubgroup : kCachePerInvocation,
                             pass->mTexelWords};
    layout.maxSets = std::max<uint32_t>(uint32_t(pass->mChunkFirst.size()), 1);
    PIC_TRY_ASSIGN(pass->mKernel,
                   Kernel::create(context, kSpirvCacheLightingComp, layout, "cache_lighting"));

    constexpr VkBufferUsageFlags kTexels = VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT;
    // The links take the node's radiance Φ / (π·A) rather than its flux (§4.7).
    if (pass->mRtpForm) {
        std::vector<GpuRtpLink> rtp(links.rtp.size());
        parallelFor(
            0, rtp.size(),
            [&](size_t i) {
                const RtpLink& link = links.rtp[i];
                // Padding (factor 0) may name any node; V = 0 marks it.
                rtp[i] = link.factor > 0.0f
                             ? packRtpLink(link, links.tint[i], boxPoint(i, link.node),
                                           links.spreadShare[i], bake.nodes[link.node].area)
                             : GpuRtpLink{};
            },
            4096);
        PIC_TRY_ASSIGN(pass->mLinks, Buffer::createWith(context, std::span<const GpuRtpLink>(rtp),
                                                        kTexels, "RTP links"));
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
                record[1] = links.tint[slot];
                record[2] = node == kNoNode
                                ? 0u
                                : boxPoint(slot, node) | uint32_t(links.spreadShare[slot]) << 24;
                const uint16_t* coefficients = links.shCoefficients.data() + slot * countY;
                for (uint32_t i = 0; i < countY; ++i)
                    record[3 + i / 2] |= uint32_t(radianceShCoefficient(coefficients[i], area))
                                         << (16 * (i % 2));
                // The half after the coefficients (shLinkWords leaves room): the link's
                // irradiance along a light-map cache's normal, also per unit of radiance.
                if (node != kNoNode)
                    record[3 + countY / 2] |=
                        uint32_t(floatToHalfClamped(float(double(linkIrradiance(bake, slot)) *
                                                          std::numbers::pi * double(area))))
                        << (16 * (countY % 2));
            },
            4096);
        PIC_TRY_ASSIGN(pass->mLinks, Buffer::createWith(context, std::span<const uint32_t>(sh),
                                                        kTexels, "SH links"));
    }
    // Light-map caches' normals for the irradiance along them; grid caches have none (w 0).
    std::vector<uint32_t> normals(bake.caches.size(), 0u);
    for (size_t c = 0; c < normals.size(); ++c)
        if (bake.caches[c].kind == kCacheKindLightmap)
            normals[c] = glm::packSnorm4x8(glm::vec4(bake.caches[c].normal, 1.0f));
    PIC_TRY_ASSIGN(pass->mNormals, Buffer::createWith(context, std::span<const uint32_t>(normals),
                                                      kTexels, "cache normals"));
    PIC_TRY_ASSIGN(pass->mNormalView,
                   TexelView::create(context, pass->mNormals, VK_FORMAT_R32_UINT, "cache normals"));
    pass->mLinkBytes = nLinks * linkWords * sizeof(uint32_t);
    const VkFormat format = uintTexelFormat(pass->mTexelWords);
    const VkDeviceSize texelBytes = VkDeviceSize{pass->mTexelWords} * sizeof(uint32_t);
    for (size_t k = 0; k < pass->mChunkFirst.size(); ++k) {
        const VkDeviceSize first = VkDeviceSize{pass->mChunkFirst[k]} * texelsPerCache;
        PIC_TRY_ASSIGN(TexelView view,
                       TexelView::create(context, pass->mLinks, format, first * texelBytes,
                                         pass->mChunkCount[k] * texelsPerCache, "links"));
        pass->mLinkViews.push_back(std::move(view));
    }
    return pass;
}

Result<void> CacheLightingPass::bind(Context& context, const Buffer& nodeLight,
                                     const Buffer& cacheY, const Buffer& cacheCo,
                                     const Buffer& cacheCg, const Buffer& cacheIrradiance,
                                     const Buffer& shTables) {
    mSets.clear();
    PIC_TRY(mKernel.resetSets());
    PIC_TRY_ASSIGN(mRadianceView, TexelView::create(context, nodeLight, VK_FORMAT_R32G32B32A32_UINT,
                                                    "node light"));
    for (size_t k = 0; k < mChunkFirst.size(); ++k) {
        const std::array<BindingResource, kBindingCount> resources = {
            BindingResource::texels(0, mRadianceView), BindingResource::texels(1, mLinkViews[k]),
            BindingResource::storage(2, cacheY),       BindingResource::storage(3, cacheCo),
            BindingResource::storage(4, cacheCg),      BindingResource::storage(5, shTables),
            BindingResource::texels(6, mNormalView),   BindingResource::storage(7, cacheIrradiance),
        };
        PIC_TRY_ASSIGN(VkDescriptorSet set, mKernel.makeSet(resources));
        mSets.push_back(set);
    }
    return {};
}

void CacheLightingPass::record(VkCommandBuffer cmd, const FrameResources&) {
    // Chunks write disjoint caches: no barrier between them.
    for (size_t k = 0; k < mSets.size(); ++k) {
        const CacheLightingPush push{mChunkFirst[k], mChunkCount[k], 0, 0};
        mKernel.dispatch(cmd, mSets[k], &push, groupsFor(push.cacheCount, mCachesPerGroup));
    }
}

}  // namespace pic::gpu
