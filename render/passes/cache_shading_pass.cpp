#include "render/passes/cache_shading_pass.h"

#include <algorithm>
#include <vector>

#include "core/color.h"
#include "spirv/cache_shading_comp.h"

namespace pic::gpu {
namespace {

/// shaders/cache_shading.comp bindings: four G-buffer samplers, lights, shadow layers, the shadow
/// maps, eight cache-texture buffers, the SH tables and the output.
constexpr uint32_t kBindingCount = 17;
constexpr uint32_t kShadowMapBinding = 6;
constexpr uint32_t kShTablesBinding = 15;

}  // namespace

Result<std::unique_ptr<Pass>> CacheShadingPass::create(Context& context, const PassConfig& config) {
    const uint32_t bandsY = config.bandsY, bandsC = config.bandsC;
    const glm::uvec3& gridDims = config.gridDims;
    const glm::uvec2& lightmapSize = config.lightmapSize;
    std::unique_ptr<CacheShadingPass> pass(new CacheShadingPass(context));
    pass->mCountY = bandsY * bandsY;
    pass->mCountC = bandsC * bandsC;
    pass->mGridVertices = uint64_t{gridDims.x} * gridDims.y * gridDims.z;
    pass->mLightmapTexels = uint64_t{lightmapSize.x} * lightmapSize.y;

    KernelLayout layout;
    layout.bindings.assign(kBindingCount, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER);
    for (uint32_t b = 0; b < kGbufferTargets; ++b)
        layout.bindings[b] = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    layout.bindings[kShadowMapBinding] = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    layout.bindings[kShTablesBinding] = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
    layout.pushBytes = sizeof(CacheShadingPush);
    layout.specialization = {bandsY, bandsC};
    PIC_TRY_ASSIGN(pass->mKernel,
                   Kernel::create(context, kSpirvCacheShadingComp, layout, "cache_shading"));

    // One buffer per channel and kind, as on the server (render/passes/lightmap_copy_pass.h);
    // each must fit one storage-buffer binding.
    const VkDeviceSize range = context.properties().limits.maxStorageBufferRange;
    const auto allocate = [&](uint64_t layers, uint64_t texels, const char* what,
                              Buffer& buffer) -> Result<void> {
        const VkDeviceSize bytes = 2 * layers * texels;
        if (bytes > range)
            return fail(ErrorCode::Unsupported,
                        "{} take {:.1f} MiB as half floats, more than the {:.1f} MiB one storage "
                        "buffer of \"{}\" holds",
                        what, double(bytes) / (1 << 20), double(range) / (1 << 20),
                        context.deviceName());
        PIC_TRY_ASSIGN(buffer, Buffer::create(context, bytes, 0, MemoryUse::Device, what));
        // Zero: no cache anywhere until the first setCaches.
        const std::vector<uint16_t> zeros(bytes / 2, 0);
        if (bytes > 0) PIC_TRY(context.upload(buffer, zeros.data(), bytes));
        return {};
    };
    for (int ch = 0; ch < 3; ++ch) {
        const uint64_t layers = ch == 0 ? pass->mCountY : pass->mCountC;
        PIC_TRY(allocate(layers, pass->mGridVertices, "grid textures", pass->mGrid[ch]));
        PIC_TRY(allocate(layers, pass->mLightmapTexels, "light-map textures", pass->mLightmap[ch]));
    }
    PIC_TRY(allocate(1, pass->mGridVertices, "grid coverage", pass->mGridCoverage));
    PIC_TRY(allocate(1, pass->mLightmapTexels, "light-map coverage", pass->mLightmapCoverage));
    return pass;
}

Result<void> CacheShadingPass::setCaches(const CacheTextures& textures) {
    std::vector<uint16_t> halves;
    const auto upload = [&](const std::vector<float>& values, Buffer& buffer) -> Result<void> {
        PIC_CHECK(2 * values.size() <= buffer.size());
        if (values.empty()) return {};
        halves.resize(values.size());
        // Half floats like the server's textures and the stream's frames; values beyond the
        // half range saturate rather than turning into infinities.
        for (size_t i = 0; i < values.size(); ++i) halves[i] = floatToHalfClamped(values[i]);
        return mContext.upload(buffer, halves.data(), halves.size() * sizeof(uint16_t));
    };
    for (int ch = 0; ch < 3; ++ch) {
        PIC_TRY(upload(textures.grid[ch], mGrid[ch]));
        PIC_TRY(upload(textures.lightmap[ch], mLightmap[ch]));
    }
    PIC_TRY(upload(textures.gridCoverage, mGridCoverage));
    return upload(textures.lightmapCoverage, mLightmapCoverage);
}

Result<void> CacheShadingPass::bind(const CacheShadingResources& r) {
    PIC_CHECK(r.gbuffer && r.shadows && r.shTables && r.radiance);
    const VkSampler sampler = mContext.nearestSampler();
    const std::array<BindingResource, kBindingCount> resources = {
        BindingResource::image(0, r.gbuffer->target(0).view(), sampler),
        BindingResource::image(1, r.gbuffer->target(1).view(), sampler),
        BindingResource::image(2, r.gbuffer->target(2).view(), sampler),
        BindingResource::image(3, r.gbuffer->target(3).view(), sampler),
        BindingResource::storage(4, r.shadows->lightBuffer()),
        BindingResource::storage(5, r.shadows->layerBuffer()),
        BindingResource::image(kShadowMapBinding, r.shadows->depth().arrayView(), sampler),
        BindingResource::storage(7, mGrid[0]),
        BindingResource::storage(8, mGrid[1]),
        BindingResource::storage(9, mGrid[2]),
        BindingResource::storage(10, mGridCoverage),
        BindingResource::storage(11, mLightmap[0]),
        BindingResource::storage(12, mLightmap[1]),
        BindingResource::storage(13, mLightmap[2]),
        BindingResource::storage(14, mLightmapCoverage),
        BindingResource::storage(kShTablesBinding, *r.shTables),
        BindingResource::storage(16, *r.radiance),
    };
    PIC_TRY(mKernel.resetSets());
    PIC_TRY_ASSIGN(mSet, mKernel.makeSet(resources));
    return {};
}

void CacheShadingPass::record(VkCommandBuffer cmd, const FrameResources& frame) {
    const CacheShadingPush& push = frame.shading;
    PIC_CHECK(mSet != VK_NULL_HANDLE);
    // Devices may cap a dispatch at 65535 workgroups along x (lavapipe does): large images
    // take several dispatches, each starting where the previous one ended.
    const uint64_t pixels = uint64_t{push.width} * push.height;
    const uint64_t maxGroups = mContext.properties().limits.maxComputeWorkGroupCount[0];
    const uint64_t chunk = maxGroups * kCacheShadingGroup;
    for (uint64_t first = 0; first < pixels; first += chunk) {
        CacheShadingPush part = push;
        part.firstPixel = uint32_t(first);
        mKernel.dispatch(cmd, mSet, &part,
                         groupsFor(std::min(chunk, pixels - first), kCacheShadingGroup));
    }
}

VkDeviceSize CacheShadingPass::bytes() const {
    VkDeviceSize total = mGridCoverage.size() + mLightmapCoverage.size();
    for (int ch = 0; ch < 3; ++ch) total += mGrid[ch].size() + mLightmap[ch].size();
    return total;
}

}  // namespace pic::gpu
