#pragma once
/// The device memory bandwidth a compute shader sees: the floor the runtime benchmark
/// compares cache lighting with on a GPU (on a CPU device the floor is the host's memcpy).

#include <cstdint>

#include "gpu/device.h"

namespace pic::gpu {

struct CopyProbeParams {
    VkDeviceSize bytes = VkDeviceSize{256} << 20;  ///< per copy, a multiple of 16
    int copiesPerSubmission = 8;  ///< back to back, so that clocks are up and no gap counts
    int submissions = 6;          ///< the first is a warm-up
    uint32_t maxGroups = 65535;   ///< workgroups per dispatch; each strides over the rest
};

/// Bytes copied per second by a compute shader copying one device buffer into another,
/// by timestamps: the median over the timed submissions. The copy is checked against the
/// data it was given (an error when it differs). The benchmarks take memcpy as the floor on
/// a CPU device (whose timestamps were once seen not to wait for a dispatch); the check
/// holds on any device.
Result<double> computeCopyBandwidth(Context& context, const CopyProbeParams& params = {});

}  // namespace pic::gpu
