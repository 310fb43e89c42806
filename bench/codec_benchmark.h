#pragma once
/// `picbench codec`: what the stream costs per frame. Bakes the scene at a paper 000 Table 2
/// setting, runs `updates` light changes on one runtime backend, turns each update's caches
/// into the stream's half planes and encodes them as a key frame and as a delta from the
/// previous update, at each of several zstd levels. Prints per level the median bytes, bits
/// per cache coefficient and encode and decode ms, and checks that decoding gives back the
/// encoder's input exactly (exit 1 if not). Writes JSON and, beside it, a PNG chart of size
/// against encode time, one point per level.

#include <string>
#include <vector>

namespace pic {

struct CodecBenchmarkParams {
    std::string scenePath;
    std::string lightsPath;            ///< empty: the scene's lights
    std::string setting = "moderate";
    std::string linkMode = "rtp";
    uint32_t chromaBands = 2;          ///< lC
    std::string backend = "cpu";       ///< "cpu" or "gpu": the textures are the same to 1 %
    std::string change = "move-one";   ///< bench_common.h changedLights
    int updates = 10;
    std::vector<int> zstdLevels{1, 3, 6, 9,
                                19};  ///< every frame is coded at each (picserver's default: 3)
    std::string jsonPath = "out/codec_benchmark.json";
};

int runCodecBenchmark(const CodecBenchmarkParams& params);

}  // namespace pic
