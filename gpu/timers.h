#pragma once
/// Per-pass GPU timings from Vulkan timestamp queries.

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <vulkan/vulkan.h>

#include "core/error.h"
#include "gpu/handle.h"

namespace pic::gpu {

class Context;

/// Timestamps of named passes inside one command buffer; Context::submit starts and ends it.
class PassTimer {
public:
    /// A timer for up to `passes` pass instances per command buffer.
    static Result<PassTimer> create(Context& context, uint32_t passes);

    /// Resets the queries at the start of a command buffer (Context::submit does).
    void start(VkCommandBuffer cmd);
    /// Marks the start of pass `name` (ends the previous pass, if any).
    void begin(VkCommandBuffer cmd, const char* name);
    /// Marks the end of the current pass.
    void end(VkCommandBuffer cmd);
    /// After the command buffer completed: adds each pass's milliseconds to `ms` by name.
    Result<void> collect(std::vector<std::pair<std::string, double>>& ms);

private:
    QueryPool mPool;
    uint32_t mCapacity = 0;
    double mPeriodNs = 1.0;
    uint64_t mValidMask = ~uint64_t{0};
    std::vector<std::string> mNames;  ///< pass of query pair i
    bool mOpen = false;
};

}  // namespace pic::gpu
