#pragma once
/// `picbench glossy` (docs/accuracy.md, "Glossy accuracy"): how well the client's glossy lobe,
/// a Phong lobe convolved with the caches' SH (paper 000 §3.2, Figure 8), reproduces the same
/// lobe path-traced (`picref --component glossy`), against the lobe's exponent and the SH
/// bands lY. Ideal caches (path-traced incident radiance, 8 bands) truncated to each lY take
/// the caches' own error out; the bake's linked caches show the product at its own lY.

#include <cstdint>
#include <string>
#include <vector>

#include "bake/bake.h"
#include "core/cache_values.h"
#include "core/cli.h"

namespace pic {

struct GlossyParams {
    std::string scenePath;
    std::string lightsPath;  ///< empty: the scene's own lights
    View view;               ///< image size and camera
    uint32_t spp = 1024;            ///< reference samples per pixel (two halves of spp/2)
    uint32_t probeSamples = 2048;   ///< path-traced directions per ideal cache
    uint32_t shadeSpp = 4;          ///< subsamples per pixel shading from the caches
    std::vector<uint32_t> bands{1, 2, 3, 4, 5, 6, 7, 8};   ///< lY of the truncated ideal caches
    std::vector<float> exponents{1, 2, 5, 10, 20, 30};     ///< Phong exponents n
    BakeOptions bake;
    std::string jsonPath = "out/glossy/glossy.json";  ///< the chart goes beside it
    uint64_t seed = 1;
};

/// The first `bands` SH bands of `values`, luma and chroma alike (lC = lY = bands): the
/// projection of the same radiance onto fewer bands. `bands` in 1..values.bandsC.
CacheValues truncateBands(const CacheValues& values, uint32_t bands);

/// Runs the comparison, prints the table, writes the JSON and a PNG chart; the exit code.
int runGlossyBenchmark(const GlossyParams& params);

}  // namespace pic
