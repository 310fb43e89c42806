#pragma once
/// Cache lighting on the GPU (paper 000 Figure 2 step 4, eq. 3, §4.6, §4.8): each cache's
/// incident radiance from its nL links, YCoCg with lY / lC bands, half floats. Links stay in
/// the bake's order, sequential per cache, and are read as uniform texel buffers in chunks of
/// caches so that no view exceeds the device's maxTexelBufferElements (2^27 on lavapipe).
/// CPU twin: render/cpu/cache_lighting.h.

#include <memory>
#include <vector>

#include "core/bake_data.h"
#include "gpu/device.h"
#include "gpu/kernel.h"
#include "gpu/resources.h"
#include "render/node_spread.h"
#include "render/passes/pass.h"
#include "shaders/shared/cache_lighting.h"

namespace pic::gpu {

/// The GPU's 16-byte form of a runtime-projected link with tint code `tint` (core/color.h
/// encodeLinkTint), box point `point` (render/node_spread.h encodeBoxPoint) and spread share code
/// `spreadShare` (core/bake_data.h encodeSpreadShare) whose node has area `nodeArea`
/// (shaders/shared/cache_lighting.h): the node index (below 2^24), V = factor·π·A as binary16
/// (clamped to 65504, at least the smallest subnormal for a link with factor > 0), 1 − cos α
/// as binary16, the direction as 2 × snorm9, the spread share in 6 bits and the tint as
/// 3 × unorm8.
GpuRtpLink packRtpLink(const RtpLink& link, uint32_t tint, uint32_t point, uint8_t spreadShare,
                       float nodeArea);
/// An SH link coefficient (binary16) rescaled to take the node's radiance instead of its flux:
/// c·π·A, clamped to ±65504.
uint16_t radianceShCoefficient(uint16_t coefficient, float nodeArea);

class CacheLightingPass final : public Pass {
public:
    static constexpr PassKind kKind = PassKind::CacheLighting;
    /// Uploads the links of config.bake (RTP: 16 bytes each, packRtpLink; SH: node index, tint, box
    /// point, lY² half coefficients, radianceShCoefficient, and the link's irradiance along a
    /// light-map cache's normal (render/link_irradiance.h linkIrradiance) rescaled alike, in
    /// shLinkWords(lY²) words) and the caches' normals, their box
    /// points in the boxes of config.spread (nodeSpread(bake)). Fails naming the count where
    /// the bake has more nodes than a GPU link addresses (2^24).
    /// config.cachePerSubgroup: a subgroup shares each cache's links (GPUs), else an invocation
    /// walks them (CPU devices); shaders/shared/cache_lighting.h says why. The links are read
    /// in uint texels of up to config.maxLinkTexelWords words that the device supports and
    /// that divide a link: 4 or 2 words before 3, else one.
    static Result<std::unique_ptr<Pass>> create(Context& context, const PassConfig& config);
    /// Binds the node light (4 words per node, shaders/shared/pull.h; its usage must allow
    /// uniform texel buffers), the output caches (half), the output irradiance along the
    /// light-map caches' normals (vec4 per cache, CacheValues::irradiance) and the SH tables.
    Result<void> bind(Context& context, const Buffer& nodeLight, const Buffer& cacheY,
                      const Buffer& cacheCo, const Buffer& cacheCg, const Buffer& cacheIrradiance,
                      const Buffer& shTables);
    /// Lights every cache, chunk by chunk (reads nothing of `frame`).
    void record(VkCommandBuffer cmd, const FrameResources& frame) override;
    /// Link bytes read per update.
    VkDeviceSize linkBytes() const { return mLinkBytes; }
    VkDeviceSize bytes() const { return mLinks.size(); }
    /// 32-bit words per texel the links are read in (1 to 4).
    uint32_t texelWords() const { return mTexelWords; }
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
    uint32_t mTexelWords = 1;
    Buffer mLinks;            ///< RTP: GpuRtpLink per link; SH: shLinkWords(lY²) words per link
    TexelView mRadianceView;  ///< node radiance as uint texels
    Buffer mNormals;          ///< per cache: packSnorm4x8(normal, 1) (light map) or 0 (grid)
    TexelView mNormalView;
    std::vector<TexelView> mLinkViews;  ///< per chunk: its links, mTexelWords words per texel
    std::vector<uint32_t> mChunkFirst;
    std::vector<uint32_t> mChunkCount;
    std::vector<VkDescriptorSet> mSets;
};

}  // namespace pic::gpu
