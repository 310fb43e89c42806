#pragma once
/// Pull on the GPU (paper 000 Figure 2 step 3, §4.1): node flux = sum of its children's, with
/// the flux's first moment, one dispatch per hierarchy level, lowest first, and one for the
/// small upper levels together (shaders/shared/pull.h); each inner node's light, the radiance
/// of its flux spread at its box centre as RGBE8 (§4.7) and the spread's slopes, is written
/// for cache lighting. CPU twin: render/cpu/pull.h, with the node spreads of
/// render/node_spread.h.

#include <memory>
#include <vector>

#include "core/bake_data.h"
#include "gpu/device.h"
#include "gpu/kernel.h"
#include "gpu/resources.h"
#include "render/node_spread.h"
#include "render/passes/pass.h"

namespace pic::gpu {

/// 1 / (π·area): the radiance W/(m²·sr) of a Lambertian node per watt of its flux (paper 000
/// §4.1), as the pull scales it.
float radianceScale(float area);

/// Words 0-2 of a node's light as the pull packs them (shaders/shared/pull.h): its nine spread
/// slopes (columns: the R, G, B slopes of render/node_spread.h ChannelSpread or
/// ExponentialSpread) and, for an exponential spread, ln Z per channel.
glm::uvec3 packNodeSpread(const glm::mat3& slopes, const glm::vec3& concentration,
                          bool exponential);

/// A node's spread from words 0-2 of its light; returns whether it is exponential.
bool unpackNodeSpread(const glm::uvec3& packed, glm::mat3& slopes, glm::vec3& concentration);

class PullPass final : public Pass {
public:
    static constexpr PassKind kKind = PassKind::Pull;
    /// Uploads each inner node of config.bake: its two children, 1 / (π·area) and flux spread
    /// (config.spread = nodeSpread(bake)).
    static Result<std::unique_ptr<Pass>> create(Context& context, const PassConfig& config);
    /// Binds the node flux (vec4 per node; its usage must allow uniform texel buffers) and
    /// node light (4 words per node, shaders/shared/pull.h) buffers, whose leaves surfel
    /// lighting writes.
    Result<void> bind(Context& context, const Buffer& nodeFlux, const Buffer& nodeLight);
    /// Records every level with a barrier after each (the tail's levels with one between
    /// them inside its workgroup), so a level reads finished children (reads nothing of
    /// `frame`).
    void record(VkCommandBuffer cmd, const FrameResources& frame) override;
    VkDeviceSize bytes() const { return mInnerNodes.size() + mMoments.size(); }

private:
    PullPass() = default;
    Kernel mLevel;  ///< the shader specialised to kPullModeLevel
    Kernel mTail;   ///< and to kPullModeTail
    VkDescriptorSet mLevelSet = VK_NULL_HANDLE;
    VkDescriptorSet mTailSet = VK_NULL_HANDLE;
    uint32_t mTailLevel = 0;    ///< levels [mTailLevel, end) are the tail's
    Buffer mLevelOffsetBuffer;  ///< the bake's level offsets
    Buffer mInnerNodes;         ///< PullNode per inner node (none for a single surfel)
    TexelView mInnerView;       ///< mInnerNodes as RGBA32UI texels
    TexelView mFluxView;        ///< the node flux as RGBA32F texels
    Buffer mMoments;            ///< 3 vec4 per node: the flux's first moment per channel
    TexelView mMomentView;      ///< mMoments as RGBA32F texels
    uint32_t mSurfelCount = 0;
    std::vector<uint32_t> mLevelOffsets;
};

}  // namespace pic::gpu
