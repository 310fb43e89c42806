#pragma once
/// A headless Vulkan context (no window, no surface) for the runtime passes: device choice,
/// buffers, depth images, one-shot command submission and per-pass timestamps. Every Vulkan
/// failure comes back as an Error (PIC_VK_TRY); nothing here exits the process.

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <vulkan/vulkan.h>

#include "core/error.h"

namespace pic::gpu {

/// Name of a VkResult ("VK_ERROR_DEVICE_LOST").
const char* vkResultName(VkResult result);

/// The Error for a failed Vulkan call: Internal, naming the call, the result and file:line;
/// out-of-memory results say so plainly.
Error vkError(VkResult result, const char* call, const char* file, int line);

}  // namespace pic::gpu

/// Evaluates a Vulkan call and returns its Error from the enclosing function when it fails.
#define PIC_VK_TRY(expr)                                                                 \
    do {                                                                                 \
        const VkResult picVkResult_ = (expr);                                            \
        if (picVkResult_ < 0)                                                            \
            return std::unexpected(::pic::gpu::vkError(picVkResult_, #expr, __FILE__, __LINE__)); \
    } while (false)

namespace pic::gpu {

class Context;

/// Where a buffer lives.
enum class MemoryUse {
    Device,    ///< device-local; mapped too when the device shares memory with the host
    Readback,  ///< host-visible, coherent (cached when available): results read by the CPU
};

/// A buffer and its memory; move-only, freed with its context still alive.
class Buffer {
public:
    Buffer() = default;
    Buffer(Buffer&& other) noexcept { *this = std::move(other); }
    Buffer& operator=(Buffer&& other) noexcept;
    ~Buffer() { reset(); }

    VkBuffer handle() const { return mBuffer; }
    VkDeviceSize size() const { return mSize; }
    /// Host pointer of a mapped buffer, null when the memory is not host-visible.
    void* mapped() const { return mMapped; }
    void reset();

private:
    friend class Context;
    VkDevice mDevice = VK_NULL_HANDLE;
    VkBuffer mBuffer = VK_NULL_HANDLE;
    VkDeviceMemory mMemory = VK_NULL_HANDLE;
    VkDeviceSize mSize = 0;
    void* mMapped = nullptr;
};

/// A typed view of a buffer range that shaders read as a uniform texel buffer
/// (`usamplerBuffer`, `samplerBuffer`); move-only. Texel fetches are gathers without branches on
/// lavapipe, where a storage-buffer load at an index that differs per lane is a branch per lane.
class TexelView {
public:
    TexelView() = default;
    TexelView(TexelView&& other) noexcept { *this = std::move(other); }
    TexelView& operator=(TexelView&& other) noexcept;
    ~TexelView() { reset(); }

    VkBufferView handle() const { return mView; }
    void reset();

private:
    friend class Context;
    VkDevice mDevice = VK_NULL_HANDLE;
    VkBufferView mView = VK_NULL_HANDLE;
};

/// A 2D-array depth image (shadow maps): one view of all layers for sampling and one view per
/// layer for rendering.
class DepthArray {
public:
    DepthArray() = default;
    DepthArray(DepthArray&& other) noexcept { *this = std::move(other); }
    DepthArray& operator=(DepthArray&& other) noexcept;
    ~DepthArray() { reset(); }

    VkImage image() const { return mImage; }
    VkImageView arrayView() const { return mArrayView; }
    VkImageView layerView(uint32_t layer) const { return mLayerViews[layer]; }
    uint32_t size() const { return mSize; }
    uint32_t layers() const { return uint32_t(mLayerViews.size()); }
    VkDeviceSize bytes() const { return VkDeviceSize{mSize} * mSize * layers() * 4; }
    void reset();

private:
    friend class Context;
    VkDevice mDevice = VK_NULL_HANDLE;
    VkImage mImage = VK_NULL_HANDLE;
    VkDeviceMemory mMemory = VK_NULL_HANDLE;
    VkImageView mArrayView = VK_NULL_HANDLE;
    std::vector<VkImageView> mLayerViews;
    uint32_t mSize = 0;
};

/// A 2D image with one view over its single layer: a colour or depth target that a raster
/// pass renders and later passes sample. Its layout is UNDEFINED once created; the pass that
/// renders it transitions it.
class RenderTarget {
public:
    RenderTarget() = default;
    RenderTarget(RenderTarget&& other) noexcept { *this = std::move(other); }
    RenderTarget& operator=(RenderTarget&& other) noexcept;
    ~RenderTarget() { reset(); }

    VkImage image() const { return mImage; }
    VkImageView view() const { return mView; }
    VkFormat format() const { return mFormat; }
    uint32_t width() const { return mWidth; }
    uint32_t height() const { return mHeight; }
    VkDeviceSize bytes() const { return mBytes; }
    void reset();

private:
    friend class Context;
    VkDevice mDevice = VK_NULL_HANDLE;
    VkImage mImage = VK_NULL_HANDLE;
    VkDeviceMemory mMemory = VK_NULL_HANDLE;
    VkImageView mView = VK_NULL_HANDLE;
    VkFormat mFormat = VK_FORMAT_UNDEFINED;
    uint32_t mWidth = 0;
    uint32_t mHeight = 0;
    VkDeviceSize mBytes = 0;
};

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
    std::span<const VkFormat> colorFormats;   ///< one per colour attachment, all written
    VkPipelineLayout layout = VK_NULL_HANDLE;
};

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

/// Timestamps of named passes inside one command buffer (Vulkan timestamp queries).
class PassTimer {
public:
    PassTimer() = default;
    PassTimer(PassTimer&& other) noexcept { *this = std::move(other); }
    PassTimer& operator=(PassTimer&& other) noexcept;
    ~PassTimer();

    /// Marks the start of pass `name` (ends the previous pass, if any).
    void begin(VkCommandBuffer cmd, const char* name);
    /// Marks the end of the current pass.
    void end(VkCommandBuffer cmd);
    /// After the command buffer completed: adds each pass's milliseconds to `ms` by name.
    Result<void> collect(std::vector<std::pair<std::string, double>>& ms);

private:
    friend class Context;
    VkDevice mDevice = VK_NULL_HANDLE;
    VkQueryPool mPool = VK_NULL_HANDLE;
    uint32_t mCapacity = 0;
    double mPeriodNs = 1.0;
    uint64_t mValidMask = ~uint64_t{0};
    std::vector<std::string> mNames;  ///< pass of query pair i
    bool mOpen = false;
};

/// One Vulkan instance, device and queue.
class Context {
public:
    static Result<std::unique_ptr<Context>> create(const ContextOptions& options = {});
    ~Context();
    Context(const Context&) = delete;
    Context& operator=(const Context&) = delete;

    VkDevice device() const { return mDevice; }
    VkPhysicalDevice physicalDevice() const { return mPhysical; }
    const VkPhysicalDeviceProperties& properties() const { return mProperties; }
    const std::string& deviceName() const { return mName; }
    /// True for a CPU implementation (lavapipe): memory is the host's.
    bool isCpuDevice() const { return mProperties.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU; }
    /// Invocations per subgroup compute shaders get by default (8 on lavapipe, 32 on NVIDIA).
    uint32_t subgroupSize() const { return mSubgroupSize; }
    /// Errors and warnings the validation layer reported so far (0 when it is off).
    uint32_t validationMessages() const { return mValidationMessages; }
    bool validationEnabled() const { return mMessenger != VK_NULL_HANDLE; }

    /// A buffer of `bytes` (> 0) for `usage` (storage and transfer usage are always added).
    Result<Buffer> createBuffer(VkDeviceSize bytes, VkBufferUsageFlags usage, MemoryUse use,
                                const char* what);
    /// A device buffer holding `bytes` of `data` (uploaded through a staging buffer when the
    /// device memory is not mapped).
    Result<Buffer> createBufferWith(const void* data, VkDeviceSize bytes, VkBufferUsageFlags usage,
                                    const char* what);
    template <class T>
    Result<Buffer> createBufferWith(std::span<const T> data, VkBufferUsageFlags usage,
                                    const char* what) {
        return createBufferWith(data.data(), data.size_bytes(), usage, what);
    }
    /// Whether shaders may read `format` from a uniform texel buffer.
    bool canReadTexels(VkFormat format) const;
    /// A view of `texels` elements of `format` (32-bit components: R32, R32G32, R32G32B32 or
    /// R32G32B32A32 UINT; R16, R32 or R32G32B32A32 SFLOAT) in `buffer` from byte `offset`, which
    /// the buffer's usage must allow (VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT). Unsupported when
    /// `texels` exceeds maxTexelBufferElements or the format cannot be a uniform texel buffer.
    Result<TexelView> createTexelView(const Buffer& buffer, VkFormat format, VkDeviceSize offset,
                                      VkDeviceSize texels, const char* what);
    /// A view of all of `buffer` as texels of `format` (as many as fit).
    Result<TexelView> createTexelView(const Buffer& buffer, VkFormat format, const char* what);
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

    /// A D32 depth array of `layers` square layers of `size`², sampled and rendered to, in
    /// SHADER_READ_ONLY layout once created.
    Result<DepthArray> createDepthArray(uint32_t size, uint32_t layers);
    /// The depths of one layer, row-major (waits for the device: for tests and debugging).
    Result<std::vector<float>> downloadDepthLayer(const DepthArray& depth, uint32_t layer);

    /// A width × height render target of `format`: a depth attachment for depth formats
    /// (VK_FORMAT_D32_SFLOAT), else a colour attachment that shaders may sample. InvalidInput
    /// when a side is 0 or beyond the device's 2D image limit.
    Result<RenderTarget> createRenderTarget(uint32_t width, uint32_t height, VkFormat format,
                                            const char* what);

    /// A shader module from SPIR-V words.
    Result<VkShaderModule> createShaderModule(std::span<const uint32_t> spirv, const char* what);

    /// A graphics pipeline as `desc` describes (the caller destroys it).
    Result<VkPipeline> createRasterPipeline(const RasterPipelineDesc& desc);

    /// A timer for up to `passes` pass instances per command buffer.
    Result<PassTimer> createPassTimer(uint32_t passes);

    /// Records `record` into a fresh command buffer, submits it and waits for it; the host may
    /// then read whatever it wrote (the buffer ends with a transfer and compute to host-read
    /// barrier). A lost device makes this and every later call fail.
    Result<void> submit(const std::function<void(VkCommandBuffer)>& record,
                        PassTimer* timer = nullptr);

    /// The nearest-filtering, clamp-to-edge sampler the passes read depth images with.
    VkSampler nearestSampler() const { return mNearestSampler; }

private:
    Context() = default;
    Result<void> init(const ContextOptions& options);
    Result<uint32_t> memoryType(uint32_t allowed, VkMemoryPropertyFlags required,
                                VkMemoryPropertyFlags preferred) const;
    Result<void> allocate(VkMemoryRequirements requirements, VkMemoryPropertyFlags required,
                          VkMemoryPropertyFlags preferred, VkDeviceMemory& memory,
                          VkMemoryPropertyFlags& flags, const char* what);
    /// The staging buffer, at least `bytes` long.
    Result<Buffer*> staging(VkDeviceSize bytes);

    VkInstance mInstance = VK_NULL_HANDLE;
    VkDebugUtilsMessengerEXT mMessenger = VK_NULL_HANDLE;
    VkPhysicalDevice mPhysical = VK_NULL_HANDLE;
    VkPhysicalDeviceProperties mProperties{};
    VkPhysicalDeviceMemoryProperties mMemory{};
    std::string mName;
    VkDevice mDevice = VK_NULL_HANDLE;
    uint32_t mQueueFamily = 0;
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

/// A full memory barrier between compute work (and transfers) recorded before and after it:
/// every shader or transfer write before is visible to every shader or transfer access after.
void computeBarrier(VkCommandBuffer cmd);

}  // namespace pic::gpu
