#include "render/passes/surfel_lighting_pass.h"

#include <array>

#include "core/cache_values.h"
#include "core/geometry.h"
#include "core/parallel.h"
#include "render/surfel_visibility.h"
#include "shaders/shared/surfel_lighting.h"
#include "spirv/surfel_lighting_comp.h"

namespace pic::gpu {
namespace {

constexpr uint32_t kBindingCount = 19;
constexpr uint32_t kSamplerBinding = 4;
constexpr uint32_t kShTablesBinding = 11;
/// Bindings read as uniform texel buffers (shaders/surfel_lighting.comp says why).
constexpr std::array<uint32_t, 11> kTexelBindings = {0, 1, 3, 7, 8, 9, 10, 13, 15, 16, 17};
constexpr VkBufferUsageFlags kTexels = VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT;
static_assert(kSkyCoefficients == 9, "shaders/surfel_lighting.comp reads 9 sky coefficients");

}  // namespace

const char* directVisibilityName(DirectVisibility visibility) {
    return visibility == DirectVisibility::Rays ? "rays" : "shadow-maps";
}

Result<std::optional<DirectVisibility>> parseDirectVisibility(std::string_view text) {
    if (text == "auto") return std::nullopt;
    if (text == "shadow-maps") return DirectVisibility::ShadowMaps;
    if (text == "rays") return DirectVisibility::Rays;
    return fail(ErrorCode::InvalidInput,
                "direct visibility \"{}\" is none of auto, shadow-maps, rays", text);
}

Result<std::unique_ptr<Pass>> SurfelLightingPass::create(Context& context,
                                                         const PassConfig& config) {
    PIC_CHECK(config.scene != nullptr && config.bake != nullptr && config.rays != nullptr);
    const Scene& scene = *config.scene;
    const BakeData& bake = *config.bake;
    const std::vector<CacheStencil> stencils = surfelStencils(scene, *config.rays, bake);
    PIC_CHECK_EQ(stencils.size(), bake.surfels.size());
    const float epsilon = config.rays->epsilon();
    const DirectVisibility visibility = config.visibility;
    std::unique_ptr<SurfelLightingPass> pass(new SurfelLightingPass(context, scene));
    pass->mSurfelCount = uint32_t(bake.surfels.size());
    pass->mEpsilon = epsilon;
    pass->mVisibility = visibility;
    const bool rays = visibility == DirectVisibility::Rays;

    KernelLayout layout;
    layout.bindings.assign(kBindingCount, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER);
    layout.bindings[kSamplerBinding] = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    for (uint32_t b : kTexelBindings) layout.bindings[b] = VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
    layout.bindings[kShTablesBinding] = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
    layout.pushBytes = sizeof(SurfelLightingPush);
    layout.specialization = {bake.params.bandsY, bake.params.bandsC,
                             rays ? kSurfelModeDirectRays : kSurfelModeDirect};
    PIC_TRY_ASSIGN(pass->mDirect, Kernel::create(context, kSpirvSurfelLightingComp, layout,
                                                 "surfel_lighting (direct)"));
    layout.specialization.back() = kSurfelModeBounce;
    PIC_TRY_ASSIGN(pass->mBounce, Kernel::create(context, kSpirvSurfelLightingComp, layout,
                                                 "surfel_lighting (bounce)"));

    // The bounce reads the caches at fixed points: each surfel's stencil is uploaded once.
    const size_t nS = bake.surfels.size();
    std::vector<SurfelStencil> records(nS);
    parallelFor(0, nS, [&](size_t i) {
        const CacheStencil& s = stencils[i];
        SurfelStencil& out = records[i];
        out = SurfelStencil{};
        for (int k = 0; k < s.count; ++k) {
            // A negative weight reads the cache's irradiance along its normal
            // (CacheStencil::alongNormal), a positive one its SH.
            const float weight = (s.alongNormal & (1u << k)) ? -s.weight[k] : s.weight[k];
            if (k < 4) {
                out.cacheLow[k] = s.cache[k];
                out.weightLow[k] = weight;
            } else {
                out.cacheHigh[k - 4] = s.cache[k];
                out.weightHigh[k - 4] = weight;
            }
        }
    }, 1024);

    PIC_TRY_ASSIGN(pass->mSurfels,
                   Buffer::createWith(context, bake.surfels.data(), nS * sizeof(pic::Surfel),
                                      kTexels, "surfels"));
    PIC_TRY_ASSIGN(pass->mStencils,
                   Buffer::createWith(context, std::span<const SurfelStencil>(records), kTexels,
                                      "surfel stencils"));
    PIC_TRY_ASSIGN(
        pass->mEmissiveScale,
        Buffer::create(context, std::max<size_t>(scene.materials.size(), 1) * sizeof(float),
                       kTexels, MemoryUse::Device, "emissive scales"));
    PIC_TRY_ASSIGN(pass->mDirectFlux, Buffer::create(context, nS * sizeof(glm::vec4), kTexels,
                                                     MemoryUse::Device, "direct flux"));
    // Records as RGBA32UI texels (their floats bit casts), flux as RGBA32F.
    PIC_TRY_ASSIGN(pass->mSurfelView, TexelView::create(context, pass->mSurfels,
                                                        VK_FORMAT_R32G32B32A32_UINT, "surfels"));
    PIC_TRY_ASSIGN(pass->mStencilView,
                   TexelView::create(context, pass->mStencils, VK_FORMAT_R32G32B32A32_UINT,
                                     "surfel stencils"));
    PIC_TRY_ASSIGN(pass->mEmissiveView, TexelView::create(context, pass->mEmissiveScale,
                                                          VK_FORMAT_R32_SFLOAT, "emissive scales"));
    PIC_TRY_ASSIGN(pass->mDirectFluxView,
                   TexelView::create(context, pass->mDirectFlux, VK_FORMAT_R32G32B32A32_SFLOAT,
                                     "direct flux"));
    PIC_TRY_ASSIGN(
        pass->mGroupFlux,
        Buffer::create(context, 2 * groupsFor(nS, kSurfelLightingGroup) * sizeof(glm::vec4), 0,
                       MemoryUse::Readback, "surfel flux sums"));
    // The sky's transfer, or a placeholder for bakes without one (the pass then adds no sky).
    pass->mHasSkyTransfer = !bake.surfelSky.empty();
    const std::vector<float> noTransfer(1, 0.0f);
    PIC_TRY_ASSIGN(pass->mSurfelSky,
                   Buffer::createWith(context,
                                      std::span<const float>(pass->mHasSkyTransfer ? bake.surfelSky
                                                                                   : noTransfer),
                                      kTexels, "surfel sky transfer"));
    PIC_TRY_ASSIGN(pass->mSurfelSkyView, TexelView::create(context, pass->mSurfelSky,
                                                           VK_FORMAT_R32_SFLOAT, "surfel sky"));
    PIC_TRY_ASSIGN(pass->mSkySh, Buffer::create(context, kSkyCoefficients * sizeof(glm::vec4), 0,
                                                MemoryUse::Device, "sky SH"));
    // Both modes share one shader, which declares both sources: the one not in use is bound to
    // a placeholder.
    if (rays) {
        PIC_TRY_ASSIGN(pass->mUnusedLayers, Buffer::create(context, sizeof(GpuShadowLayer), 0,
                                                           MemoryUse::Device, "unused"));
        PIC_TRY_ASSIGN(pass->mUnusedDepth, DepthArray::create(context, kMinShadowSide, 1));
    } else {
        PIC_TRY_ASSIGN(pass->mUnusedVisibility, Buffer::create(context, sizeof(uint32_t), kTexels,
                                                               MemoryUse::Device, "unused"));
    }
    return pass;
}

Result<void> SurfelLightingPass::bind(const SurfelLightingResources& r) {
    const bool rays = mVisibility == DirectVisibility::Rays;
    PIC_CHECK(rays ? r.rays != nullptr : r.shadows != nullptr);
    PIC_CHECK(r.nodeFlux && r.nodeRadiance && r.cacheY && r.cacheCo && r.cacheCg &&
              r.cacheIrradiance && r.shTables);
    PIC_TRY(mDirect.resetSets());
    PIC_TRY(mBounce.resetSets());
    const Buffer& lights = rays ? r.rays->lightBuffer() : r.shadows->lightBuffer();
    const Buffer& visibility = rays ? r.rays->visibilityBuffer() : mUnusedVisibility;
    PIC_TRY_ASSIGN(mLightView,
                   TexelView::create(mContext, lights, VK_FORMAT_R32G32B32A32_UINT, "lights"));
    PIC_TRY_ASSIGN(mVisibilityView,
                   TexelView::create(mContext, visibility, VK_FORMAT_R32_UINT, "visibility"));
    const std::array<const Buffer*, 3> caches = {r.cacheY, r.cacheCo, r.cacheCg};
    for (size_t c = 0; c < caches.size(); ++c) {
        PIC_TRY_ASSIGN(mCacheViews[c],
                       TexelView::create(mContext, *caches[c], VK_FORMAT_R16_SFLOAT, "caches"));
    }
    PIC_TRY_ASSIGN(mIrradianceView, TexelView::create(mContext, *r.cacheIrradiance,
                                                      VK_FORMAT_R32G32B32A32_SFLOAT, "irradiance"));
    const std::array<BindingResource, kBindingCount> resources = {
        BindingResource::texels(0, mSurfelView),
        BindingResource::texels(1, mLightView),
        BindingResource::storage(2, rays ? mUnusedLayers : r.shadows->layerBuffer()),
        BindingResource::texels(3, mEmissiveView),
        BindingResource::image(4, (rays ? mUnusedDepth : r.shadows->depth()).arrayView(),
                               mContext.nearestSampler()),
        BindingResource::storage(5, mDirectFlux),
        BindingResource::storage(6, *r.nodeFlux),
        BindingResource::texels(7, mStencilView),
        BindingResource::texels(8, mCacheViews[0]),
        BindingResource::texels(9, mCacheViews[1]),
        BindingResource::texels(10, mCacheViews[2]),
        BindingResource::storage(11, *r.shTables),
        BindingResource::storage(12, mGroupFlux),
        BindingResource::texels(13, mVisibilityView),
        BindingResource::storage(14, *r.nodeRadiance),
        BindingResource::texels(15, mDirectFluxView),
        BindingResource::texels(16, mIrradianceView),
        BindingResource::texels(17, mSurfelSkyView),
        BindingResource::storage(18, mSkySh),
    };
    PIC_TRY_ASSIGN(mDirectSet, mDirect.makeSet(resources));
    PIC_TRY_ASSIGN(mBounceSet, mBounce.makeSet(resources));
    return {};
}

Result<void> SurfelLightingPass::setEmissiveScales(const LightSet& lights) {
    std::vector<float> scales(std::max<size_t>(mScene.materials.size(), 1), 1.0f);
    for (size_t m = 0; m < mScene.materials.size(); ++m)
        scales[m] = lights.emissiveScaleOf(mScene.materials[m].name);
    return mContext.uploadWithNextSubmit(mEmissiveScale, scales.data(), scales.size() * sizeof(float));
}

Result<void> SurfelLightingPass::setSky(const std::array<glm::vec3, kSkyCoefficients>* sh) {
    mSky = sh != nullptr;
    if (!sh) return {};
    PIC_CHECK(mHasSkyTransfer);
    std::array<glm::vec4, kSkyCoefficients> padded;
    for (int k = 0; k < kSkyCoefficients; ++k) padded[size_t(k)] = glm::vec4((*sh)[size_t(k)], 0.0f);
    return mContext.uploadWithNextSubmit(mSkySh, padded.data(), sizeof(padded));
}

void SurfelLightingPass::record(VkCommandBuffer cmd, const FrameResources& frame) {
    PIC_CHECK(frame.sumSlot < 2);
    PIC_CHECK(mDirectSet != VK_NULL_HANDLE && mBounceSet != VK_NULL_HANDLE);
    SurfelLightingPush push{};
    push.surfelCount = mSurfelCount;
    push.lightCount = frame.lightCount;
    push.epsilon = mEpsilon;
    push.sumSlot = frame.sumSlot;
    push.tail = glm::vec4(frame.tail, 0.0f);
    push.sky = mSky && !frame.bounce ? 1u : 0u;
    const Kernel& kernel = frame.bounce ? mBounce : mDirect;
    kernel.dispatch(cmd, frame.bounce ? mBounceSet : mDirectSet, &push,
                    groupsFor(mSurfelCount, kSurfelLightingGroup));
}

Result<glm::dvec3> SurfelLightingPass::totalFlux(uint32_t sumSlot) {
    PIC_CHECK(sumSlot < 2);
    const uint32_t groups = groupsFor(mSurfelCount, kSurfelLightingGroup);
    std::vector<glm::vec4> sums(groups);
    PIC_TRY(mContext.download(mGroupFlux, sums.data(), groups * sizeof(glm::vec4),
                              sumSlot * groups * sizeof(glm::vec4)));
    glm::dvec3 total(0.0);
    for (const glm::vec4& s : sums) total += glm::dvec3(s);
    return total;
}

VkDeviceSize SurfelLightingPass::bytes() const {
    return mSurfels.size() + mStencils.size() + mEmissiveScale.size() + mDirectFlux.size() +
           mGroupFlux.size() + mUnusedLayers.size() + mUnusedVisibility.size() +
           mSurfelSky.size() + mSkySh.size();
}

}  // namespace pic::gpu
