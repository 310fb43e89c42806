#include "gpu/vk_error.h"

#include <fmt/format.h>

namespace pic::gpu {

const char* vkResultName(VkResult result) {
    switch (result) {
#define PIC_VK_CASE(name) \
    case name:            \
        return #name;
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
    default:
        return "VK_RESULT_UNKNOWN";
    }
}

Error vkError(VkResult result, const char* call, const char* file, int line) {
    const char* hint = "";
    if (result == VK_ERROR_OUT_OF_DEVICE_MEMORY || result == VK_ERROR_OUT_OF_HOST_MEMORY)
        hint = " (out of memory: use a smaller bake or a device with more memory)";
    else if (result == VK_ERROR_DEVICE_LOST)
        hint = " (the GPU device was lost; the runtime must be recreated)";
    return Error{ErrorCode::Internal, fmt::format("Vulkan call {} failed with {}{} at {}:{}", call,
                                                  vkResultName(result), hint, file, line)};
}

}  // namespace pic::gpu
