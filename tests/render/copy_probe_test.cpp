// The copy probe (render/copy_probe.h): the bandwidth floor the runtime benchmark compares
// cache lighting with on a GPU copies every word and refuses sizes it cannot copy.

#include <gtest/gtest.h>

#include <string>

#include "gpu/device.h"
#include "render/copy_probe.h"

namespace pic {
namespace {

TEST(GpuCopyProbe, CopiesEveryWordAndReportsARate) {
    auto context = gpu::Context::create({.mapDeviceMemory = false});
    ASSERT_TRUE(context) << context.error().message;
    // Fewer workgroups than the data needs: each strides over the rest, past a partial group.
    auto rate = gpu::computeCopyBandwidth(
        **context, {.bytes = 16 * 3001, .copiesPerSubmission = 2, .submissions = 3, .maxGroups = 3});
    ASSERT_TRUE(rate) << rate.error().message;
    EXPECT_GT(*rate, 0.0);
    auto bad = gpu::computeCopyBandwidth(**context, {.bytes = 20});
    ASSERT_FALSE(bad);
    EXPECT_EQ(bad.error().code, ErrorCode::InvalidInput);
    EXPECT_NE(bad.error().message.find("20"), std::string::npos) << bad.error().message;
}

}  // namespace
}  // namespace pic
