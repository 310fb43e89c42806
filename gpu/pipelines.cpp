#include "gpu/pipelines.h"

#include <map>
#include <vector>

#include "gpu/device.h"
#include "gpu/vk_error.h"

namespace pic::gpu {

Result<ShaderModule> createShaderModule(Context& context, std::span<const uint32_t> spirv,
                                        const char* what) {
    VkShaderModuleCreateInfo info{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    info.codeSize = spirv.size_bytes();
    info.pCode = spirv.data();
    VkShaderModule module = VK_NULL_HANDLE;
    if (VkResult r = vkCreateShaderModule(context.device(), &info, nullptr, &module);
        r != VK_SUCCESS)
        return fail(ErrorCode::Internal, "shader {} could not be loaded: {}", what,
                    vkResultName(r));
    return ShaderModule(context.device(), module);
}

Result<DescriptorSetLayout> createDescriptorSetLayout(Context& context,
                                                      std::span<const VkDescriptorType> bindings,
                                                      VkShaderStageFlags stages) {
    std::vector<VkDescriptorSetLayoutBinding> layoutBindings;
    for (uint32_t b = 0; b < bindings.size(); ++b)
        layoutBindings.push_back({b, bindings[b], 1, stages, nullptr});
    VkDescriptorSetLayoutCreateInfo info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    info.bindingCount = uint32_t(layoutBindings.size());
    info.pBindings = layoutBindings.data();
    VkDescriptorSetLayout layout = VK_NULL_HANDLE;
    PIC_VK_TRY(vkCreateDescriptorSetLayout(context.device(), &info, nullptr, &layout));
    return DescriptorSetLayout(context.device(), layout);
}

Result<DescriptorPool> createDescriptorPool(Context& context,
                                            std::span<const VkDescriptorType> bindings,
                                            uint32_t maxSets) {
    std::map<VkDescriptorType, uint32_t> typeCounts;
    for (VkDescriptorType type : bindings) typeCounts[type] += maxSets;
    std::vector<VkDescriptorPoolSize> sizes;
    for (const auto& [type, count] : typeCounts) sizes.push_back({type, count});
    VkDescriptorPoolCreateInfo info{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    info.maxSets = maxSets;
    info.poolSizeCount = uint32_t(sizes.size());
    info.pPoolSizes = sizes.data();
    VkDescriptorPool pool = VK_NULL_HANDLE;
    PIC_VK_TRY(vkCreateDescriptorPool(context.device(), &info, nullptr, &pool));
    return DescriptorPool(context.device(), pool);
}

Result<PipelineLayout> createPipelineLayout(Context& context, VkDescriptorSetLayout set,
                                            const VkPushConstantRange& push) {
    VkPipelineLayoutCreateInfo info{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    info.setLayoutCount = set ? 1 : 0;
    info.pSetLayouts = &set;
    info.pushConstantRangeCount = push.size ? 1 : 0;
    info.pPushConstantRanges = &push;
    VkPipelineLayout layout = VK_NULL_HANDLE;
    PIC_VK_TRY(vkCreatePipelineLayout(context.device(), &info, nullptr, &layout));
    return PipelineLayout(context.device(), layout);
}

Result<Pipeline> createRasterPipeline(Context& context, const RasterPipelineDesc& desc) {
    PIC_TRY_ASSIGN(const ShaderModule vertex,
                   createShaderModule(context, desc.vertexSpirv, desc.vertexName));
    ShaderModule fragment;
    if (!desc.fragmentSpirv.empty()) {
        PIC_TRY_ASSIGN(fragment,
                       createShaderModule(context, desc.fragmentSpirv, desc.fragmentName));
    }
    VkPipelineShaderStageCreateInfo stages[2] = {
        {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO},
        {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO}};
    stages[0].stage = VK_SHADER_STAGE_VERTEX_BIT;
    stages[0].module = vertex.get();
    stages[0].pName = "main";
    stages[1].stage = VK_SHADER_STAGE_FRAGMENT_BIT;
    stages[1].module = fragment.get();
    stages[1].pName = "main";

    VkPipelineVertexInputStateCreateInfo vertexInput{
        VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
    vertexInput.vertexBindingDescriptionCount = 1;
    vertexInput.pVertexBindingDescriptions = &desc.binding;
    vertexInput.vertexAttributeDescriptionCount = uint32_t(desc.attributes.size());
    vertexInput.pVertexAttributeDescriptions = desc.attributes.data();
    VkPipelineInputAssemblyStateCreateInfo assembly{
        VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
    assembly.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
    VkPipelineViewportStateCreateInfo viewport{
        VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
    viewport.viewportCount = 1;
    viewport.scissorCount = 1;
    VkPipelineRasterizationStateCreateInfo raster{
        VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
    raster.polygonMode = VK_POLYGON_MODE_FILL;
    raster.cullMode = desc.cullMode;
    raster.frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE;
    raster.lineWidth = 1.0f;
    VkPipelineMultisampleStateCreateInfo multisample{
        VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
    multisample.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;
    VkPipelineDepthStencilStateCreateInfo depthState{
        VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO};
    depthState.depthTestEnable = VK_TRUE;
    depthState.depthWriteEnable = VK_TRUE;
    depthState.depthCompareOp = desc.depthCompare;
    std::vector<VkPipelineColorBlendAttachmentState> blendTargets(desc.colorFormats.size());
    for (auto& target : blendTargets)
        target.colorWriteMask = VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT |
                                VK_COLOR_COMPONENT_B_BIT | VK_COLOR_COMPONENT_A_BIT;
    VkPipelineColorBlendStateCreateInfo blend{
        VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
    blend.attachmentCount = uint32_t(blendTargets.size());
    blend.pAttachments = blendTargets.data();
    const VkDynamicState dynamicStates[] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR};
    VkPipelineDynamicStateCreateInfo dynamic{VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO};
    dynamic.dynamicStateCount = 2;
    dynamic.pDynamicStates = dynamicStates;
    VkPipelineRenderingCreateInfo rendering{VK_STRUCTURE_TYPE_PIPELINE_RENDERING_CREATE_INFO};
    rendering.colorAttachmentCount = uint32_t(desc.colorFormats.size());
    rendering.pColorAttachmentFormats = desc.colorFormats.data();
    rendering.depthAttachmentFormat = VK_FORMAT_D32_SFLOAT;
    VkGraphicsPipelineCreateInfo info{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO};
    info.pNext = &rendering;
    info.stageCount = fragment ? 2 : 1;
    info.pStages = stages;
    info.pVertexInputState = &vertexInput;
    info.pInputAssemblyState = &assembly;
    info.pViewportState = &viewport;
    info.pRasterizationState = &raster;
    info.pMultisampleState = &multisample;
    info.pDepthStencilState = &depthState;
    info.pColorBlendState = &blend;
    info.pDynamicState = &dynamic;
    info.layout = desc.layout;
    VkPipeline pipeline = VK_NULL_HANDLE;
    PIC_VK_TRY(
        vkCreateGraphicsPipelines(context.device(), VK_NULL_HANDLE, 1, &info, nullptr, &pipeline));
    return Pipeline(context.device(), pipeline);
}

}  // namespace pic::gpu
