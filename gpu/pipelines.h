#pragma once
/// Shader modules, descriptor set and pipeline layouts, and pic's raster pipelines, each
/// returned as a Handle (handle.h) that destroys it. Compute pipelines are kernels (kernel.h).

#include <cstdint>
#include <span>

#include <vulkan/vulkan.h>

#include "core/error.h"
#include "gpu/handle.h"

namespace pic::gpu {

class Context;

/// A shader module from SPIR-V words; the error names the shader `what`.
Result<ShaderModule> createShaderModule(Context& context, std::span<const uint32_t> spirv,
                                        const char* what);

/// A descriptor set layout whose binding i holds one descriptor of type bindings[i], seen by
/// the shader `stages`.
Result<DescriptorSetLayout> createDescriptorSetLayout(Context& context,
                                                      std::span<const VkDescriptorType> bindings,
                                                      VkShaderStageFlags stages);

/// A descriptor pool for `maxSets` sets of a layout whose binding i has type bindings[i].
Result<DescriptorPool> createDescriptorPool(Context& context,
                                            std::span<const VkDescriptorType> bindings,
                                            uint32_t maxSets);

/// A pipeline layout with descriptor set layout `set` (none when null) and push-constant range
/// `push` (none when its size is 0).
Result<PipelineLayout> createPipelineLayout(Context& context, VkDescriptorSetLayout set,
                                            const VkPushConstantRange& push);

/// What differs between pic's raster pipelines. The rest is fixed: triangle lists, both faces
/// drawn (surfels and camera rays see either side of single-sided geometry), one sample,
/// dynamic viewport and scissor, dynamic rendering into a D32 depth attachment.
struct RasterPipelineDesc {
    std::span<const uint32_t> vertexSpirv;
    const char* vertexName = "";
    std::span<const uint32_t> fragmentSpirv;  ///< empty: a depth-only pipeline
    const char* fragmentName = "";
    VkVertexInputBindingDescription binding{};
    std::span<const VkVertexInputAttributeDescription> attributes;
    VkCompareOp depthCompare = VK_COMPARE_OP_LESS;
    VkCullModeFlags cullMode = VK_CULL_MODE_NONE;  ///< front faces wind counter-clockwise
    std::span<const VkFormat> colorFormats;        ///< one per colour attachment, all written
    VkPipelineLayout layout = VK_NULL_HANDLE;
};

/// A graphics pipeline as `desc` describes.
Result<Pipeline> createRasterPipeline(Context& context, const RasterPipelineDesc& desc);

}  // namespace pic::gpu
