#pragma once
/// `picbench runtime`: the runtime passes on the GPU backend against the CPU twin in the same
/// run, at paper 000 Table 2's settings (moderate: nS 32k, nL 128, l 3; high: nS 128k,
/// nL 254, l 4) with RTP and SH links. Per setting and link form: a light change that moves
/// one light (its shadow map re-renders) is applied `repeat` times to each backend after a
/// warm-up; the medians of the update time and of every pass (GPU timestamps), the
/// cache-lighting link bandwidth against this machine's memcpy bandwidth, the GPU/CPU time
/// ratio and the runtime memory per buffer. Prints a table and writes JSON. Never asserts.

#include <string>
#include <vector>

namespace pic {

struct RuntimeBenchmarkParams {
    std::string scenePath;
    std::string lightsPath;                        ///< empty: the scene's lights
    std::vector<std::string> settings{"moderate", "high"};
    std::vector<std::string> linkModes{"rtp", "sh"};
    std::vector<int> bounces{1, -1};               ///< per update; −1 = progressive
    int repeat = 5;
    std::string device;                            ///< Vulkan device name substring
    uint32_t shadowMapSize = 1024;
    std::string jsonPath = "runtime_benchmark.json";
};

/// Runs the benchmark; returns the process exit code.
int runRuntimeBenchmark(const RuntimeBenchmarkParams& params);

}  // namespace pic
