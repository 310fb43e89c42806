#pragma once
/// `picbench bake`: times every bake stage on one scene (median of repeats), peak memory
/// and bytes per bake-file section; prints a table and writes JSON. Never asserts.

#include <string>

#include "bake/bake.h"

namespace pic {

struct BakeBenchmarkParams {
    std::string scenePath;
    BakeOptions options;
    uint32_t repeat = 1;
    std::string jsonPath;  ///< empty: no JSON file
};

/// Runs the benchmark; returns the process exit code.
int runBakeBenchmark(const BakeBenchmarkParams& params);

}  // namespace pic
