#include "gpu/kernel.h"

#include "gpu/device.h"
#include "gpu/pipelines.h"
#include "gpu/vk_error.h"

namespace pic::gpu {

Result<Kernel> Kernel::create(Context& context, std::span<const uint32_t> spirv,
                              const KernelLayout& layout, const char* name) {
    Kernel kernel;
    kernel.mBindings = layout.bindings;
    kernel.mPushBytes = layout.pushBytes;
    kernel.mName = name;
    PIC_TRY_ASSIGN(kernel.mSetLayout, createDescriptorSetLayout(context, layout.bindings,
                                                                VK_SHADER_STAGE_COMPUTE_BIT));
    PIC_TRY_ASSIGN(kernel.mPool, createDescriptorPool(context, layout.bindings, layout.maxSets));
    PIC_TRY_ASSIGN(kernel.mPipelineLayout,
                   createPipelineLayout(context, kernel.mSetLayout.get(),
                                        {VK_SHADER_STAGE_COMPUTE_BIT, 0, layout.pushBytes}));

    std::vector<VkSpecializationMapEntry> entries;
    for (uint32_t i = 0; i < layout.specialization.size(); ++i)
        entries.push_back({i, uint32_t(i * sizeof(uint32_t)), sizeof(uint32_t)});
    VkSpecializationInfo specialization{uint32_t(entries.size()), entries.data(),
                                        layout.specialization.size() * sizeof(uint32_t),
                                        layout.specialization.data()};
    PIC_TRY_ASSIGN(const ShaderModule module, createShaderModule(context, spirv, name));
    VkComputePipelineCreateInfo pipelineInfo{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
    pipelineInfo.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
    pipelineInfo.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
    pipelineInfo.stage.module = module.get();
    pipelineInfo.stage.pName = "main";
    pipelineInfo.stage.pSpecializationInfo = entries.empty() ? nullptr : &specialization;
    pipelineInfo.layout = kernel.mPipelineLayout.get();
    VkPipeline pipeline = VK_NULL_HANDLE;
    PIC_VK_TRY(vkCreateComputePipelines(context.device(), VK_NULL_HANDLE, 1, &pipelineInfo, nullptr,
                                        &pipeline));
    kernel.mPipeline = {context.device(), pipeline};
    return kernel;
}

Result<VkDescriptorSet> Kernel::makeSet(std::span<const BindingResource> resources) {
    PIC_CHECK_EQ(resources.size(), mBindings.size());
    VkDescriptorSetAllocateInfo info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    info.descriptorPool = mPool.get();
    info.descriptorSetCount = 1;
    const VkDescriptorSetLayout setLayout = mSetLayout.get();
    info.pSetLayouts = &setLayout;
    VkDescriptorSet set = VK_NULL_HANDLE;
    PIC_VK_TRY(vkAllocateDescriptorSets(mPool.device(), &info, &set));

    std::vector<VkDescriptorBufferInfo> buffers(resources.size());
    std::vector<VkDescriptorImageInfo> images(resources.size());
    std::vector<VkWriteDescriptorSet> writes;
    for (size_t i = 0; i < resources.size(); ++i) {
        const BindingResource& r = resources[i];
        PIC_CHECK(r.binding < mBindings.size());
        VkWriteDescriptorSet write{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
        write.dstSet = set;
        write.dstBinding = r.binding;
        write.descriptorCount = 1;
        write.descriptorType = mBindings[r.binding];
        if (write.descriptorType == VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER) {
            images[i] = {r.sampler, r.imageView, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
            write.pImageInfo = &images[i];
        } else if (write.descriptorType == VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER) {
            write.pTexelBufferView = &resources[i].texelView;
        } else {
            buffers[i] = {r.buffer, r.offset, r.range};
            write.pBufferInfo = &buffers[i];
        }
        writes.push_back(write);
    }
    vkUpdateDescriptorSets(mPool.device(), uint32_t(writes.size()), writes.data(), 0, nullptr);
    return set;
}

Result<void> Kernel::resetSets() {
    PIC_VK_TRY(vkResetDescriptorPool(mPool.device(), mPool.get(), 0));
    return {};
}

void Kernel::dispatch(VkCommandBuffer cmd, VkDescriptorSet set, const void* push,
                      uint32_t groups) const {
    if (groups == 0) return;
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, mPipeline.get());
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, mPipelineLayout.get(), 0, 1, &set,
                            0, nullptr);
    if (mPushBytes)
        vkCmdPushConstants(cmd, mPipelineLayout.get(), VK_SHADER_STAGE_COMPUTE_BIT, 0, mPushBytes,
                           push);
    vkCmdDispatch(cmd, groups, 1, 1);
}

void computeBarrier(VkCommandBuffer cmd) {
    VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    barrier.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
    barrier.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT |
                            VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
    const VkPipelineStageFlags stages =
        VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT;
    vkCmdPipelineBarrier(cmd, stages, stages, 0, 1, &barrier, 0, nullptr, 0, nullptr);
}

}  // namespace pic::gpu
