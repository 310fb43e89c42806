// gpu::Handle destroys its object exactly once, through moves, resets and releases, whichever
// way it leaves; a fake destroy function stands in for vkDestroy*.

#include <gtest/gtest.h>

#include <cstdint>
#include <type_traits>
#include <utility>
#include <vector>

#include "gpu/handle.h"

namespace pic::gpu {
namespace {

/// (device, fence) of every fakeDestroy call, in order.
std::vector<std::pair<VkDevice, VkFence>> destroyed;

void fakeDestroy(VkDevice device, VkFence fence, const VkAllocationCallbacks*) {
    destroyed.emplace_back(device, fence);
}

using FakeHandle = Handle<VkFence, fakeDestroy>;

static_assert(!std::is_copy_constructible_v<FakeHandle>);
static_assert(!std::is_copy_assignable_v<FakeHandle>);
static_assert(std::is_nothrow_move_constructible_v<FakeHandle>);
static_assert(std::is_nothrow_move_assignable_v<FakeHandle>);

// Distinct non-null values; never dereferenced.
const VkDevice kDevice = reinterpret_cast<VkDevice>(uintptr_t{0x100});
const VkFence kFirst = reinterpret_cast<VkFence>(uintptr_t{0x1});
const VkFence kSecond = reinterpret_cast<VkFence>(uintptr_t{0x2});

class GpuHandle : public testing::Test {
protected:
    void SetUp() override { destroyed.clear(); }
};

using Destroyed = std::vector<std::pair<VkDevice, VkFence>>;

TEST_F(GpuHandle, DestroysWithItsDeviceWhenItGoesOutOfScope) {
    {
        FakeHandle handle(kDevice, kFirst);
        EXPECT_EQ(handle.get(), kFirst);
        EXPECT_EQ(handle.device(), kDevice);
        EXPECT_TRUE(handle);
        EXPECT_TRUE(destroyed.empty());
    }
    EXPECT_EQ(destroyed, (Destroyed{{kDevice, kFirst}}));
}

TEST_F(GpuHandle, AnEmptyHandleDestroysNothing) {
    {
        FakeHandle handle;
        EXPECT_FALSE(handle);
    }
    EXPECT_TRUE(destroyed.empty());
}

TEST_F(GpuHandle, MoveConstructionTransfersOwnership) {
    {
        FakeHandle from(kDevice, kFirst);
        FakeHandle to(std::move(from));
        EXPECT_EQ(from.get(), VK_NULL_HANDLE);
        EXPECT_EQ(from.device(), VK_NULL_HANDLE);
        EXPECT_EQ(to.get(), kFirst);
    }
    EXPECT_EQ(destroyed, (Destroyed{{kDevice, kFirst}}));
}

TEST_F(GpuHandle, MoveAssignmentDestroysWhatItHeldAtOnce) {
    {
        FakeHandle from(kDevice, kFirst);
        FakeHandle to(kDevice, kSecond);
        to = std::move(from);
        EXPECT_EQ(destroyed, (Destroyed{{kDevice, kSecond}}));
        EXPECT_EQ(from.get(), VK_NULL_HANDLE);
        EXPECT_EQ(to.get(), kFirst);
    }
    EXPECT_EQ(destroyed, (Destroyed{{kDevice, kSecond}, {kDevice, kFirst}}));
}

TEST_F(GpuHandle, SelfMoveAssignmentKeepsTheObject) {
    {
        FakeHandle handle(kDevice, kFirst);
        FakeHandle& alias = handle;
        handle = std::move(alias);
        EXPECT_EQ(handle.get(), kFirst);
        EXPECT_TRUE(destroyed.empty());
    }
    EXPECT_EQ(destroyed, (Destroyed{{kDevice, kFirst}}));
}

TEST_F(GpuHandle, ResetDestroysOnceAndEmpties) {
    FakeHandle handle(kDevice, kFirst);
    handle.reset();
    EXPECT_EQ(handle.get(), VK_NULL_HANDLE);
    handle.reset();
    EXPECT_EQ(destroyed, (Destroyed{{kDevice, kFirst}}));
    handle = FakeHandle(kDevice, kSecond);  // reusable after a reset
    EXPECT_EQ(handle.get(), kSecond);
}

TEST_F(GpuHandle, ReleaseGivesTheObjectUpWithoutDestroyingIt) {
    {
        FakeHandle handle(kDevice, kFirst);
        EXPECT_EQ(handle.release(), kFirst);
        EXPECT_EQ(handle.get(), VK_NULL_HANDLE);
    }
    EXPECT_TRUE(destroyed.empty());
}

TEST_F(GpuHandle, AGrowingVectorDestroysEachObjectOnce) {
    {
        std::vector<FakeHandle> handles;
        for (uintptr_t i = 1; i <= 100; ++i)
            handles.emplace_back(kDevice, reinterpret_cast<VkFence>(i));
        EXPECT_TRUE(destroyed.empty());  // reallocation moved them, destroyed none
    }
    ASSERT_EQ(destroyed.size(), 100u);
    std::vector<bool> seen(101, false);
    for (const auto& [device, fence] : destroyed) {
        const uintptr_t i = reinterpret_cast<uintptr_t>(fence);
        ASSERT_TRUE(i >= 1 && i <= 100 && !seen[i]) << i;
        seen[i] = true;
    }
}

}  // namespace
}  // namespace pic::gpu
