// Buffers, depth arrays and render targets on the Vulkan device (lavapipe in CI): bytes survive
// upload and download whether device memory is mapped or staged, moved-from resources are
// empty, and failures come back as errors. Every test ends with no validation message.

#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <numeric>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <vulkan/vulkan.h>

#include "gpu/device.h"
#include "gpu/resources.h"

namespace pic::gpu {
namespace {

/// Vulkan physical devices on this machine (0 when no Vulkan implementation opens at all).
uint32_t vulkanDeviceCount() {
    VkInstanceCreateInfo info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    VkInstance instance = VK_NULL_HANDLE;
    if (vkCreateInstance(&info, nullptr, &instance) != VK_SUCCESS) return 0;
    uint32_t count = 0;
    if (vkEnumeratePhysicalDevices(instance, &count, nullptr) != VK_SUCCESS) count = 0;
    vkDestroyInstance(instance, nullptr);
    return count;
}

/// Opens a context for each test (skipping only where no Vulkan device exists) and checks
/// that the test left no validation message.
class GpuResources : public testing::Test {
protected:
    void SetUp() override {
        auto created = Context::create({.mapDeviceMemory = mapDeviceMemory()});
        if (!created && vulkanDeviceCount() == 0) GTEST_SKIP() << "no Vulkan device";
        ASSERT_TRUE(created) << created.error().message;
        mContext = std::move(*created);
    }
    void TearDown() override {
        if (mContext) {
            EXPECT_EQ(mContext->validationMessages(), 0u);
        }
    }
    virtual bool mapDeviceMemory() const { return true; }
    Context& context() { return *mContext; }

private:
    std::unique_ptr<Context> mContext;
};

std::vector<uint32_t> iota(size_t count, uint32_t first) {
    std::vector<uint32_t> words(count);
    std::iota(words.begin(), words.end(), first);
    return words;
}

/// Mapped device memory (lavapipe's default) and staged transfers (a discrete GPU's path).
class GpuBuffer : public GpuResources, public testing::WithParamInterface<bool> {
protected:
    bool mapDeviceMemory() const override { return GetParam(); }
};

TEST_P(GpuBuffer, BytesSurviveUploadAndDownload) {
    const std::vector<uint32_t> words = iota(1000, 7);
    auto buffer = Buffer::createWith(context(), std::span<const uint32_t>(words), 0, "round trip");
    ASSERT_TRUE(buffer) << buffer.error().message;
    EXPECT_EQ(buffer->size(), words.size() * sizeof(uint32_t));
    // Unmapped when asked; mapped where device memory is the host's otherwise.
    if (!GetParam()) {
        EXPECT_EQ(buffer->mapped(), nullptr);
    } else if (context().isCpuDevice()) {
        EXPECT_NE(buffer->mapped(), nullptr);
    }

    std::vector<uint32_t> back(words.size());
    ASSERT_TRUE(context().download(*buffer, back.data(), back.size() * sizeof(uint32_t)));
    EXPECT_EQ(back, words);

    // A range at an offset, then one that waits for the next submission.
    const std::vector<uint32_t> middle = iota(10, 5000), last = iota(4, 9000);
    ASSERT_TRUE(context().upload(*buffer, middle.data(), 40, 400));
    ASSERT_TRUE(context().uploadWithNextSubmit(*buffer, last.data(), 16, 3984));
    ASSERT_TRUE(context().submit([](VkCommandBuffer) {}));
    std::vector<uint32_t> expected = words;
    std::copy(middle.begin(), middle.end(), expected.begin() + 100);
    std::copy(last.begin(), last.end(), expected.end() - 4);
    ASSERT_TRUE(context().download(*buffer, back.data(), back.size() * sizeof(uint32_t)));
    EXPECT_EQ(back, expected);
    std::vector<uint32_t> part(10);
    ASSERT_TRUE(context().download(*buffer, part.data(), 40, 400));
    EXPECT_EQ(part, middle);
}

INSTANTIATE_TEST_SUITE_P(Memory, GpuBuffer, testing::Bool(),
                         [](const testing::TestParamInfo<bool>& info) {
                             return info.param ? "Mapped" : "Staged";
                         });

TEST_F(GpuResources, AMovedFromBufferIsEmpty) {
    auto created = Buffer::create(context(), 256, 0, MemoryUse::Readback, "moved");
    ASSERT_TRUE(created) << created.error().message;
    const VkBuffer handle = created->handle();
    ASSERT_NE(handle, VK_NULL_HANDLE);
    ASSERT_NE(created->mapped(), nullptr);  // readback memory is always mapped

    Buffer moved = std::move(*created);
    EXPECT_EQ(created->handle(), VK_NULL_HANDLE);
    EXPECT_EQ(created->size(), 0u);
    EXPECT_EQ(created->mapped(), nullptr);
    EXPECT_EQ(moved.handle(), handle);
    EXPECT_EQ(moved.size(), 256u);

    // Assigning over a buffer frees it; the moved-from one takes a new buffer.
    auto other = Buffer::create(context(), 64, 0, MemoryUse::Device, "other");
    ASSERT_TRUE(other) << other.error().message;
    moved = std::move(*other);
    EXPECT_EQ(moved.size(), 64u);
    *created = std::move(moved);
    EXPECT_EQ(created->size(), 64u);
    EXPECT_EQ(moved.handle(), VK_NULL_HANDLE);
}

TEST_F(GpuResources, OutOfMemoryIsAnError) {
    auto buffer =
        Buffer::create(context(), VkDeviceSize{1} << 44, 0, MemoryUse::Device, "huge test buffer");
    ASSERT_FALSE(buffer);
    EXPECT_NE(buffer.error().message.find("out of memory"), std::string::npos)
        << buffer.error().message;
    // The context stays usable after the failure.
    auto small = Buffer::create(context(), 1024, 0, MemoryUse::Device, "small test buffer");
    EXPECT_TRUE(small) << (small ? "" : small.error().message);
}

TEST_F(GpuResources, ADepthArrayStartsAtTheFarPlane) {
    auto depth = DepthArray::create(context(), 16, 3);
    ASSERT_TRUE(depth) << depth.error().message;
    EXPECT_EQ(depth->layers(), 3u);
    EXPECT_EQ(depth->bytes(), 16u * 16u * 3u * 4u);
    for (uint32_t layer = 0; layer < 3; ++layer) {
        EXPECT_NE(depth->layerView(layer), VK_NULL_HANDLE);
        auto texels = context().downloadDepthLayer(*depth, layer);
        ASSERT_TRUE(texels) << texels.error().message;
        ASSERT_EQ(texels->size(), 256u);
        for (float d : *texels) ASSERT_EQ(d, 1.0f);
    }
}

TEST_F(GpuResources, RenderTargetsCheckTheirSize) {
    auto colour = RenderTarget::create(context(), 40, 30, VK_FORMAT_R32G32B32A32_SFLOAT, "colour");
    ASSERT_TRUE(colour) << colour.error().message;
    EXPECT_EQ(colour->width(), 40u);
    EXPECT_EQ(colour->height(), 30u);
    EXPECT_GE(colour->bytes(), 40u * 30u * 16u);
    EXPECT_NE(colour->view(), VK_NULL_HANDLE);
    auto empty = RenderTarget::create(context(), 0, 30, VK_FORMAT_D32_SFLOAT, "empty target");
    ASSERT_FALSE(empty);
    EXPECT_EQ(empty.error().code, ErrorCode::InvalidInput);
    EXPECT_NE(empty.error().message.find("empty target"), std::string::npos);
}

}  // namespace
}  // namespace pic::gpu
