#include "gpu/timers.h"

#include "gpu/device.h"
#include "gpu/vk_error.h"

namespace pic::gpu {

Result<PassTimer> PassTimer::create(Context& context, uint32_t passes) {
    PassTimer timer;
    timer.mCapacity = passes;
    timer.mPeriodNs = context.properties().limits.timestampPeriod;
    const uint32_t bits = context.timestampValidBits();
    timer.mValidMask = bits >= 64 ? ~uint64_t{0} : (uint64_t{1} << bits) - 1;
    VkQueryPoolCreateInfo info{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    info.queryType = VK_QUERY_TYPE_TIMESTAMP;
    info.queryCount = 2 * passes;
    VkQueryPool pool = VK_NULL_HANDLE;
    PIC_VK_TRY(vkCreateQueryPool(context.device(), &info, nullptr, &pool));
    timer.mPool = {context.device(), pool};
    return timer;
}

void PassTimer::start(VkCommandBuffer cmd) {
    vkCmdResetQueryPool(cmd, mPool.get(), 0, 2 * mCapacity);
}

void PassTimer::begin(VkCommandBuffer cmd, const char* name) {
    if (mOpen) end(cmd);
    if (mNames.size() >= mCapacity) return;  // more passes than queries: the rest go untimed
    vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, mPool.get(),
                        uint32_t(2 * mNames.size()));
    mNames.emplace_back(name);
    mOpen = true;
}

void PassTimer::end(VkCommandBuffer cmd) {
    if (!mOpen) return;
    vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, mPool.get(),
                        uint32_t(2 * mNames.size() - 1));
    mOpen = false;
}

Result<void> PassTimer::collect(std::vector<std::pair<std::string, double>>& ms) {
    if (mNames.empty()) return {};
    std::vector<uint64_t> ticks(2 * mNames.size());
    PIC_VK_TRY(vkGetQueryPoolResults(
        mPool.device(), mPool.get(), 0, uint32_t(ticks.size()), ticks.size() * sizeof(uint64_t),
        ticks.data(), sizeof(uint64_t), VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT));
    for (size_t i = 0; i < mNames.size(); ++i) {
        const uint64_t start = ticks[2 * i] & mValidMask, stop = ticks[2 * i + 1] & mValidMask;
        const double ns = stop >= start ? double(stop - start) * mPeriodNs : 0.0;
        ms.emplace_back(mNames[i], ns * 1e-6);
    }
    mNames.clear();
    return {};
}

}  // namespace pic::gpu
