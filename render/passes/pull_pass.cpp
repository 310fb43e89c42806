#include "render/passes/pull_pass.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include <glm/glm.hpp>
#include <glm/gtc/packing.hpp>

#include "core/color.h"
#include "render/node_spread.h"
#include "shaders/shared/pull.h"
#include "spirv/pull_comp.h"

namespace pic::gpu {

float radianceScale(float area) {
    return float(1.0 / (std::numbers::pi * double(area)));
}

namespace {

/// snorm8 of v ∈ [−1, 1], rounded towards zero or to nearest, in the low byte.
uint32_t snorm8(float v, bool towardsZero) {
    const float scaled = std::clamp(v, -1.0f, 1.0f) * 127.0f;
    return uint32_t(uint8_t(int8_t(towardsZero ? std::trunc(scaled) : std::round(scaled))));
}

/// unorm7 of ln Z over [0, kConcentrationRange], rounded to nearest.
uint32_t concentrationBits(float concentration) {
    return uint32_t(std::round(std::clamp(concentration / kConcentrationRange, 0.0f, 1.0f) * 127.0f));
}

}  // namespace

glm::uvec3 packNodeSpread(const glm::mat3& slopes, const glm::vec3& concentration,
                          bool exponential) {
    const float scale = exponential ? 1.0f / kExponentialSpreadCap : 1.0f;
    std::array<uint32_t, 9> bytes;
    for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 3; ++k) bytes[3 * c + k] = snorm8(slopes[c][k] * scale, !exponential);
    glm::uvec3 packed(bytes[0] | bytes[1] << 8 | bytes[2] << 16 | bytes[3] << 24,
                      bytes[4] | bytes[5] << 8 | bytes[6] << 16 | bytes[7] << 24, bytes[8]);
    if (exponential)
        packed.z |= concentrationBits(concentration.r) << 8 |
                    concentrationBits(concentration.g) << 15 |
                    concentrationBits(concentration.b) << 22 | kNodeLightExponentialBit;
    return packed;
}

bool unpackNodeSpread(const glm::uvec3& packed, glm::mat3& slopes, glm::vec3& concentration) {
    const glm::vec4 a = glm::unpackSnorm4x8(packed.x), b = glm::unpackSnorm4x8(packed.y);
    const float z = glm::unpackSnorm4x8(packed.z & 0xFFu).x;
    slopes = glm::mat3(glm::vec3(a), glm::vec3(a.w, b.x, b.y), glm::vec3(b.z, b.w, z));
    const bool exponential = (packed.z & kNodeLightExponentialBit) != 0;
    concentration = glm::vec3(0.0f);
    if (!exponential) return false;
    slopes *= kExponentialSpreadCap;
    for (int c = 0; c < 3; ++c)
        concentration[c] = float((packed.z >> (8 + 7 * c)) & 0x7Fu) / 127.0f * kConcentrationRange;
    return true;
}

Result<std::unique_ptr<Pass>> PullPass::create(Context& context, const PassConfig& config) {
    PIC_CHECK(config.bake != nullptr && config.spread != nullptr);
    const BakeData& bake = *config.bake;
    const NodeSpread& spread = *config.spread;
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
    layout.bindings = {
        VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,      VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER,
        VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,      VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER,
        VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,      VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
        VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER};
    layout.pushBytes = sizeof(PullPush);
    layout.specialization = {kPullModeLevel};
    PIC_TRY_ASSIGN(pass->mLevel, Kernel::create(context, kSpirvPullComp, layout, "pull (level)"));
    layout.specialization = {kPullModeTail};
    PIC_TRY_ASSIGN(pass->mTail, Kernel::create(context, kSpirvPullComp, layout, "pull (tail)"));
    // The children, the area and the flux spread (render/node_spread.h).
    PIC_CHECK_EQ(spread.centroid.size(), bake.nodes.size());
    std::vector<PullNode> inner(bake.nodes.size() - nS);
    for (size_t n = nS; n < bake.nodes.size(); ++n) {
        const Node& node = bake.nodes[n];
        const glm::mat3& axes = spread.axes[n];
        const glm::vec3 &low = spread.low[n], &centroid = spread.centroid[n];
        inner[n - nS] = {node.left,
                         node.right,
                         radianceScale(node.area),
                         0,
                         axes[0],
                         low.x,
                         axes[1],
                         low.y,
                         axes[2],
                         low.z,
                         spread.inverseVariance[n],
                         0.0f,
                         spread.high[n],
                         0.0f,
                         spread.centroid[node.left] - centroid,
                         0.0f,
                         spread.centroid[node.right] - centroid,
                         0.0f};
    }
    if (inner.empty()) return pass;  // a single surfel: nothing to pull
    // The leaves' moments are zero and stay so: only inner nodes are written.
    const std::vector<glm::vec4> zeros(3 * bake.nodes.size(), glm::vec4(0.0f));
    PIC_TRY_ASSIGN(pass->mMoments,
                   Buffer::createWith(context, std::span<const glm::vec4>(zeros),
                                      VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT, "node moments"));
    PIC_TRY_ASSIGN(
        pass->mMomentView,
        TexelView::create(context, pass->mMoments, VK_FORMAT_R32G32B32A32_SFLOAT, "node moments"));
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

Result<void> PullPass::bind(Context& context, const Buffer& nodeFlux, const Buffer& nodeLight) {
    if (!mInnerNodes.handle()) return {};
    PIC_TRY(mLevel.resetSets());
    PIC_TRY(mTail.resetSets());
    PIC_TRY_ASSIGN(mFluxView, TexelView::create(context, nodeFlux, VK_FORMAT_R32G32B32A32_SFLOAT,
                                                "node flux"));
    const std::array<BindingResource, 7> resources = {
        BindingResource::storage(0, nodeFlux),           BindingResource::texels(1, mInnerView),
        BindingResource::storage(2, nodeLight),          BindingResource::texels(3, mFluxView),
        BindingResource::storage(4, mLevelOffsetBuffer), BindingResource::storage(5, mMoments),
        BindingResource::texels(6, mMomentView)};
    PIC_TRY_ASSIGN(mLevelSet, mLevel.makeSet(resources));
    PIC_TRY_ASSIGN(mTailSet, mTail.makeSet(resources));
    return {};
}

void PullPass::record(VkCommandBuffer cmd, const FrameResources&) {
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
