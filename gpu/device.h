#pragma once
/// A headless Vulkan context (no window, no surface): instance, device choice, one queue,
/// one-shot command submission, the device's properties and limits, validation messages, and
/// the transfers between host and buffers that go through its staging buffers. Every Vulkan
/// failure comes back as an Error (PIC_VK_TRY); nothing here exits the process.

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <vulkan/vulkan.h>

#include "core/error.h"
#include "gpu/resources.h"

namespace pic::gpu {

class PassTimer;

/// How to open a context.
struct ContextOptions {
    /// Case-insensitive substring of the device name to use ("llvmpipe", "NVIDIA"); empty:
    /// the first discrete GPU, else integrated, else virtual, else a CPU device (lavapipe).
    std::string deviceName;
    /// Enables VK_LAYER_KHRONOS_validation when it is installed (off when it is not). The
    /// PIC_VK_VALIDATION environment variable (0/1) overrides this.
    bool validation = false;
    /// False leaves device-local memory unmapped even where the host could map it (a CPU
    /// device), so that the staging paths a discrete GPU takes run there too (tests).
    bool mapDeviceMemory = true;
};

/// One Vulkan instance, device and queue.
class Context {
public:
    /// Opens the instance (with the validation layer when wanted) and the device `options`
    /// choose, with one graphics + compute queue, its command pool and the nearest sampler.
    static Result<std::unique_ptr<Context>> create(const ContextOptions& options = {});
    ~Context();
    Context(const Context&) = delete;
    Context& operator=(const Context&) = delete;

    VkDevice device() const { return mDevice; }
    VkPhysicalDevice physicalDevice() const { return mPhysical; }
    const VkPhysicalDeviceProperties& properties() const { return mProperties; }
    /// The device's memory types and heaps.
    const VkPhysicalDeviceMemoryProperties& memoryProperties() const { return mMemory; }
    const std::string& deviceName() const { return mName; }
    /// True for a CPU implementation (lavapipe): memory is the host's.
    bool isCpuDevice() const { return mProperties.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU; }
    /// Invocations per subgroup compute shaders get by default (8 on lavapipe, 32 on NVIDIA).
    uint32_t subgroupSize() const { return mSubgroupSize; }
    /// Bits of the queue's timestamps that count (1 to 64).
    uint32_t timestampValidBits() const { return mTimestampBits; }
    /// Whether device-local memory the host can see is mapped (ContextOptions::mapDeviceMemory).
    bool mapsDeviceMemory() const { return mMapDeviceMemory; }
    /// Errors and warnings the validation layer reported so far (0 when it is off).
    uint32_t validationMessages() const { return mValidationMessages; }
    bool validationEnabled() const { return mMessenger != VK_NULL_HANDLE; }
    /// Whether shaders may read `format` from a uniform texel buffer.
    bool canReadTexels(VkFormat format) const;
    /// The nearest-filtering, clamp-to-edge sampler the passes read depth images with.
    VkSampler nearestSampler() const { return mNearestSampler; }
    /// Fails (Internal) once the device was lost: nothing created or submitted after would work.
    Result<void> checkAlive() const;

    /// Records `record` into a fresh command buffer, submits it and waits for it; the host may
    /// then read whatever it wrote (the buffer ends with a transfer and compute to host-read
    /// barrier). A lost device makes this and every later call fail.
    Result<void> submit(const std::function<void(VkCommandBuffer)>& record,
                        PassTimer* timer = nullptr);

    // Transfers (defined in resources.cpp, beside the buffers they fill).

    /// Writes `bytes` of `data` into `buffer` at `offset`.
    Result<void> upload(Buffer& buffer, const void* data, VkDeviceSize bytes,
                        VkDeviceSize offset = 0);
    /// Writes `bytes` of `data` into `buffer` at `offset` for the next submit(): at once where
    /// the buffer is mapped, else by a copy recorded at the start of that submission, before
    /// all it records. Small per-update uploads take no submission of their own this way.
    Result<void> uploadWithNextSubmit(Buffer& buffer, const void* data, VkDeviceSize bytes,
                                      VkDeviceSize offset = 0);
    /// Reads `bytes` of `buffer` at `offset` into `data` (waits for nothing: call after the
    /// work that wrote it completed).
    Result<void> download(const Buffer& buffer, void* data, VkDeviceSize bytes,
                          VkDeviceSize offset = 0);
    /// The depths of one layer, row-major (waits for the device: for tests and debugging).
    Result<std::vector<float>> downloadDepthLayer(const DepthArray& depth, uint32_t layer);

private:
    Context() = default;
    Result<void> init(const ContextOptions& options);
    /// The staging buffer, at least `bytes` long.
    Result<Buffer*> staging(VkDeviceSize bytes);
    /// Records the copies of uploadWithNextSubmit() waiting for this submission.
    void recordPendingUploads(VkCommandBuffer cmd);

    VkInstance mInstance = VK_NULL_HANDLE;
    VkDebugUtilsMessengerEXT mMessenger = VK_NULL_HANDLE;
    VkPhysicalDevice mPhysical = VK_NULL_HANDLE;
    VkPhysicalDeviceProperties mProperties{};
    VkPhysicalDeviceMemoryProperties mMemory{};
    std::string mName;
    VkDevice mDevice = VK_NULL_HANDLE;
    uint32_t mQueueFamily = 0;
    uint32_t mTimestampBits = 64;
    VkQueue mQueue = VK_NULL_HANDLE;
    VkCommandPool mCommandPool = VK_NULL_HANDLE;
    VkCommandBuffer mCommandBuffer = VK_NULL_HANDLE;
    VkFence mFence = VK_NULL_HANDLE;
    VkSampler mNearestSampler = VK_NULL_HANDLE;
    /// Host-visible go-between of uploads to and downloads from memory the host cannot map,
    /// kept and grown rather than allocated per transfer: on a discrete GPU an allocation
    /// costs more than the copy.
    Buffer mStaging;
    /// Uploads waiting for the next submission: their bytes in mPendingStaging.
    struct PendingUpload {
        VkBuffer target;
        VkDeviceSize stagingOffset, targetOffset, bytes;
    };
    std::vector<PendingUpload> mPending;
    Buffer mPendingStaging;
    VkDeviceSize mPendingBytes = 0;
    bool mMapDeviceMemory = true;
    uint32_t mSubgroupSize = 1;
    bool mLost = false;
    uint32_t mValidationMessages = 0;

    static VKAPI_ATTR VkBool32 VKAPI_CALL onValidation(
        VkDebugUtilsMessageSeverityFlagBitsEXT severity, VkDebugUtilsMessageTypeFlagsEXT types,
        const VkDebugUtilsMessengerCallbackDataEXT* data, void* user);
};

}  // namespace pic::gpu
