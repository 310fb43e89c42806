#include "gpu/device.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <cstring>
#include <vector>

#include <fmt/format.h>

#include "gpu/timers.h"
#include "gpu/vk_error.h"

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
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU:
        return 0;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU:
        return 1;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU:
        return 2;
    case VK_PHYSICAL_DEVICE_TYPE_CPU:
        return 3;
    default:
        return 4;
    }
}

bool layerAvailable(const char* name) {
    uint32_t count = 0;
    if (vkEnumerateInstanceLayerProperties(&count, nullptr) != VK_SUCCESS) return false;
    std::vector<VkLayerProperties> layers(count);
    if (vkEnumerateInstanceLayerProperties(&count, layers.data()) != VK_SUCCESS) return false;
    return std::any_of(layers.begin(), layers.end(), [&](const VkLayerProperties& l) {
        return std::strcmp(l.layerName, name) == 0;
    });
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
            return fail(ErrorCode::NotFound,
                        "no Vulkan 1.3 device matches --device \"{}\"; devices: {}",
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
    VkPhysicalDeviceSubgroupProperties subgroups{
        VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES};
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
            mTimestampBits = families[f].timestampValidBits;
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
        mStaging = {};
        mPendingStaging = {};
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

bool Context::canReadTexels(VkFormat format) const {
    VkFormatProperties properties{};
    vkGetPhysicalDeviceFormatProperties(mPhysical, format, &properties);
    return (properties.bufferFeatures & VK_FORMAT_FEATURE_UNIFORM_TEXEL_BUFFER_BIT) != 0;
}

Result<void> Context::checkAlive() const {
    if (mLost) return fail(ErrorCode::Internal, "the Vulkan device \"{}\" was lost", mName);
    return {};
}

Result<void> Context::submit(const std::function<void(VkCommandBuffer)>& record, PassTimer* timer) {
    PIC_TRY(checkAlive());
    const auto lostOn = [&](VkResult r) {
        if (r == VK_ERROR_DEVICE_LOST) mLost = true;
    };
    PIC_VK_TRY(vkResetCommandBuffer(mCommandBuffer, 0));
    VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    PIC_VK_TRY(vkBeginCommandBuffer(mCommandBuffer, &begin));
    if (timer) timer->start(mCommandBuffer);
    recordPendingUploads(mCommandBuffer);
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

}  // namespace pic::gpu
