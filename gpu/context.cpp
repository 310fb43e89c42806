#include "gpu/context.h"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cstdlib>
#include <cstring>
#include <vector>

#include <fmt/format.h>

namespace pic::gpu {
namespace {

constexpr const char* kValidationLayer = "VK_LAYER_KHRONOS_validation";

/// Timeout of one submission: long enough for the high settings on lavapipe, short enough
/// that a hung device is reported instead of hanging the server (ns).
constexpr uint64_t kSubmitTimeoutNs = 120ull * 1000 * 1000 * 1000;

std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return s;
}

/// Device preference: discrete, integrated, virtual, CPU, other.
int typeRank(VkPhysicalDeviceType type) {
    switch (type) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return 0;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return 1;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return 2;
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return 3;
    default: return 4;
    }
}

bool layerAvailable(const char* name) {
    uint32_t count = 0;
    if (vkEnumerateInstanceLayerProperties(&count, nullptr) != VK_SUCCESS) return false;
    std::vector<VkLayerProperties> layers(count);
    if (vkEnumerateInstanceLayerProperties(&count, layers.data()) != VK_SUCCESS) return false;
    return std::any_of(layers.begin(), layers.end(),
                       [&](const VkLayerProperties& l) { return std::strcmp(l.layerName, name) == 0; });
}

/// PIC_VK_VALIDATION=0/1 overrides the option.
bool wantValidation(bool requested) {
    const char* env = std::getenv("PIC_VK_VALIDATION");
    if (env && *env) return std::strcmp(env, "0") != 0;
    return requested;
}

/// Makes transfer and compute-shader writes recorded before it visible to host reads once
/// the submission's fence has signalled: a fence alone does not make device writes visible
/// to the host.
void hostReadBarrier(VkCommandBuffer cmd) {
    VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    barrier.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT | VK_ACCESS_SHADER_WRITE_BIT;
    barrier.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                         VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &barrier, 0, nullptr, 0, nullptr);
}

}  // namespace

const char* vkResultName(VkResult result) {
    switch (result) {
#define PIC_VK_CASE(name) \
    case name: return #name;
        PIC_VK_CASE(VK_SUCCESS)
        PIC_VK_CASE(VK_NOT_READY)
        PIC_VK_CASE(VK_TIMEOUT)
        PIC_VK_CASE(VK_INCOMPLETE)
        PIC_VK_CASE(VK_ERROR_OUT_OF_HOST_MEMORY)
        PIC_VK_CASE(VK_ERROR_OUT_OF_DEVICE_MEMORY)
        PIC_VK_CASE(VK_ERROR_INITIALIZATION_FAILED)
        PIC_VK_CASE(VK_ERROR_DEVICE_LOST)
        PIC_VK_CASE(VK_ERROR_MEMORY_MAP_FAILED)
        PIC_VK_CASE(VK_ERROR_LAYER_NOT_PRESENT)
        PIC_VK_CASE(VK_ERROR_EXTENSION_NOT_PRESENT)
        PIC_VK_CASE(VK_ERROR_FEATURE_NOT_PRESENT)
        PIC_VK_CASE(VK_ERROR_INCOMPATIBLE_DRIVER)
        PIC_VK_CASE(VK_ERROR_TOO_MANY_OBJECTS)
        PIC_VK_CASE(VK_ERROR_FORMAT_NOT_SUPPORTED)
        PIC_VK_CASE(VK_ERROR_FRAGMENTED_POOL)
        PIC_VK_CASE(VK_ERROR_OUT_OF_POOL_MEMORY)
        PIC_VK_CASE(VK_ERROR_UNKNOWN)
#undef PIC_VK_CASE
    default: return "VK_RESULT_UNKNOWN";
    }
}

Error vkError(VkResult result, const char* call, const char* file, int line) {
    const char* hint = "";
    if (result == VK_ERROR_OUT_OF_DEVICE_MEMORY || result == VK_ERROR_OUT_OF_HOST_MEMORY)
        hint = " (out of memory: use a smaller bake or a device with more memory)";
    else if (result == VK_ERROR_DEVICE_LOST)
        hint = " (the GPU device was lost; the runtime must be recreated)";
    return Error{ErrorCode::Internal,
                 fmt::format("Vulkan call {} failed with {}{} at {}:{}", call,
                             vkResultName(result), hint, file, line)};
}

// ---------------------------------------------------------------------------------------------
// Buffer, DepthArray

Buffer& Buffer::operator=(Buffer&& other) noexcept {
    if (this != &other) {
        reset();
        mDevice = std::exchange(other.mDevice, VK_NULL_HANDLE);
        mBuffer = std::exchange(other.mBuffer, VK_NULL_HANDLE);
        mMemory = std::exchange(other.mMemory, VK_NULL_HANDLE);
        mSize = std::exchange(other.mSize, 0);
        mMapped = std::exchange(other.mMapped, nullptr);
    }
    return *this;
}

void Buffer::reset() {
    if (mDevice == VK_NULL_HANDLE) return;
    if (mBuffer) vkDestroyBuffer(mDevice, mBuffer, nullptr);
    if (mMemory) vkFreeMemory(mDevice, mMemory, nullptr);  // unmaps implicitly
    mDevice = VK_NULL_HANDLE;
    mBuffer = VK_NULL_HANDLE;
    mMemory = VK_NULL_HANDLE;
    mSize = 0;
    mMapped = nullptr;
}

