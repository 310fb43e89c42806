#pragma once
/// `picbench soak`: the server held under a steady load for a long time, from outside. Bakes
/// the scene, starts picserver as a child on a free loopback port and runs `picclient load`'s
/// test in this process: `clients` subscribers decoding every frame of one session while an
/// editor changes a light `updateRate` times a second for `duration` seconds. Samples the
/// server's resident memory every second. Passes when every subscriber ends with the last
/// version (no lost final state), nothing failed, and the resident memory grew less than
/// `maxRssGrowthPercent` from the end of the first tenth of the run (start-up and the first
/// frames allocate) to the end. Prints the verdict, writes JSON and a chart of memory and
/// latency over time.

#include <cstdint>
#include <string>

namespace pic {

struct SoakBenchmarkParams {
    std::string scenePath;
    std::string bakePath;         ///< a bake of the scene to serve; empty: bake it at `setting`
    std::string setting = "moderate";
    std::string backend = "gpu";
    uint32_t clients = 200;
    double updateRate = 10.0;     ///< light changes per second
    double duration = 600.0;      ///< seconds
    double maxRssGrowthPercent = 5.0;
    std::string picserver;        ///< empty: the build tree's
    std::string jsonPath = "out/soak.json";
};

/// 0 when the soak passed, 1 when it failed its criteria, 2 for bad input.
int runSoakBenchmark(const SoakBenchmarkParams& params);

}  // namespace pic
