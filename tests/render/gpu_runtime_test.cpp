// The whole GPU runtime on lavapipe (or whatever Vulkan device the machine has): progressive
// updates against the CPU runtime for every link form and visibility, unmapped device memory
// and the host's or the device's light-map copy giving the same results bit for bit, the
// default visibility and copy per device, and refusals.
// Each pass alone against its CPU twin: tests/render/passes/.

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <cmath>
#include <string>
#include <tuple>
#include <vector>

#include <unistd.h>

#include "core/image.h"
#include "core/light_set.h"
#include "render/cpu_runtime.h"
#include "render/gpu_runtime.h"
#include "tests/render/gpu_fixture.h"

namespace pic {
namespace {

class GpuRuntimeForms : public testing::TestWithParam<std::tuple<LinkMode, gpu::DirectVisibility>> {
};

TEST_P(GpuRuntimeForms, ProgressiveUpdateMatchesTheCpuRuntime) {
    const auto [mode, visibility] = GetParam();
    const test::BakedScene& b = test::smallBake("cornell", mode);
    ASSERT_TRUE(b.ok);
    auto gpu = test::gpuFor(b, {}, {.directVisibility = visibility});
    ASSERT_TRUE(gpu);
    auto cpu = createCpuRuntime(b.scene, *b.rays, b.bake, BounceParams{});
    ASSERT_TRUE(cpu);
    const LightSet lights = defaultLightSet(b.scene);
    UpdateStats gpuStats, cpuStats;
    auto cpuValues = (*cpu)->setLights(lights, &cpuStats);
    ASSERT_TRUE(cpuValues) << cpuValues.error().message;
    auto gpuValues = gpu->setLights(lights, &gpuStats);
    ASSERT_TRUE(gpuValues) << gpuValues.error().message;
    EXPECT_EQ(gpuStats.bounces, cpuStats.bounces);
    EXPECT_NEAR(gpuStats.surfelFlux / cpuStats.surfelFlux, 1.0, 0.01);
    EXPECT_LE(test::relativeL2(**gpuValues, **cpuValues), 0.01);
    for (float v : (*gpuValues)->y) ASSERT_TRUE(std::isfinite(v));
    // The textures are the caches, copied.
    auto textures = gpu->textures();
    ASSERT_TRUE(textures) << textures.error().message;
    auto cpuTextures = (*cpu)->textures();
    ASSERT_TRUE(cpuTextures);
    EXPECT_EQ((*textures)->grid[0].size(), (*cpuTextures)->grid[0].size());
    EXPECT_EQ(gpu->context().validationMessages(), 0u);
}

// What a budgeted server streams early (server/progressive.h): both backends show every
// bounce's caches as they compute them, the last one flagged, and the GPU's bounces are the
// CPU twin's.
TEST(GpuRuntime, EveryBouncesCachesAreObservedAsTheCpuRuntimesAre) {
    const test::BakedScene& b = test::smallBake("cornell", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    auto cpu = createCpuRuntime(b.scene, *b.rays, b.bake, BounceParams{3});
    ASSERT_TRUE(cpu);
    auto gpu3 = test::gpuFor(b, {3});
    ASSERT_TRUE(gpu3);
    struct Seen {
        std::vector<int> bounces;
        std::vector<bool> last;
        std::vector<CacheValues> caches;
    };
    const auto observer = [](Seen& seen) {
        return [&seen](int bounce, const CacheValues& caches, bool last) {
            seen.bounces.push_back(bounce);
            seen.last.push_back(last);
            seen.caches.push_back(caches);
        };
    };
    const LightSet lights = defaultLightSet(b.scene);
    Seen onCpu, onGpu;
    auto cpuValues = (*cpu)->setLights(lights, nullptr, observer(onCpu));
    ASSERT_TRUE(cpuValues) << cpuValues.error().message;
    auto gpuValues = gpu3->setLights(lights, nullptr, observer(onGpu));
    ASSERT_TRUE(gpuValues) << gpuValues.error().message;
    for (const Seen* seen : {&onCpu, &onGpu}) {
        EXPECT_EQ(seen->bounces, (std::vector<int>{1, 2, 3}));
        EXPECT_EQ(seen->last, (std::vector<bool>{false, false, true}));
    }
    ASSERT_EQ(onGpu.caches.size(), 3u);
    for (size_t i = 0; i < 3; ++i)
        EXPECT_LE(test::relativeL2(onGpu.caches[i], onCpu.caches[i]), 0.01) << "bounce " << i + 1;
    // Without a sky the last bounce's caches are the result; each bounce adds light.
    EXPECT_EQ(onCpu.caches.back().y, (*cpuValues)->y);
    EXPECT_EQ(onGpu.caches.back().y, (*gpuValues)->y);
    const auto luma = [](const CacheValues& values) {
        double sum = 0.0;
        for (const float v : values.y) sum += v;
        return sum;
    };
    EXPECT_LT(luma(onCpu.caches[0]), luma(onCpu.caches[1]));
    EXPECT_LT(luma(onCpu.caches[1]), luma(onCpu.caches[2]));
}

/// "ShadowMaps" or "Rays", for test names.
std::string visibilityName(gpu::DirectVisibility visibility) {
    return visibility == gpu::DirectVisibility::Rays ? "Rays" : "ShadowMaps";
}

INSTANTIATE_TEST_SUITE_P(LinkFormsAndVisibility, GpuRuntimeForms,
                         testing::Combine(testing::Values(LinkMode::Rtp, LinkMode::Sh),
                                          testing::Values(gpu::DirectVisibility::ShadowMaps,
                                                          gpu::DirectVisibility::Rays)),
                         [](const auto& info) {
                             return std::string(std::get<0>(info.param) == LinkMode::Rtp ? "Rtp"
                                                                                         : "Sh") +
                                    visibilityName(std::get<1>(info.param));
                         });

TEST(GpuRuntime, DirectVisibilityIsRaysOnACpuDeviceAndShadowMapsOnAGpu) {
    const test::BakedScene& b = test::smallBake("cornell", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    auto gpu = test::gpuFor(b);
    ASSERT_TRUE(gpu);
    EXPECT_EQ(gpu->directVisibility(), gpu->context().isCpuDevice()
                                           ? gpu::DirectVisibility::Rays
                                           : gpu::DirectVisibility::ShadowMaps);
    EXPECT_EQ(*gpu::parseDirectVisibility("rays"), gpu::DirectVisibility::Rays);
    EXPECT_EQ(*gpu::parseDirectVisibility("shadow-maps"), gpu::DirectVisibility::ShadowMaps);
    EXPECT_EQ(*gpu::parseDirectVisibility("auto"), std::nullopt);
    auto bad = gpu::parseDirectVisibility("raytraced");
    ASSERT_FALSE(bad);
    EXPECT_EQ(bad.error().code, ErrorCode::InvalidInput);
    EXPECT_NE(bad.error().message.find("raytraced"), std::string::npos);
}

TEST(GpuRuntime, ZeroBouncesLeaveCachesAndTexturesDark) {
    const test::BakedScene& b = test::smallBake("cornell", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    auto lit = test::gpuFor(b, BounceParams{1});
    ASSERT_TRUE(lit);
    ASSERT_TRUE(lit->setLights(defaultLightSet(b.scene), nullptr));
    auto dark = test::gpuFor(b, BounceParams{0});
    ASSERT_TRUE(dark);
    auto values = dark->setLights(defaultLightSet(b.scene), nullptr);
    ASSERT_TRUE(values) << values.error().message;
    for (float v : (*values)->y) ASSERT_EQ(v, 0.0f);
    auto textures = dark->textures();
    ASSERT_TRUE(textures) << textures.error().message;
    for (int ch = 0; ch < 3; ++ch)
        for (float v : (*textures)->lightmap[ch]) ASSERT_EQ(v, 0.0f);
}

// A discrete GPU's device memory is not mapped: uploads, downloads and the caches' read-back
// go through host-visible buffers. Lavapipe could map it; left unmapped, it takes those paths
// and must give the same caches and textures, bit for bit (the same shaders on the same data).
class GpuRuntimeMemory : public testing::TestWithParam<gpu::DirectVisibility> {};

TEST_P(GpuRuntimeMemory, UnmappedDeviceMemoryGivesTheSameResults) {
    const test::BakedScene& b = test::smallBake("cornell", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    auto mapped = test::gpuFor(b, {}, {.directVisibility = GetParam()});
    auto unmapped = test::gpuFor(b, {}, {.directVisibility = GetParam(), .mapDeviceMemory = false});
    ASSERT_TRUE(mapped && unmapped);
    LightSet lights = defaultLightSet(b.scene);
    for (int update = 0; update < 3; ++update) {
        auto expected = mapped->setLights(lights, nullptr);
        auto actual = unmapped->setLights(lights, nullptr);
        ASSERT_TRUE(expected && actual);
        EXPECT_EQ((*actual)->y, (*expected)->y);
        EXPECT_EQ((*actual)->co, (*expected)->co);
        EXPECT_EQ((*actual)->cg, (*expected)->cg);
        auto expectedTextures = mapped->textures();
        auto actualTextures = unmapped->textures();
        ASSERT_TRUE(expectedTextures && actualTextures);
        for (int ch = 0; ch < 3; ++ch) {
            EXPECT_EQ((*actualTextures)->grid[ch], (*expectedTextures)->grid[ch]);
            EXPECT_EQ((*actualTextures)->lightmap[ch], (*expectedTextures)->lightmap[ch]);
        }
        // A recolour, then a move.
        if (update == 0) lights.lights[0].intensity *= 0.5f;
        if (update == 1) lights.lights[0].position.y -= 0.1f;
    }
    // The single-pass path reads the caches back the same way.
    std::vector<glm::vec3> nodes(b.bake.nodes.size(), glm::vec3(0.25f, 0.5f, 1.0f));
    auto expected = mapped->runCacheLighting(nodes);
    auto actual = unmapped->runCacheLighting(nodes);
    ASSERT_TRUE(expected && actual);
    EXPECT_EQ(actual->y, expected->y);
    EXPECT_GT(*std::max_element(actual->y.begin(), actual->y.end()), 0.0f);
    EXPECT_EQ(unmapped->context().validationMessages(), 0u);
}

INSTANTIATE_TEST_SUITE_P(Visibility, GpuRuntimeMemory,
                         testing::Values(gpu::DirectVisibility::ShadowMaps,
                                         gpu::DirectVisibility::Rays),
                         [](const auto& info) { return visibilityName(info.param); });

// The light-map copy on the host (the default on a CPU device) and on the device give the
// same textures bit for bit: both copy the same half-float caches of a progressive update,
// with the device's memory mapped or not.
class GpuRuntimeLightmapCopy : public testing::TestWithParam<bool> {};

TEST_P(GpuRuntimeLightmapCopy, HostAndDeviceCopiesGiveTheSameTextures) {
    const test::BakedScene& b = test::smallBake("cornell", LinkMode::Sh);
    ASSERT_TRUE(b.ok);
    const bool mapped = GetParam();
    auto host = test::gpuFor(b, {}, {.mapDeviceMemory = mapped, .lightmapCopyOnHost = true});
    auto device = test::gpuFor(b, {}, {.mapDeviceMemory = mapped, .lightmapCopyOnHost = false});
    ASSERT_TRUE(host && device);
    EXPECT_TRUE(host->lightmapCopyOnHost());
    EXPECT_FALSE(device->lightmapCopyOnHost());
    LightSet lights = defaultLightSet(b.scene);
    for (int update = 0; update < 2; ++update) {
        UpdateStats hostStats, deviceStats;
        auto expected = device->setLights(lights, &deviceStats);
        auto actual = host->setLights(lights, &hostStats);
        ASSERT_TRUE(expected && actual);
        EXPECT_GT(hostStats.bounces, 1);
        EXPECT_EQ(hostStats.bounces, deviceStats.bounces);
        EXPECT_EQ((*actual)->y, (*expected)->y);
        // The copy runs on demand in textures(), from what setLights returned, even when a
        // single pass has reused the cache buffers in between.
        EXPECT_FALSE(hostStats.passMs.contains("lightmap_copy"));
        EXPECT_FALSE(deviceStats.passMs.contains("lightmap_copy"));
        if (update == 1) {
            ASSERT_TRUE(device->runCacheLighting(std::vector<glm::uvec4>(b.bake.nodes.size(), glm::uvec4(0u))));
        }
        auto expectedTextures = device->textures();
        auto actualTextures = host->textures();
        ASSERT_TRUE(expectedTextures && actualTextures);
        for (int ch = 0; ch < 3; ++ch) {
            EXPECT_EQ((*actualTextures)->grid[ch], (*expectedTextures)->grid[ch]);
            EXPECT_EQ((*actualTextures)->lightmap[ch], (*expectedTextures)->lightmap[ch]);
        }
        EXPECT_GT(*std::max_element((*actualTextures)->lightmap[0].begin(),
                                    (*actualTextures)->lightmap[0].end()),
                  0.0f);
        lights.lights[0].position.y -= 0.1f;
    }
    EXPECT_EQ(host->context().validationMessages(), 0u);
    EXPECT_EQ(device->context().validationMessages(), 0u);
}

INSTANTIATE_TEST_SUITE_P(Memory, GpuRuntimeLightmapCopy, testing::Bool(),
                         [](const auto& info) { return info.param ? "Mapped" : "Unmapped"; });

TEST(GpuRuntime, LightmapCopyIsOnTheHostOnACpuDeviceByDefault) {
    const test::BakedScene& b = test::smallBake("cornell", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    auto gpu = test::gpuFor(b);
    ASSERT_TRUE(gpu);
    EXPECT_EQ(gpu->lightmapCopyOnHost(), gpu->context().isCpuDevice());
}

TEST(GpuRuntime, SkyMatchesTheCpuRuntime) {
    // The Cornell box opens towards +Z: a sky with a bright patch, turned so that the patch
    // looks in, lights it through the surfels' transfer and the caches' visibility. Both
    // backends with a point light too, with every bounce count: none (the caches hold the sky
    // alone) and progressive.
    const test::BakedScene& b = test::smallBake("cornell", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    ASSERT_FALSE(b.bake.cacheSky.empty());
    const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                      ("pic_gpu_sky_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    Image image(32, 16);
    for (glm::vec3& texel : image.pixels) texel = glm::vec3(0.3f, 0.4f, 0.6f);
    for (uint32_t x = 14; x < 18; ++x)
        for (uint32_t y = 5; y < 8; ++y) image.at(x, y) = glm::vec3(30.0f, 24.0f, 16.0f);
    ASSERT_TRUE(writeImage((dir / "patch.exr").string(), image));
    Scene scene = b.scene;
    scene.sourcePath = (dir / "cornell.gltf").string();

    LightSet lights = defaultLightSet(b.scene);
    lights.sky = SkyLight{.color = {1.0f, 0.9f, 0.8f}, .intensity = 2.0f,
                          .environment = "patch.exr", .rotationDegrees = 20.0f};
    for (const BounceParams bounces : {BounceParams{.bounces = 0}, BounceParams{}}) {
        auto gpu = GpuRuntime::create(scene, *b.rays, b.bake, bounces, {});
        ASSERT_TRUE(gpu) << gpu.error().message;
        auto cpu = createCpuRuntime(scene, *b.rays, b.bake, bounces);
        ASSERT_TRUE(cpu);
        UpdateStats gpuStats, cpuStats;
        auto cpuValues = (*cpu)->setLights(lights, &cpuStats);
        ASSERT_TRUE(cpuValues) << cpuValues.error().message;
        auto gpuValues = (*gpu)->setLights(lights, &gpuStats);
        ASSERT_TRUE(gpuValues) << gpuValues.error().message;
        EXPECT_EQ(gpuStats.bounces, cpuStats.bounces);
        EXPECT_TRUE(gpuStats.passMs.contains("sky_caches"));
        EXPECT_LE(test::relativeL2(**gpuValues, **cpuValues), 0.01) << bounces.bounces;
        // The sky is there: without it the caches differ by far more.
        LightSet noSky = lights;
        noSky.sky.reset();
        auto darker = (*cpu)->setLights(noSky, nullptr);
        ASSERT_TRUE(darker);
        EXPECT_GT(test::relativeL2(**darker, **gpuValues), 0.1) << bounces.bounces;
        EXPECT_EQ((*gpu)->context().validationMessages(), 0u);
    }
    std::filesystem::remove_all(dir);
}

TEST(GpuRuntime, RefusesInvalidLights) {
    const test::BakedScene& b = test::smallBake("cornell", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    auto gpu = test::gpuFor(b);
    ASSERT_TRUE(gpu);
    LightSet lights = defaultLightSet(b.scene);
    ASSERT_FALSE(lights.lights.empty());
    lights.lights[0].intensity = std::nanf("");
    auto values = gpu->setLights(lights, nullptr);
    ASSERT_FALSE(values);
    EXPECT_EQ(values.error().code, ErrorCode::InvalidInput);
}

}  // namespace
}  // namespace pic