TexelView& TexelView::operator=(TexelView&& other) noexcept {
    if (this != &other) {
        reset();
        mDevice = std::exchange(other.mDevice, VK_NULL_HANDLE);
        mView = std::exchange(other.mView, VK_NULL_HANDLE);
    }
    return *this;
}

void TexelView::reset() {
    if (mDevice == VK_NULL_HANDLE) return;
    if (mView) vkDestroyBufferView(mDevice, mView, nullptr);
    mDevice = VK_NULL_HANDLE;
    mView = VK_NULL_HANDLE;
}

DepthArray& DepthArray::operator=(DepthArray&& other) noexcept {
    if (this != &other) {
        reset();
        mDevice = std::exchange(other.mDevice, VK_NULL_HANDLE);
        mImage = std::exchange(other.mImage, VK_NULL_HANDLE);
        mMemory = std::exchange(other.mMemory, VK_NULL_HANDLE);
        mArrayView = std::exchange(other.mArrayView, VK_NULL_HANDLE);
        mLayerViews = std::move(other.mLayerViews);
        other.mLayerViews.clear();
        mSize = std::exchange(other.mSize, 0);
    }
    return *this;
}

void DepthArray::reset() {
    if (mDevice == VK_NULL_HANDLE) return;
    for (VkImageView view : mLayerViews) vkDestroyImageView(mDevice, view, nullptr);
    if (mArrayView) vkDestroyImageView(mDevice, mArrayView, nullptr);
    if (mImage) vkDestroyImage(mDevice, mImage, nullptr);
    if (mMemory) vkFreeMemory(mDevice, mMemory, nullptr);
    mLayerViews.clear();
    mDevice = VK_NULL_HANDLE;
    mImage = VK_NULL_HANDLE;
    mMemory = VK_NULL_HANDLE;
    mArrayView = VK_NULL_HANDLE;
    mSize = 0;
}

RenderTarget& RenderTarget::operator=(RenderTarget&& other) noexcept {
    if (this != &other) {
        reset();
        mDevice = std::exchange(other.mDevice, VK_NULL_HANDLE);
        mImage = std::exchange(other.mImage, VK_NULL_HANDLE);
        mMemory = std::exchange(other.mMemory, VK_NULL_HANDLE);
        mView = std::exchange(other.mView, VK_NULL_HANDLE);
        mFormat = std::exchange(other.mFormat, VK_FORMAT_UNDEFINED);
        mWidth = std::exchange(other.mWidth, 0);
        mHeight = std::exchange(other.mHeight, 0);
        mBytes = std::exchange(other.mBytes, 0);
    }
    return *this;
}

void RenderTarget::reset() {
    if (mDevice == VK_NULL_HANDLE) return;
    if (mView) vkDestroyImageView(mDevice, mView, nullptr);
    if (mImage) vkDestroyImage(mDevice, mImage, nullptr);
    if (mMemory) vkFreeMemory(mDevice, mMemory, nullptr);
    mDevice = VK_NULL_HANDLE;
    mImage = VK_NULL_HANDLE;
    mMemory = VK_NULL_HANDLE;
    mView = VK_NULL_HANDLE;
    mFormat = VK_FORMAT_UNDEFINED;
    mWidth = mHeight = 0;
    mBytes = 0;
}

// ---------------------------------------------------------------------------------------------
// PassTimer

PassTimer& PassTimer::operator=(PassTimer&& other) noexcept {
    if (this != &other) {
        if (mPool) vkDestroyQueryPool(mDevice, mPool, nullptr);
        mDevice = std::exchange(other.mDevice, VK_NULL_HANDLE);
        mPool = std::exchange(other.mPool, VK_NULL_HANDLE);
        mCapacity = other.mCapacity;
        mPeriodNs = other.mPeriodNs;
        mValidMask = other.mValidMask;
        mNames = std::move(other.mNames);
        mOpen = other.mOpen;
    }
    return *this;
}

PassTimer::~PassTimer() {
    if (mPool) vkDestroyQueryPool(mDevice, mPool, nullptr);
}

void PassTimer::begin(VkCommandBuffer cmd, const char* name) {
    if (mOpen) end(cmd);
    if (mNames.size() >= mCapacity) return;  // more passes than queries: the rest go untimed
    vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, mPool, uint32_t(2 * mNames.size()));
    mNames.emplace_back(name);
    mOpen = true;
}

void PassTimer::end(VkCommandBuffer cmd) {
    if (!mOpen) return;
    vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, mPool,
                        uint32_t(2 * mNames.size() - 1));
    mOpen = false;
}

Result<void> PassTimer::collect(std::vector<std::pair<std::string, double>>& ms) {
    if (mNames.empty()) return {};
    std::vector<uint64_t> ticks(2 * mNames.size());
    PIC_VK_TRY(vkGetQueryPoolResults(mDevice, mPool, 0, uint32_t(ticks.size()),
                                     ticks.size() * sizeof(uint64_t), ticks.data(),
                                     sizeof(uint64_t), VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT));
    for (size_t i = 0; i < mNames.size(); ++i) {
        const uint64_t start = ticks[2 * i] & mValidMask, stop = ticks[2 * i + 1] & mValidMask;
        const double ns = stop >= start ? double(stop - start) * mPeriodNs : 0.0;
        ms.emplace_back(mNames[i], ns * 1e-6);
    }
    mNames.clear();
    return {};
}

// ---------------------------------------------------------------------------------------------
// Context

