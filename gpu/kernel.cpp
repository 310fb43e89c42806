#include "gpu/kernel.h"

#include <map>

namespace pic::gpu {

Kernel& Kernel::operator=(Kernel&& other) noexcept {
    if (this != &other) {
        reset();
        mDevice = std::exchange(other.mDevice, VK_NULL_HANDLE);
        mSetLayout = std::exchange(other.mSetLayout, VK_NULL_HANDLE);
        mPipelineLayout = std::exchange(other.mPipelineLayout, VK_NULL_HANDLE);
        mPipeline = std::exchange(other.mPipeline, VK_NULL_HANDLE);
        mPool = std::exchange(other.mPool, VK_NULL_HANDLE);
        mBindings = std::move(other.mBindings);
        mPushBytes = other.mPushBytes;
        mName = other.mName;
    }
    return *this;
}

void Kernel::reset() {
    if (mDevice == VK_NULL_HANDLE) return;
    if (mPipeline) vkDestroyPipeline(mDevice, mPipeline, nullptr);
    if (mPipelineLayout) vkDestroyPipelineLayout(mDevice, mPipelineLayout, nullptr);
    if (mPool) vkDestroyDescriptorPool(mDevice, mPool, nullptr);
    if (mSetLayout) vkDestroyDescriptorSetLayout(mDevice, mSetLayout, nullptr);
    mDevice = VK_NULL_HANDLE;
}

Result<Kernel> Kernel::create(Context& context, std::span<const uint32_t> spirv,
                              const KernelLayout& layout, const char* name) {
    Kernel kernel;
    kernel.mDevice = context.device();
    kernel.mBindings = layout.bindings;
    kernel.mPushBytes = layout.pushBytes;
    kernel.mName = name;
    VkDevice device = context.device();

    std::vector<VkDescriptorSetLayoutBinding> bindings;
    std::map<VkDescriptorType, uint32_t> typeCounts;
    for (uint32_t b = 0; b < layout.bindings.size(); ++b) {
        bindings.push_back({b, layout.bindings[b], 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr});
        typeCounts[layout.bindings[b]] += layout.maxSets;
    }
    VkDescriptorSetLayoutCreateInfo setInfo{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    setInfo.bindingCount = uint32_t(bindings.size());
    setInfo.pBindings = bindings.data();
    PIC_VK_TRY(vkCreateDescriptorSetLayout(device, &setInfo, nullptr, &kernel.mSetLayout));

    std::vector<VkDescriptorPoolSize> sizes;
    for (const auto& [type, count] : typeCounts) sizes.push_back({type, count});
    VkDescriptorPoolCreateInfo poolInfo{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    poolInfo.maxSets = layout.maxSets;
    poolInfo.poolSizeCount = uint32_t(sizes.size());
    poolInfo.pPoolSizes = sizes.data();
    PIC_VK_TRY(vkCreateDescriptorPool(device, &poolInfo, nullptr, &kernel.mPool));

    const VkPushConstantRange push{VK_SHADER_STAGE_COMPUTE_BIT, 0, layout.pushBytes};
    VkPipelineLayoutCreateInfo pipelineLayoutInfo{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    pipelineLayoutInfo.setLayoutCount = 1;
    pipelineLayoutInfo.pSetLayouts = &kernel.mSetLayout;
    pipelineLayoutInfo.pushConstantRangeCount = layout.pushBytes ? 1 : 0;
    pipelineLayoutInfo.pPushConstantRanges = &push;
    PIC_VK_TRY(vkCreatePipelineLayout(device, &pipelineLayoutInfo, nullptr, &kernel.mPipelineLayout));

    std::vector<VkSpecializationMapEntry> entries;
    for (uint32_t i = 0; i < layout.specialization.size(); ++i)
        entries.push_back({i, uint32_t(i * sizeof(uint32_t)), sizeof(uint32_t)});
    VkSpecializationInfo specialization{uint32_t(entries.size()), entries.data(),
                                        layout.specialization.size() * sizeof(uint32_t),
                                        layout.specialization.data()};
    PIC_TRY_ASSIGN(VkShaderModule module, context.createShaderModule(spirv, name));
    VkComputePipelineCreateInfo pipelineInfo{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
    pipelineInfo.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
    pipelineInfo.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
    pipelineInfo.stage.module = module;
    pipelineInfo.stage.pName = "main";
    pipelineInfo.stage.pSpecializationInfo = entries.empty() ? nullptr : &specialization;
    pipelineInfo.layout = kernel.mPipelineLayout;
    const VkResult r =
        vkCreateComputePipelines(device, VK_NULL_HANDLE, 1, &pipelineInfo, nullptr, &kernel.mPipeline);
    vkDestroyShaderModule(device, module, nullptr);
    PIC_VK_TRY(r);
    return kernel;
}

Result<VkDescriptorSet> Kernel::makeSet(std::span<const BindingResource> resources) {
    PIC_CHECK_EQ(resources.size(), mBindings.size());
    VkDescriptorSetAllocateInfo info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    info.descriptorPool = mPool;
    info.descriptorSetCount = 1;
    info.pSetLayouts = &mSetLayout;
    VkDescriptorSet set = VK_NULL_HANDLE;
    PIC_VK_TRY(vkAllocateDescriptorSets(mDevice, &info, &set));

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
    vkUpdateDescriptorSets(mDevice, uint32_t(writes.size()), writes.data(), 0, nullptr);
    return set;
}

Result<void> Kernel::resetSets() {
    PIC_VK_TRY(vkResetDescriptorPool(mDevice, mPool, 0));
    return {};
}

void Kernel::dispatch(VkCommandBuffer cmd, VkDescriptorSet set, const void* push,
                      uint32_t groups) const {
    if (groups == 0) return;
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, mPipeline);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, mPipelineLayout, 0, 1, &set, 0,
                            nullptr);
    if (mPushBytes) vkCmdPushConstants(cmd, mPipelineLayout, VK_SHADER_STAGE_COMPUTE_BIT, 0, mPushBytes, push);
    vkCmdDispatch(cmd, groups, 1, 1);
}

}  // namespace pic::gpu
