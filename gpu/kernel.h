#pragma once
/// A compute pipeline with its descriptor layout: storage and uniform buffers, uniform texel
/// buffers and depth samplers by binding, push constants, uint specialization constants
/// (STYLE.md 11), and the descriptor sets that bind concrete resources to it.

#include <cstdint>
#include <span>
#include <vector>

#include "gpu/handle.h"
#include "gpu/resources.h"

namespace pic::gpu {

class Context;

/// One resource bound to a binding of a kernel's set.
struct BindingResource {
    uint32_t binding = 0;
    VkBuffer buffer = VK_NULL_HANDLE;      ///< storage or uniform buffer (null for an image)
    VkDeviceSize offset = 0;
    VkDeviceSize range = VK_WHOLE_SIZE;
    VkImageView imageView = VK_NULL_HANDLE;  ///< combined image sampler (depth array)
    VkSampler sampler = VK_NULL_HANDLE;
    VkBufferView texelView = VK_NULL_HANDLE;  ///< uniform texel buffer

    static BindingResource storage(uint32_t binding, const Buffer& buffer,
                                   VkDeviceSize offset = 0, VkDeviceSize range = VK_WHOLE_SIZE) {
        return {binding,        buffer.handle(), offset,        range,
                VK_NULL_HANDLE, VK_NULL_HANDLE,  VK_NULL_HANDLE};
    }
    static BindingResource image(uint32_t binding, VkImageView view, VkSampler sampler) {
        return {binding, VK_NULL_HANDLE, 0, 0, view, sampler, VK_NULL_HANDLE};
    }
    static BindingResource texels(uint32_t binding, const TexelView& view) {
        return {binding, VK_NULL_HANDLE, 0, 0, VK_NULL_HANDLE, VK_NULL_HANDLE, view.handle()};
    }
};

/// What a kernel binds.
struct KernelLayout {
    std::vector<VkDescriptorType> bindings;  ///< type of binding 0, 1, …
    uint32_t pushBytes = 0;                  ///< push-constant block size
    std::vector<uint32_t> specialization;    ///< values of constant_id 0, 1, …
    uint32_t maxSets = 4;                    ///< descriptor sets makeSet may create
};

/// A compute shader ready to dispatch.
class Kernel {
public:
    /// The compute pipeline of `spirv` with the bindings, push constants and specialization of
    /// `layout`, and a descriptor pool for its sets; `name` names it in errors.
    static Result<Kernel> create(Context& context, std::span<const uint32_t> spirv,
                                 const KernelLayout& layout, const char* name);
    /// A descriptor set binding `resources` (every binding of the layout exactly once).
    Result<VkDescriptorSet> makeSet(std::span<const BindingResource> resources);
    /// Frees every set makeSet created (before binding new resources).
    Result<void> resetSets();
    /// Records one dispatch of `groups` workgroups along x with push constants `push`.
    void dispatch(VkCommandBuffer cmd, VkDescriptorSet set, const void* push, uint32_t groups) const;

private:
    DescriptorSetLayout mSetLayout;
    DescriptorPool mPool;  ///< frees the sets makeSet created
    PipelineLayout mPipelineLayout;
    Pipeline mPipeline;
    std::vector<VkDescriptorType> mBindings;
    uint32_t mPushBytes = 0;
    const char* mName = "";
};

/// A full memory barrier between compute work (and transfers) recorded before and after it:
/// every shader or transfer write before is visible to every shader or transfer access after.
void computeBarrier(VkCommandBuffer cmd);

/// Workgroups of `groupSize` that cover `count` invocations.
inline uint32_t groupsFor(uint64_t count, uint32_t groupSize) {
    return uint32_t((count + groupSize - 1) / groupSize);
}

}  // namespace pic::gpu
