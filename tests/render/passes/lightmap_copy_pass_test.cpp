// The light-map copy pass on lavapipe (or the machine's GPU) against its CPU twin
// (core/cache_textures.h copyCachesToTextures): the same grid and light-map layers, to
// half-float rounding, and the same coverage.

#include <gtest/gtest.h>

#include <cmath>

#include "core/cache_textures.h"
#include "core/light_set.h"
#include "render/cpu/cache_lighting.h"
#include "tests/render/gpu_fixture.h"

namespace pic {
namespace {

TEST(GpuLightmapCopy, TexturesMatchTheCpuTwin) {
    const test::BakedScene& b = test::smallBake("cornell", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    auto gpu = test::gpuFor(b);
    ASSERT_TRUE(gpu);
    CacheValues caches;
    lightCaches(b.bake, test::cpuNodeFlux(b, defaultLightSet(b.scene)), caches);
    CacheTextures cpu = makeCacheTextures(b.bake);
    copyCachesToTextures(b.bake, caches, cpu);
    auto textures = gpu->runLightmapCopy(caches);
    ASSERT_TRUE(textures) << textures.error().message;
    for (int ch = 0; ch < 3; ++ch) {
        ASSERT_EQ(textures->grid[ch].size(), cpu.grid[ch].size());
        ASSERT_EQ(textures->lightmap[ch].size(), cpu.lightmap[ch].size());
        // Half floats: 11 significant bits.
        for (size_t i = 0; i < cpu.grid[ch].size(); ++i)
            ASSERT_NEAR(textures->grid[ch][i], cpu.grid[ch][i], 1e-3f * std::abs(cpu.grid[ch][i]) + 1e-7f);
        for (size_t i = 0; i < cpu.lightmap[ch].size(); ++i)
            ASSERT_NEAR(textures->lightmap[ch][i], cpu.lightmap[ch][i],
                        1e-3f * std::abs(cpu.lightmap[ch][i]) + 1e-7f);
    }
    EXPECT_EQ(textures->gridCoverage, cpu.gridCoverage);
    EXPECT_EQ(textures->lightmapCoverage, cpu.lightmapCoverage);
}

}  // namespace
}  // namespace pic
