#include "render/passes/lightmap_copy_pass.h"

#include <vector>

#include "core/color.h"
#include "shaders/shared/lightmap_copy.h"
#include "spirv/lightmap_copy_comp.h"

namespace pic::gpu {

Result<std::unique_ptr<Pass>> LightmapCopyPass::create(Context& context, const PassConfig& config) {
    PIC_CHECK(config.bake != nullptr);
    const BakeData& bake = *config.bake;
    std::unique_ptr<LightmapCopyPass> pass(new LightmapCopyPass());
    pass->mCountY = bake.params.bandsY * bake.params.bandsY;
    pass->mCountC = bake.params.bandsC * bake.params.bandsC;
    pass->mGridVertices = uint32_t(bake.grid.cacheIndex.size());
    pass->mLightmapTexels = uint32_t(bake.lightmap.cacheIndex.size());
    KernelLayout layout;
    layout.bindings.assign(7, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER);
    layout.pushBytes = sizeof(LightmapCopyPush);
    layout.specialization = {bake.params.bandsY, bake.params.bandsC};
    PIC_TRY_ASSIGN(pass->mKernel, Kernel::create(context, kSpirvLightmapCopyComp, layout, "lightmap_copy"));
    PIC_TRY_ASSIGN(pass->mGridIndex,
                   Buffer::createWith(context, std::span<const uint32_t>(bake.grid.cacheIndex), 0,
                                      "grid index"));
    PIC_TRY_ASSIGN(pass->mLightmapIndex,
                   Buffer::createWith(context, std::span<const uint32_t>(bake.lightmap.cacheIndex),
                                      0, "light-map index"));
    for (int ch = 0; ch < 3; ++ch) {
        const VkDeviceSize count = ch == 0 ? pass->mCountY : pass->mCountC;
        PIC_TRY_ASSIGN(pass->mGrid[ch], Buffer::create(context, 2 * count * pass->mGridVertices, 0,
                                                       MemoryUse::Device, "grid textures"));
        PIC_TRY_ASSIGN(pass->mLightmap[ch],
                       Buffer::create(context, 2 * count * pass->mLightmapTexels, 0,
                                      MemoryUse::Device, "light-map textures"));
    }
    return pass;
}

Result<void> LightmapCopyPass::bind(const Buffer& cacheY, const Buffer& cacheCo,
                                    const Buffer& cacheCg) {
    PIC_TRY(mKernel.resetSets());
    const auto setFor = [&](const Buffer& index, const std::array<Buffer, 3>& layers) {
        const std::array<BindingResource, 7> resources = {
            BindingResource::storage(0, index),   BindingResource::storage(1, cacheY),
            BindingResource::storage(2, cacheCo), BindingResource::storage(3, cacheCg),
            BindingResource::storage(4, layers[0]), BindingResource::storage(5, layers[1]),
            BindingResource::storage(6, layers[2]),
        };
        return mKernel.makeSet(resources);
    };
    PIC_TRY_ASSIGN(mGridSet, setFor(mGridIndex, mGrid));
    PIC_TRY_ASSIGN(mLightmapSet, setFor(mLightmapIndex, mLightmap));
    return {};
}

void LightmapCopyPass::record(VkCommandBuffer cmd, const FrameResources&) {
    const LightmapCopyPush grid{mGridVertices, 0, 0, 0};
    mKernel.dispatch(cmd, mGridSet, &grid, groupsFor(mGridVertices, kLightmapCopyGroup));
    const LightmapCopyPush lightmap{mLightmapTexels, 0, 0, 0};
    mKernel.dispatch(cmd, mLightmapSet, &lightmap, groupsFor(mLightmapTexels, kLightmapCopyGroup));
}

Result<void> LightmapCopyPass::read(Context& context, CacheTextures& out) const {
    std::vector<uint16_t> halves;
    const auto readLayers = [&](const Buffer& buffer, std::vector<float>& values) -> Result<void> {
        halves.resize(values.size());
        if (!halves.empty())
            PIC_TRY(context.download(buffer, halves.data(), halves.size() * sizeof(uint16_t)));
        for (size_t i = 0; i < halves.size(); ++i) values[i] = halfToFloat(halves[i]);
        return {};
    };
    for (int ch = 0; ch < 3; ++ch) {
        PIC_TRY(readLayers(mGrid[ch], out.grid[ch]));
        PIC_TRY(readLayers(mLightmap[ch], out.lightmap[ch]));
    }
    return {};
}

VkDeviceSize LightmapCopyPass::bytes() const {
    VkDeviceSize total = mGridIndex.size() + mLightmapIndex.size();
    for (int ch = 0; ch < 3; ++ch) total += mGrid[ch].size() + mLightmap[ch].size();
    return total;
}

}  // namespace pic::gpu
