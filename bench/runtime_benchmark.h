#pragma once
/// `picbench runtime`: the runtime passes on the GPU backend against the CPU twin in the same
/// run, at paper 000 Table 2's settings (moderate: nS 32k, nL 128, l 3; high: nS 128k,
/// nL 254, l 4) with RTP and SH links. Per setting, link form and kind of light change
/// (`move-all`: every light moves, so every shadow map re-renders or every light's rays are
/// traced; `move-one`: the first point or spot light moves; `recolour`: intensities change,
/// visibility stays) and direct visibility (shadow maps or host rays) the
/// change is applied `repeat` times to each backend after a warm-up; the medians of the
/// update time and of every pass (GPU timestamps), the cache-lighting link bandwidth
/// against this machine's memcpy bandwidth, the GPU/CPU time ratio and the runtime memory
/// per buffer. Prints a table and writes JSON. Never asserts.
///
/// `picbench shadows`: the shadow-map size's trade-off. Per size, the wall-clock ms of the
/// GPU's direct light (every light's shadow maps + surfel lighting) against the CPU twin's
/// rays, and how far the GPU's direct surfel flux is from the rays' (relative L1, and the
/// fraction of surfels differing by more than 1 %); last, the same for the GPU backend with
/// host-traced rays (DirectVisibility::Rays), the exact end of the trade-off.

#include <string>
#include <vector>

namespace pic {

struct RuntimeBenchmarkParams {
    std::string scenePath;
    std::string lightsPath;                        ///< empty: the scene's lights
    std::vector<std::string> settings{"moderate", "high"};
    std::vector<std::string> linkModes{"rtp", "sh"};
    uint32_t chromaBands = 2;                      ///< lC
    std::vector<int> bounces{1, -1};               ///< per update; −1 = progressive
    std::vector<std::string> changes{"move-all", "move-one", "recolour"};
    int repeat = 5;
    std::string device;                            ///< Vulkan device name substring
    uint32_t shadowMapSize = 1024;
    bool shadowEqualFootprint = true;              ///< GpuRuntimeOptions::shadowEqualFootprint
    /// GpuRuntimeOptions::directVisibility, one GPU runtime each: auto, shadow-maps, rays.
    std::vector<std::string> visibilities{"auto"};
    /// GpuRuntimeOptions::lightmapCopyOnHost: auto, host or device.
    std::string lightmapCopy = "auto";
    std::string jsonPath = "out/runtime_benchmark.json";
};

/// Runs the benchmark; returns the process exit code.
int runRuntimeBenchmark(const RuntimeBenchmarkParams& params);

struct ShadowBenchmarkParams {
    std::string scenePath;
    std::string lightsPath;                        ///< empty: the scene's lights
    std::string setting = "moderate";
    std::vector<uint32_t> sizes{256, 512, 1024, 2048};
    std::vector<std::string> sides{"uniform", "footprint"};  ///< GpuRuntimeOptions::shadowEqualFootprint
    int repeat = 5;
    std::string device;
    std::string jsonPath = "out/shadow_benchmark.json";
};

/// Runs the shadow-map size sweep; returns the process exit code.
int runShadowBenchmark(const ShadowBenchmarkParams& params);

}  // namespace pic
