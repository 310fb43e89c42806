#pragma once
/// Vulkan results as pic Errors (STYLE.md 19): every failed Vulkan call comes back as an Error
/// naming the call, its VkResult and file:line; nothing in pic_gpu exits the process.

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
#define PIC_VK_TRY(expr)                                                                          \
    do {                                                                                          \
        const VkResult picVkResult_ = (expr);                                                     \
        if (picVkResult_ < 0)                                                                     \
            return std::unexpected(::pic::gpu::vkError(picVkResult_, #expr, __FILE__, __LINE__)); \
    } while (false)
