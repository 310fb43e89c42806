// The sky on lavapipe (or the machine's GPU) against its CPU twins: the sky_caches pass adds
// the same folded sky to given caches as render/cpu/sky_caches.h, and surfel lighting's direct
// part adds the same sky irradiance as directSurfelFlux.

#include <gtest/gtest.h>

#include <cmath>

#include "core/light_set.h"
#include "core/sky.h"
#include "render/cpu/cache_lighting.h"
#include "render/cpu/sky_caches.h"
#include "render/cpu/surfel_lighting.h"
#include "tests/render/gpu_fixture.h"

namespace pic {
namespace {

/// A sky that is not constant: every coefficient of every channel set.
std::array<glm::vec3, kSkyCoefficients> unevenSky() {
    std::array<glm::vec3, kSkyCoefficients> sh{};
    for (int k = 0; k < kSkyCoefficients; ++k)
        sh[size_t(k)] = glm::vec3(0.3f + 0.05f * float(k), 0.25f - 0.04f * float(k), 0.5f) *
                        (k == 0 ? 6.0f : 1.0f);
    return sh;
}

TEST(GpuSkyCaches, AddsWhatTheCpuTwinAdds) {
    const test::BakedScene& b = test::smallBake("cornell", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    auto gpu = test::gpuFor(b);
    ASSERT_TRUE(gpu);
    // The lamp's caches, then the sky on top of them.
    CacheValues caches;
    lightCaches(b.bake, test::cpuNodeFlux(b, defaultLightSet(b.scene)), caches);
    const SkyCacheWeights weights = skyCacheWeights(unevenSky(), int(b.bake.params.bandsY),
                                                    int(b.bake.params.bandsC));
    CacheValues cpu = caches;
    addSkyToCaches(b.bake, weights, cpu);
    auto result = gpu->runSkyCaches(caches, weights);
    ASSERT_TRUE(result) << result.error().message;
    for (const auto& [ours, theirs, before, name] :
         {std::tuple{&result->y, &cpu.y, &caches.y, "Y"},
          std::tuple{&result->co, &cpu.co, &caches.co, "Co"},
          std::tuple{&result->cg, &cpu.cg, &caches.cg, "Cg"}}) {
        ASSERT_EQ(ours->size(), theirs->size()) << name;
        // Half floats, rounded on the GPU before the sky (2^-11 of the lamp's value) and after
        // (2^-11 of the sum).
        for (size_t i = 0; i < theirs->size(); ++i)
            ASSERT_NEAR((*ours)[i], (*theirs)[i],
                        6e-4f * (std::abs((*before)[i]) + std::abs((*theirs)[i])) + 1e-6f)
                << name << " coefficient " << i;
    }
    // The sky changed the caches: it is not the rounding that matched.
    double moved = 0.0;
    for (size_t i = 0; i < cpu.y.size(); ++i) moved += std::abs(cpu.y[i] - caches.y[i]);
    EXPECT_GT(moved, 1.0);
    EXPECT_EQ(gpu->context().validationMessages(), 0u);
}

TEST(GpuSurfelLighting, DirectPartAddsTheSkyAsTheCpuTwin) {
    const test::BakedScene& b = test::smallBake("cornell", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    auto gpu = test::gpuFor(b);
    ASSERT_TRUE(gpu);
    LightSet lights = defaultLightSet(b.scene);
    lights.sky = SkyLight{.color = {0.6f, 0.75f, 1.0f}, .intensity = 3.0f};
    auto direct = gpu->runDirect(lights);
    ASSERT_TRUE(direct) << direct.error().message;
    std::vector<glm::vec3> cpu(b.bake.surfels.size());
    const auto sh = resolveSky(*lights.sky, b.scene.sourcePath)->project();
    directSurfelFlux(b.scene, *b.rays, b.bake, lights, cpu, &sh);
    std::vector<glm::vec3> lampOnly(b.bake.surfels.size());
    directSurfelFlux(b.scene, *b.rays, b.bake, defaultLightSet(b.scene), lampOnly);
    size_t skyLit = 0;
    for (size_t i = 0; i < cpu.size(); ++i) {
        for (int c = 0; c < 3; ++c)
            ASSERT_NEAR((*direct)[i][c], cpu[i][c], 1e-4f * std::abs(cpu[i][c]) + 1e-7f)
                << "surfel " << i << " channel " << c;
        if (cpu[i].b > lampOnly[i].b * 1.01f + 1e-9f) ++skyLit;
    }
    // The open front lets the sky onto most of the box's surfels.
    EXPECT_GT(skyLit, cpu.size() / 2);
    EXPECT_EQ(gpu->context().validationMessages(), 0u);
}

}  // namespace
}  // namespace pic
