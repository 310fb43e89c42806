// The Vulkan context's failures come back as errors that say what failed.

#include <gtest/gtest.h>

#include <string>

#include "gpu/device.h"
#include "gpu/vk_error.h"

namespace pic::gpu {
namespace {

TEST(GpuContext, DeviceLostIsReportedAsAnError) {
    const Error e = vkError(VK_ERROR_DEVICE_LOST, "vkQueueSubmit", "file.cpp", 12);
    EXPECT_EQ(e.code, ErrorCode::Internal);
    EXPECT_NE(e.message.find("VK_ERROR_DEVICE_LOST"), std::string::npos);
    EXPECT_NE(e.message.find("lost"), std::string::npos);
    EXPECT_NE(e.message.find("file.cpp:12"), std::string::npos);
}

TEST(GpuContext, UnknownDeviceNameIsNotFound) {
    auto context = Context::create({"no-such-device-name", false});
    ASSERT_FALSE(context);
    EXPECT_EQ(context.error().code, ErrorCode::NotFound);
    EXPECT_NE(context.error().message.find("no-such-device-name"), std::string::npos);
}

}  // namespace
}  // namespace pic::gpu
