#pragma once
/// One RAII handle for every Vulkan object that a VkDevice destroys (vkDestroy* and vkFreeMemory
/// share one shape: device, object, allocator). Classes holding Handles need no destructor and
/// no move code of their own. Their members are destroyed in reverse order of declaration, so
/// memory is declared before the image or buffer bound to it, and an image before its views.
/// (Move assignment replaces members in declaration order, freeing the old memory first; Vulkan
/// allows freeing memory still bound to objects that are not used again.)

#include <utility>

#include <vulkan/vulkan.h>

namespace pic::gpu {

/// Owns one `T` together with the device that destroys it with `Destroy(device, handle,
/// nullptr)`; move-only, and empty (get() null) once moved from, reset or released.
template <typename T, auto Destroy>
class Handle {
public:
    Handle() = default;
    /// Takes ownership of `handle`, created on `device`.
    Handle(VkDevice device, T handle) : mDevice(device), mHandle(handle) {}
    Handle(Handle&& other) noexcept
        : mDevice(std::exchange(other.mDevice, VK_NULL_HANDLE)),
          mHandle(std::exchange(other.mHandle, VK_NULL_HANDLE)) {}
    /// Destroys what it held and takes `other`'s (by value: `other` is moved into the argument).
    Handle& operator=(Handle other) noexcept {
        std::swap(mDevice, other.mDevice);
        std::swap(mHandle, other.mHandle);
        return *this;
    }
    ~Handle() { reset(); }

    /// The object, null when empty.
    T get() const { return mHandle; }
    /// The device that destroys it, null when empty.
    VkDevice device() const { return mDevice; }
    /// Whether it holds an object.
    explicit operator bool() const { return mHandle != VK_NULL_HANDLE; }
    /// Destroys the object now, if any.
    void reset() {
        if (mHandle != VK_NULL_HANDLE) Destroy(mDevice, mHandle, nullptr);
        mDevice = VK_NULL_HANDLE;
        mHandle = VK_NULL_HANDLE;
    }
    /// Gives the object up without destroying it: the caller destroys it.
    [[nodiscard]] T release() {
        mDevice = VK_NULL_HANDLE;
        return std::exchange(mHandle, VK_NULL_HANDLE);
    }

private:
    VkDevice mDevice = VK_NULL_HANDLE;
    T mHandle = VK_NULL_HANDLE;
};

// One name per kind of object pic owns.
using DeviceMemory = Handle<VkDeviceMemory, vkFreeMemory>;  ///< unmapped implicitly when freed
using BufferView = Handle<VkBufferView, vkDestroyBufferView>;
using Image = Handle<VkImage, vkDestroyImage>;
using ImageView = Handle<VkImageView, vkDestroyImageView>;
using QueryPool = Handle<VkQueryPool, vkDestroyQueryPool>;
using ShaderModule = Handle<VkShaderModule, vkDestroyShaderModule>;
using DescriptorSetLayout = Handle<VkDescriptorSetLayout, vkDestroyDescriptorSetLayout>;
using DescriptorPool = Handle<VkDescriptorPool, vkDestroyDescriptorPool>;  ///< frees its sets
using PipelineLayout = Handle<VkPipelineLayout, vkDestroyPipelineLayout>;
using Pipeline = Handle<VkPipeline, vkDestroyPipeline>;

}  // namespace pic::gpu