VKAPI_ATTR VkBool32 VKAPI_CALL Context::onValidation(
    VkDebugUtilsMessageSeverityFlagBitsEXT severity, VkDebugUtilsMessageTypeFlagsEXT,
    const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
    auto* self = static_cast<Context*>(user);
    if (severity >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT) {
        ++self->mValidationMessages;
        fmt::print(stderr, "vulkan validation: {}\n", data->pMessage ? data->pMessage : "");
    }
    return VK_FALSE;
}

Result<std::unique_ptr<Context>> Context::create(const ContextOptions& options) {
    std::unique_ptr<Context> context(new Context());
    if (auto ok = context->init(options); !ok) return std::unexpected(ok.error());
    return context;
}

Result<void> Context::init(const ContextOptions& options) {
    mMapDeviceMemory = options.mapDeviceMemory;
    // Instance: no surface extensions; the validation layer and its messenger when wanted.
    const bool validation = wantValidation(options.validation) && layerAvailable(kValidationLayer);
    VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
    app.pApplicationName = "pic";
    app.apiVersion = VK_API_VERSION_1_3;
    VkInstanceCreateInfo instanceInfo{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    instanceInfo.pApplicationInfo = &app;
    const char* layers[] = {kValidationLayer};
    const char* extensions[] = {VK_EXT_DEBUG_UTILS_EXTENSION_NAME};
    VkDebugUtilsMessengerCreateInfoEXT messengerInfo{
        VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
    messengerInfo.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT |
                                    VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
    messengerInfo.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                                VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT;
    messengerInfo.pfnUserCallback = &Context::onValidation;
    messengerInfo.pUserData = this;
    if (validation) {
        instanceInfo.enabledLayerCount = 1;
        instanceInfo.ppEnabledLayerNames = layers;
        instanceInfo.enabledExtensionCount = 1;
        instanceInfo.ppEnabledExtensionNames = extensions;
    }
    if (VkResult r = vkCreateInstance(&instanceInfo, nullptr, &mInstance); r != VK_SUCCESS)
        return fail(ErrorCode::Internal,
                    "no Vulkan implementation could be opened ({}); install "
                    "mesa-vulkan-drivers for the CPU device lavapipe",
                    vkResultName(r));
    if (validation) {
        auto createMessenger = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
            vkGetInstanceProcAddr(mInstance, "vkCreateDebugUtilsMessengerEXT"));
        if (createMessenger)
            PIC_VK_TRY(createMessenger(mInstance, &messengerInfo, nullptr, &mMessenger));
    }

    // Device: by name when asked, else by type preference, among Vulkan 1.3 devices.
    uint32_t count = 0;
    PIC_VK_TRY(vkEnumeratePhysicalDevices(mInstance, &count, nullptr));
    std::vector<VkPhysicalDevice> devices(count);
    PIC_VK_TRY(vkEnumeratePhysicalDevices(mInstance, &count, devices.data()));
    std::string names;
    int bestRank = 1 << 30;
    for (VkPhysicalDevice candidate : devices) {
        VkPhysicalDeviceProperties p;
        vkGetPhysicalDeviceProperties(candidate, &p);
        names += fmt::format("{}\"{}\"", names.empty() ? "" : ", ", p.deviceName);
        if (p.apiVersion < VK_API_VERSION_1_3) continue;
        if (!options.deviceName.empty()) {
            if (lower(p.deviceName).find(lower(options.deviceName)) == std::string::npos) continue;
        }
        const int rank = typeRank(p.deviceType);
        if (rank < bestRank) {
            bestRank = rank;
            mPhysical = candidate;
            mProperties = p;
        }
    }
    if (!mPhysical) {
        if (!options.deviceName.empty())
            return fail(ErrorCode::NotFound, "no Vulkan 1.3 device matches --device \"{}\"; devices: {}",
                        options.deviceName, names.empty() ? "none" : names);
        return fail(ErrorCode::Internal, "no Vulkan 1.3 device found (devices: {})",
                    names.empty() ? "none" : names);
    }
    mName = mProperties.deviceName;
    vkGetPhysicalDeviceMemoryProperties(mPhysical, &mMemory);

    // Features the shaders rely on: 16-bit storage (half links and caches), dynamic rendering
    // (shadow maps without render-pass objects).
    VkPhysicalDeviceVulkan13Features has13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
    VkPhysicalDeviceVulkan12Features has12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
    VkPhysicalDeviceVulkan11Features has11{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_FEATURES};
    has12.pNext = &has13;
    has11.pNext = &has12;
    VkPhysicalDeviceFeatures2 has{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
    has.pNext = &has11;
    vkGetPhysicalDeviceFeatures2(mPhysical, &has);
    if (!has11.storageBuffer16BitAccess || !has13.dynamicRendering)
        return fail(ErrorCode::Unsupported,
                    "Vulkan device \"{}\" lacks storageBuffer16BitAccess or dynamicRendering",
                    mName);
    // Subgroup sums in compute shaders (surfel lighting's per-workgroup flux).
    VkPhysicalDeviceSubgroupProperties subgroups{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES};
    VkPhysicalDeviceProperties2 properties2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
    properties2.pNext = &subgroups;
    vkGetPhysicalDeviceProperties2(mPhysical, &properties2);
    if (!(subgroups.supportedStages & VK_SHADER_STAGE_COMPUTE_BIT) ||
        !(subgroups.supportedOperations & VK_SUBGROUP_FEATURE_ARITHMETIC_BIT))
        return fail(ErrorCode::Unsupported,
                    "Vulkan device \"{}\" lacks subgroup arithmetic in compute shaders", mName);
    mSubgroupSize = std::max(subgroups.subgroupSize, 1u);

    // One queue that does graphics and compute and has timestamps.
    uint32_t familyCount = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(mPhysical, &familyCount, nullptr);
    std::vector<VkQueueFamilyProperties> families(familyCount);
    vkGetPhysicalDeviceQueueFamilyProperties(mPhysical, &familyCount, families.data());
    bool found = false;
    for (uint32_t f = 0; f < familyCount && !found; ++f) {
        const VkQueueFlags need = VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT;
        if ((families[f].queueFlags & need) == need && families[f].timestampValidBits > 0) {
            mQueueFamily = f;
            found = true;
        }
    }
    if (!found)
        return fail(ErrorCode::Unsupported,
                    "Vulkan device \"{}\" has no graphics + compute queue with timestamps", mName);

    VkPhysicalDeviceVulkan13Features use13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
    use13.dynamicRendering = VK_TRUE;
    VkPhysicalDeviceVulkan12Features use12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
    use12.shaderFloat16 = has12.shaderFloat16;
    use12.pNext = &use13;
    VkPhysicalDeviceVulkan11Features use11{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_FEATURES};
    use11.storageBuffer16BitAccess = VK_TRUE;
    use11.pNext = &use12;
    VkPhysicalDeviceFeatures2 use{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
    use.pNext = &use11;
    const float priority = 1.0f;
    VkDeviceQueueCreateInfo queueInfo{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    queueInfo.queueFamilyIndex = mQueueFamily;
    queueInfo.queueCount = 1;
    queueInfo.pQueuePriorities = &priority;
    VkDeviceCreateInfo deviceInfo{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
    deviceInfo.pNext = &use;
    deviceInfo.queueCreateInfoCount = 1;
    deviceInfo.pQueueCreateInfos = &queueInfo;
    PIC_VK_TRY(vkCreateDevice(mPhysical, &deviceInfo, nullptr, &mDevice));
    vkGetDeviceQueue(mDevice, mQueueFamily, 0, &mQueue);

    VkCommandPoolCreateInfo poolInfo{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    poolInfo.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    poolInfo.queueFamilyIndex = mQueueFamily;
    PIC_VK_TRY(vkCreateCommandPool(mDevice, &poolInfo, nullptr, &mCommandPool));
    VkCommandBufferAllocateInfo cmdInfo{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    cmdInfo.commandPool = mCommandPool;
    cmdInfo.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    cmdInfo.commandBufferCount = 1;
    PIC_VK_TRY(vkAllocateCommandBuffers(mDevice, &cmdInfo, &mCommandBuffer));
    VkFenceCreateInfo fenceInfo{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    PIC_VK_TRY(vkCreateFence(mDevice, &fenceInfo, nullptr, &mFence));

    VkSamplerCreateInfo samplerInfo{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
    samplerInfo.magFilter = VK_FILTER_NEAREST;
    samplerInfo.minFilter = VK_FILTER_NEAREST;
    samplerInfo.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
    samplerInfo.addressModeU = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
    samplerInfo.addressModeV = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
    samplerInfo.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
    PIC_VK_TRY(vkCreateSampler(mDevice, &samplerInfo, nullptr, &mNearestSampler));
    return {};
}

Context::~Context() {
    if (mDevice) {
        vkDeviceWaitIdle(mDevice);
        mStaging.reset();
        mPendingStaging.reset();
        if (mNearestSampler) vkDestroySampler(mDevice, mNearestSampler, nullptr);
        if (mFence) vkDestroyFence(mDevice, mFence, nullptr);
        if (mCommandPool) vkDestroyCommandPool(mDevice, mCommandPool, nullptr);
        vkDestroyDevice(mDevice, nullptr);
    }
    if (mMessenger) {
        auto destroyMessenger = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
            vkGetInstanceProcAddr(mInstance, "vkDestroyDebugUtilsMessengerEXT"));
        if (destroyMessenger) destroyMessenger(mInstance, mMessenger, nullptr);
    }
    if (mInstance) vkDestroyInstance(mInstance, nullptr);
}

Result<uint32_t> Context::memoryType(uint32_t allowed, VkMemoryPropertyFlags required,
                                     VkMemoryPropertyFlags preferred) const {
    int best = -1;
    for (uint32_t t = 0; t < mMemory.memoryTypeCount; ++t) {
        const VkMemoryPropertyFlags flags = mMemory.memoryTypes[t].propertyFlags;
        if (!(allowed & (1u << t)) || (flags & required) != required) continue;
        if ((flags & preferred) == preferred) return t;
        if (best < 0) best = int(t);
    }
    if (best < 0)
        return fail(ErrorCode::Unsupported, "Vulkan device \"{}\" has no memory type with flags {:#x}",
                    mName, uint32_t(required));
    return uint32_t(best);
}

Result<void> Context::allocate(VkMemoryRequirements requirements, VkMemoryPropertyFlags required,
                               VkMemoryPropertyFlags preferred, VkDeviceMemory& memory,
                               VkMemoryPropertyFlags& flags, const char* what) {
    PIC_TRY_ASSIGN(const uint32_t type, memoryType(requirements.memoryTypeBits, required, preferred));
    flags = mMemory.memoryTypes[type].propertyFlags;
    const VkDeviceSize heap = mMemory.memoryHeaps[mMemory.memoryTypes[type].heapIndex].size;
    if (requirements.size > heap)
        return fail(ErrorCode::Internal,
                    "{} needs {:.1f} MiB, more than the {:.1f} MiB memory heap of \"{}\" (out of "
                    "memory)",
                    what, double(requirements.size) / (1 << 20), double(heap) / (1 << 20), mName);
    VkMemoryAllocateInfo info{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    info.allocationSize = requirements.size;
    info.memoryTypeIndex = type;
    if (VkResult r = vkAllocateMemory(mDevice, &info, nullptr, &memory); r != VK_SUCCESS)
        return fail(ErrorCode::Internal, "allocating {:.1f} MiB for {} failed: {} (out of memory)",
                    double(requirements.size) / (1 << 20), what, vkResultName(r));
    return {};
}

Result<Buffer> Context::createBuffer(VkDeviceSize bytes, VkBufferUsageFlags usage, MemoryUse use,
                                     const char* what) {
    if (mLost) return fail(ErrorCode::Internal, "the Vulkan device \"{}\" was lost", mName);
    Buffer buffer;
    buffer.mDevice = mDevice;
    buffer.mSize = std::max<VkDeviceSize>(bytes, 4);
    VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    info.size = buffer.mSize;
    info.usage = usage | VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT |
                 VK_BUFFER_USAGE_TRANSFER_DST_BIT;
    info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    PIC_VK_TRY(vkCreateBuffer(mDevice, &info, nullptr, &buffer.mBuffer));
    VkMemoryRequirements requirements;
    vkGetBufferMemoryRequirements(mDevice, buffer.mBuffer, &requirements);
    VkMemoryPropertyFlags flags = 0;
    if (use == MemoryUse::Device) {
        PIC_TRY(allocate(requirements, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, 0, buffer.mMemory, flags,
                         what));
    } else {
        PIC_TRY(allocate(requirements,
                         VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT,
                         VK_MEMORY_PROPERTY_HOST_CACHED_BIT, buffer.mMemory, flags, what));
    }
    PIC_VK_TRY(vkBindBufferMemory(mDevice, buffer.mBuffer, buffer.mMemory, 0));
    // Memory the host sees coherently is mapped once for its whole life.
    const VkMemoryPropertyFlags mappable =
        VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
    if ((flags & mappable) == mappable && (use != MemoryUse::Device || mMapDeviceMemory))
        PIC_VK_TRY(vkMapMemory(mDevice, buffer.mMemory, 0, VK_WHOLE_SIZE, 0, &buffer.mMapped));
    return buffer;
}

Result<Buffer> Context::createBufferWith(const void* data, VkDeviceSize bytes,
                                         VkBufferUsageFlags usage, const char* what) {
    PIC_TRY_ASSIGN(Buffer buffer, createBuffer(bytes, usage, MemoryUse::Device, what));
    if (bytes > 0) PIC_TRY(upload(buffer, data, bytes));
    return buffer;
}

Result<Buffer*> Context::staging(VkDeviceSize bytes) {
    if (mStaging.size() < bytes) {
        mStaging.reset();
        PIC_TRY_ASSIGN(mStaging,
                       createBuffer(std::bit_ceil(bytes), 0, MemoryUse::Readback, "staging"));
    }
    return &mStaging;
}

namespace {

/// Bytes per texel of the formats texel views take (0 for any other).
VkDeviceSize texelSize(VkFormat format) {
    switch (format) {
    case VK_FORMAT_R16_SFLOAT:
        return 2;
    case VK_FORMAT_R32_UINT:
    case VK_FORMAT_R32_SFLOAT:
        return 4;
    case VK_FORMAT_R32G32_UINT:
        return 8;
    case VK_FORMAT_R32G32B32_UINT:
        return 12;
    case VK_FORMAT_R32G32B32A32_UINT:
    case VK_FORMAT_R32G32B32A32_SFLOAT:
        return 16;
    default:
        return 0;
    }
}

}  // namespace

Result<TexelView> Context::createTexelView(const Buffer& buffer, VkFormat format,
                                           const char* what) {
    const VkDeviceSize texelBytes = texelSize(format);
    return createTexelView(buffer, format, 0, texelBytes ? buffer.size() / texelBytes : 0, what);
}

bool Context::canReadTexels(VkFormat format) const {
    VkFormatProperties properties{};
    vkGetPhysicalDeviceFormatProperties(mPhysical, format, &properties);
    return (properties.bufferFeatures & VK_FORMAT_FEATURE_UNIFORM_TEXEL_BUFFER_BIT) != 0;
}

Result<TexelView> Context::createTexelView(const Buffer& buffer, VkFormat format,
                                           VkDeviceSize offset, VkDeviceSize texels,
                                           const char* what) {
    const VkDeviceSize texelBytes = texelSize(format);
    if (texelBytes == 0)
        return fail(ErrorCode::InvalidInput, "{}: texel format {} is not one texel views take",
                    what, int(format));
    if (!canReadTexels(format))
        return fail(ErrorCode::Unsupported, "{}: {} cannot read format {} as a texel buffer", what,
                    mName, int(format));
    const uint32_t maxTexels = mProperties.limits.maxTexelBufferElements;
    if (texels == 0 || texels > maxTexels)
        return fail(ErrorCode::Unsupported, "{}: a texel view of {} elements (1 to {} on {})", what,
                    texels, maxTexels, mName);
    if (offset % mProperties.limits.minTexelBufferOffsetAlignment != 0 ||
        offset + texels * texelBytes > buffer.size())
        return fail(ErrorCode::InvalidInput,
                    "{}: texels [{}, {}) of {} bytes do not lie aligned within a buffer of {} "
                    "bytes (offset alignment {})",
                    what, offset, offset + texels * texelBytes, texelBytes, buffer.size(),
                    mProperties.limits.minTexelBufferOffsetAlignment);
    VkBufferViewCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_VIEW_CREATE_INFO};
    info.buffer = buffer.handle();
    info.format = format;
    info.offset = offset;
    info.range = texels * texelBytes;
    TexelView view;
    PIC_VK_TRY(vkCreateBufferView(mDevice, &info, nullptr, &view.mView));
    view.mDevice = mDevice;
    return view;
}

Result<void> Context::upload(Buffer& buffer, const void* data, VkDeviceSize bytes,
                             VkDeviceSize offset) {
    PIC_CHECK(offset + bytes <= buffer.size());
    if (buffer.mapped()) {
        std::memcpy(static_cast<char*>(buffer.mapped()) + offset, data, bytes);
        return {};
    }
    PIC_TRY_ASSIGN(Buffer* staging, this->staging(bytes));
    std::memcpy(staging->mapped(), data, bytes);
    return submit([&](VkCommandBuffer cmd) {
        const VkBufferCopy region{0, offset, bytes};
        vkCmdCopyBuffer(cmd, staging->handle(), buffer.handle(), 1, &region);
    });
}

Result<void> Context::uploadWithNextSubmit(Buffer& buffer, const void* data, VkDeviceSize bytes,
                                           VkDeviceSize offset) {
    PIC_CHECK(offset + bytes <= buffer.size());
    if (buffer.mapped()) {
        std::memcpy(static_cast<char*>(buffer.mapped()) + offset, data, bytes);
        return {};
    }
    VkDeviceSize start = (mPendingBytes + 15) / 16 * 16;
    if (start + bytes > mPendingStaging.size()) {
        // Grow only with nothing pending: an empty submission records what is.
        if (!mPending.empty()) PIC_TRY(submit([](VkCommandBuffer) {}));
        if (bytes > mPendingStaging.size()) {
            mPendingStaging.reset();
            const VkDeviceSize size = std::bit_ceil(std::max<VkDeviceSize>(bytes, 4096));
            PIC_TRY_ASSIGN(mPendingStaging,
                           createBuffer(size, 0, MemoryUse::Readback, "pending uploads"));
        }
        start = 0;
    }
    std::memcpy(static_cast<char*>(mPendingStaging.mapped()) + start, data, bytes);
    mPending.push_back({buffer.handle(), start, offset, bytes});
    mPendingBytes = start + bytes;
    return {};
}

Result<void> Context::download(const Buffer& buffer, void* data, VkDeviceSize bytes,
                               VkDeviceSize offset) {
    PIC_CHECK(offset + bytes <= buffer.size());
    if (buffer.mapped()) {
        std::memcpy(data, static_cast<const char*>(buffer.mapped()) + offset, bytes);
        return {};
    }
    PIC_TRY_ASSIGN(Buffer* staging, this->staging(bytes));
    PIC_TRY(submit([&](VkCommandBuffer cmd) {
        const VkBufferCopy region{offset, 0, bytes};
        vkCmdCopyBuffer(cmd, buffer.handle(), staging->handle(), 1, &region);
    }));
    std::memcpy(data, staging->mapped(), bytes);
    return {};
}

Result<std::vector<float>> Context::downloadDepthLayer(const DepthArray& depth, uint32_t layer) {
    PIC_CHECK(layer < depth.layers());
    const VkDeviceSize bytes = VkDeviceSize{depth.size()} * depth.size() * sizeof(float);
    PIC_TRY_ASSIGN(Buffer staging, createBuffer(bytes, 0, MemoryUse::Readback, "depth download"));
    PIC_TRY(submit([&](VkCommandBuffer cmd) {
        // Earlier depth writes and shader reads finish before the copy reads the layer.
        VkImageMemoryBarrier toCopy{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
        toCopy.srcAccessMask = VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;
        toCopy.dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
        toCopy.oldLayout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
        toCopy.newLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
        toCopy.srcQueueFamilyIndex = toCopy.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
        toCopy.image = depth.image();
        toCopy.subresourceRange = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, layer, 1};
        vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
                             0, 0, nullptr, 0, nullptr, 1, &toCopy);
        VkBufferImageCopy region{};
        region.imageSubresource = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, layer, 1};
        region.imageExtent = {depth.size(), depth.size(), 1};
        vkCmdCopyImageToBuffer(cmd, depth.image(), VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                               staging.handle(), 1, &region);
        // The copy finishes before the layer is sampled or rendered again.
        VkImageMemoryBarrier back = toCopy;
        back.srcAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
        back.dstAccessMask = 0;
        back.oldLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
        back.newLayout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
        vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT,
                             0, 0, nullptr, 0, nullptr, 1, &back);
    }));
    std::vector<float> texels(size_t(depth.size()) * depth.size());
    std::memcpy(texels.data(), staging.mapped(), bytes);
    return texels;
}

Result<DepthArray> Context::createDepthArray(uint32_t size, uint32_t layers) {
    if (mLost) return fail(ErrorCode::Internal, "the Vulkan device \"{}\" was lost", mName);
    if (size == 0 || layers == 0 || size > mProperties.limits.maxImageDimension2D ||
        layers > mProperties.limits.maxImageArrayLayers)
        return fail(ErrorCode::InvalidInput,
                    "shadow maps of {}² × {} layers exceed the device's limits ({}², {} layers)",
                    size, layers, mProperties.limits.maxImageDimension2D,
                    mProperties.limits.maxImageArrayLayers);
    DepthArray depth;
    depth.mDevice = mDevice;
    depth.mSize = size;
    VkImageCreateInfo info{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
    info.imageType = VK_IMAGE_TYPE_2D;
    info.format = VK_FORMAT_D32_SFLOAT;
    info.extent = {size, size, 1};
    info.mipLevels = 1;
    info.arrayLayers = layers;
    info.samples = VK_SAMPLE_COUNT_1_BIT;
    info.tiling = VK_IMAGE_TILING_OPTIMAL;
    // Cleared once at creation; read back by downloadDepthLayer.
    info.usage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT |
                 VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
    info.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    PIC_VK_TRY(vkCreateImage(mDevice, &info, nullptr, &depth.mImage));
    VkMemoryRequirements requirements;
    vkGetImageMemoryRequirements(mDevice, depth.mImage, &requirements);
    VkMemoryPropertyFlags flags = 0;
    PIC_TRY(allocate(requirements, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, 0, depth.mMemory, flags,
                     "shadow maps"));
    PIC_VK_TRY(vkBindImageMemory(mDevice, depth.mImage, depth.mMemory, 0));

    VkImageViewCreateInfo viewInfo{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    viewInfo.image = depth.mImage;
    viewInfo.viewType = VK_IMAGE_VIEW_TYPE_2D_ARRAY;
    viewInfo.format = VK_FORMAT_D32_SFLOAT;
    viewInfo.subresourceRange = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, 0, layers};
    PIC_VK_TRY(vkCreateImageView(mDevice, &viewInfo, nullptr, &depth.mArrayView));
    for (uint32_t layer = 0; layer < layers; ++layer) {
        viewInfo.viewType = VK_IMAGE_VIEW_TYPE_2D;
        viewInfo.subresourceRange = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, layer, 1};
        VkImageView view = VK_NULL_HANDLE;
        PIC_VK_TRY(vkCreateImageView(mDevice, &viewInfo, nullptr, &view));
        depth.mLayerViews.push_back(view);
    }
    // Every layer starts readable (cleared to the far plane) so that a pass may sample layers
    // that no light rendered yet.
    PIC_TRY(submit([&](VkCommandBuffer cmd) {
        VkImageMemoryBarrier toClear{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
        toClear.srcAccessMask = 0;
        toClear.dstAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
        toClear.oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;
        toClear.newLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
        toClear.srcQueueFamilyIndex = toClear.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
        toClear.image = depth.mImage;
        toClear.subresourceRange = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, 0, layers};
        vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
                             0, 0, nullptr, 0, nullptr, 1, &toClear);
        const VkClearDepthStencilValue far{1.0f, 0};
        vkCmdClearDepthStencilImage(cmd, depth.mImage, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &far, 1,
                                    &toClear.subresourceRange);
        // The clear before any shader read of the layers.
        VkImageMemoryBarrier toRead = toClear;
        toRead.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
        toRead.dstAccessMask = VK_ACCESS_SHADER_READ_BIT;
        toRead.oldLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
        toRead.newLayout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
        vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT,
                             VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 0, nullptr, 0, nullptr, 1,
                             &toRead);
    }));
    return depth;
}

Result<RenderTarget> Context::createRenderTarget(uint32_t width, uint32_t height, VkFormat format,
                                                 const char* what) {
    if (mLost) return fail(ErrorCode::Internal, "the Vulkan device \"{}\" was lost", mName);
    const uint32_t limit = mProperties.limits.maxImageDimension2D;
    if (width == 0 || height == 0 || width > limit || height > limit)
        return fail(ErrorCode::InvalidInput, "{} of {}x{} is outside the device's 1..{} per side",
                    what, width, height, limit);
    const bool depth = format == VK_FORMAT_D32_SFLOAT;
    RenderTarget target;
    target.mDevice = mDevice;
    target.mFormat = format;
    target.mWidth = width;
    target.mHeight = height;
    VkImageCreateInfo info{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
    info.imageType = VK_IMAGE_TYPE_2D;
    info.format = format;
    info.extent = {width, height, 1};
    info.mipLevels = 1;
    info.arrayLayers = 1;
    info.samples = VK_SAMPLE_COUNT_1_BIT;
    info.tiling = VK_IMAGE_TILING_OPTIMAL;
    info.usage = depth ? VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT
                       : VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT;
    info.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    PIC_VK_TRY(vkCreateImage(mDevice, &info, nullptr, &target.mImage));
    VkMemoryRequirements requirements;
    vkGetImageMemoryRequirements(mDevice, target.mImage, &requirements);
    VkMemoryPropertyFlags flags = 0;
    PIC_TRY(allocate(requirements, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, 0, target.mMemory, flags,
                     what));
    PIC_VK_TRY(vkBindImageMemory(mDevice, target.mImage, target.mMemory, 0));
    target.mBytes = requirements.size;
    VkImageViewCreateInfo viewInfo{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    viewInfo.image = target.mImage;
    viewInfo.viewType = VK_IMAGE_VIEW_TYPE_2D;
    viewInfo.format = format;
    viewInfo.subresourceRange = {depth ? VkImageAspectFlags(VK_IMAGE_ASPECT_DEPTH_BIT)
                                       : VkImageAspectFlags(VK_IMAGE_ASPECT_COLOR_BIT),
                                 0, 1, 0, 1};
    PIC_VK_TRY(vkCreateImageView(mDevice, &viewInfo, nullptr, &target.mView));
    return target;
}

Result<VkPipeline> Context::createRasterPipeline(const RasterPipelineDesc& desc) {
    PIC_TRY_ASSIGN(VkShaderModule vertex, createShaderModule(desc.vertexSpirv, desc.vertexName));
    VkShaderModule fragment = VK_NULL_HANDLE;
    if (!desc.fragmentSpirv.empty()) {
        auto created = createShaderModule(desc.fragmentSpirv, desc.fragmentName);
        if (!created) {
            vkDestroyShaderModule(mDevice, vertex, nullptr);
            return std::unexpected(created.error());
        }
        fragment = *created;
    }
    VkPipelineShaderStageCreateInfo stages[2] = {
        {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO},
        {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO}};
    stages[0].stage = VK_SHADER_STAGE_VERTEX_BIT;
    stages[0].module = vertex;
    stages[0].pName = "main";
    stages[1].stage = VK_SHADER_STAGE_FRAGMENT_BIT;
    stages[1].module = fragment;
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
    VkPipelineViewportStateCreateInfo viewport{VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
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
    VkPipelineColorBlendStateCreateInfo blend{VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
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
    const VkResult r = vkCreateGraphicsPipelines(mDevice, VK_NULL_HANDLE, 1, &info, nullptr, &pipeline);
    vkDestroyShaderModule(mDevice, vertex, nullptr);
    if (fragment) vkDestroyShaderModule(mDevice, fragment, nullptr);
    PIC_VK_TRY(r);
    return pipeline;
}

Result<VkShaderModule> Context::createShaderModule(std::span<const uint32_t> spirv,
                                                   const char* what) {
    VkShaderModuleCreateInfo info{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    info.codeSize = spirv.size_bytes();
    info.pCode = spirv.data();
    VkShaderModule module = VK_NULL_HANDLE;
    if (VkResult r = vkCreateShaderModule(mDevice, &info, nullptr, &module); r != VK_SUCCESS)
        return fail(ErrorCode::Internal, "shader {} could not be loaded: {}", what, vkResultName(r));
    return module;
}

Result<PassTimer> Context::createPassTimer(uint32_t passes) {
    PassTimer timer;
    timer.mDevice = mDevice;
    timer.mCapacity = passes;
    timer.mPeriodNs = mProperties.limits.timestampPeriod;
    uint32_t familyCount = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(mPhysical, &familyCount, nullptr);
    std::vector<VkQueueFamilyProperties> families(familyCount);
    vkGetPhysicalDeviceQueueFamilyProperties(mPhysical, &familyCount, families.data());
    const uint32_t bits = families[mQueueFamily].timestampValidBits;
    timer.mValidMask = bits >= 64 ? ~uint64_t{0} : (uint64_t{1} << bits) - 1;
    VkQueryPoolCreateInfo info{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    info.queryType = VK_QUERY_TYPE_TIMESTAMP;
    info.queryCount = 2 * passes;
    PIC_VK_TRY(vkCreateQueryPool(mDevice, &info, nullptr, &timer.mPool));
    return timer;
}

Result<void> Context::submit(const std::function<void(VkCommandBuffer)>& record,
                             PassTimer* timer) {
    if (mLost) return fail(ErrorCode::Internal, "the Vulkan device \"{}\" was lost", mName);
    const auto lostOn = [&](VkResult r) {
        if (r == VK_ERROR_DEVICE_LOST) mLost = true;
    };
    PIC_VK_TRY(vkResetCommandBuffer(mCommandBuffer, 0));
    VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    PIC_VK_TRY(vkBeginCommandBuffer(mCommandBuffer, &begin));
    if (timer) vkCmdResetQueryPool(mCommandBuffer, timer->mPool, 0, 2 * timer->mCapacity);
    if (!mPending.empty()) {
        for (const PendingUpload& u : mPending) {
            const VkBufferCopy region{u.stagingOffset, u.targetOffset, u.bytes};
            vkCmdCopyBuffer(mCommandBuffer, mPendingStaging.handle(), u.target, 1, &region);
        }
        // The uploads land before any later command reads them.
        VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
        barrier.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
        barrier.dstAccessMask = VK_ACCESS_MEMORY_READ_BIT | VK_ACCESS_MEMORY_WRITE_BIT;
        vkCmdPipelineBarrier(mCommandBuffer, VK_PIPELINE_STAGE_TRANSFER_BIT,
                             VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, 0, 1, &barrier, 0, nullptr, 0,
                             nullptr);
        // Recorded: the staging bytes stay untouched until this submission has waited.
        mPending.clear();
        mPendingBytes = 0;
    }
    record(mCommandBuffer);
    // Whatever the submission wrote, the host may read once the fence has signalled (mapped
    // buffers are read in place).
    hostReadBarrier(mCommandBuffer);
    if (timer) timer->end(mCommandBuffer);
    PIC_VK_TRY(vkEndCommandBuffer(mCommandBuffer));
    VkSubmitInfo submitInfo{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    submitInfo.commandBufferCount = 1;
    submitInfo.pCommandBuffers = &mCommandBuffer;
    PIC_VK_TRY(vkResetFences(mDevice, 1, &mFence));
    VkResult r = vkQueueSubmit(mQueue, 1, &submitInfo, mFence);
    lostOn(r);
    PIC_VK_TRY(r);
    r = vkWaitForFences(mDevice, 1, &mFence, VK_TRUE, kSubmitTimeoutNs);
    lostOn(r);
    if (r == VK_TIMEOUT) {
        mLost = true;
        return fail(ErrorCode::Internal,
                    "the Vulkan device \"{}\" did not finish a submission within {} s; treating it "
                    "as lost",
                    mName, kSubmitTimeoutNs / 1000000000ull);
    }
    PIC_VK_TRY(r);
    return {};
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
