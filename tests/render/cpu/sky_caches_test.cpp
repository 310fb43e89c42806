// The sky in the CPU runtime (render/cpu/sky_caches.h, the sky term of surfel lighting): the
// analytic furnace of an open plane under a constant sky, a closed box that sees none of it,
// relighting a rotated or brighter sky without a re-bake, and bakes without sky transfer.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <unistd.h>

#include "core/color.h"
#include "core/image.h"
#include "core/light_set.h"
#include "core/sh.h"
#include "core/sky.h"
#include "render/cpu/surfel_lighting.h"
#include "render/cpu_runtime.h"
#include "tests/support/baked_scene.h"

namespace pic {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

const test::BakedScene& baked(const std::string& name, uint32_t skyRays = 256) {
    BakeOptions options = test::smallBakeOptions(2048, 32);
    options.skyRays = skyRays;
    return test::bakedScene(name, options, 0.12f, 0.06f);
}

LightSet skyOnly(glm::vec3 color, float intensity, std::string environment = {},
                 float rotation = 0.0f) {
    LightSet lights;
    lights.sky = SkyLight{.color = color,
                          .intensity = intensity,
                          .environment = std::move(environment),
                          .rotationDegrees = rotation};
    return lights;
}

/// RGB irradiance that cache c's SH delivers to a surface of unit normal n.
glm::vec3 cacheIrradiance(const CacheValues& values, size_t c, const glm::vec3& n) {
    const size_t nY = size_t(values.bandsY) * values.bandsY;
    const size_t nC = size_t(values.bandsC) * values.bandsC;
    const glm::vec3 ycocg(shIrradiance(int(values.bandsY), &values.y[c * nY], n),
                          shIrradiance(int(values.bandsC), &values.co[c * nC], n),
                          shIrradiance(int(values.bandsC), &values.cg[c * nC], n));
    return yCoCgToRgb(ycocg);
}

void expectVecNear(const glm::vec3& a, const glm::vec3& b, float relative, const char* what) {
    for (int k = 0; k < 3; ++k)
        EXPECT_NEAR(a[k], b[k], relative * std::abs(b[k]) + 1e-6f) << what << " channel " << k;
}

TEST(SkyFurnace, AnOpenPlaneReceivesPiLAndReflectsAlbedoTimesL) {
    // Under a constant sky L the floor's surfels receive E = π·L and leave B = ρ·L; a light-map
    // cache on it sees the sky over its hemisphere, whose irradiance through any lY ≥ 2 bands
    // is exactly π·L (the clamped cosine has no odd bands above 1, the hemisphere no even
    // ones above 0). A grid cache just above the middle of the floor sees the sky above and
    // the floor's ρ·L below: π·L facing up and about π·ρ·L facing down.
    const test::BakedScene& b = baked("open_plane");
    ASSERT_TRUE(b.ok);
    const glm::vec3 sky(2.0f, 1.0f, 0.5f);
    const LightSet lights = skyOnly(sky / 2.0f, 2.0f);

    std::vector<glm::vec3> flux(b.bake.surfels.size());
    const auto skySh = resolveSky(*lights.sky, b.scene.sourcePath)->project();
    directSurfelFlux(b.scene, *b.rays, b.bake, lights, flux, &skySh);
    for (size_t i = 0; i < flux.size(); ++i) {
        const Surfel& s = b.bake.surfels[i];
        expectVecNear(flux[i], s.albedo * s.area * kPi * sky, 0.01f, "surfel flux");
        if (HasFailure()) break;
    }

    auto runtime = createCpuRuntime(b.scene, *b.rays, b.bake, BounceParams{});
    ASSERT_TRUE(runtime) << runtime.error().message;
    UpdateStats stats;
    auto values = (*runtime)->setLights(lights, &stats);
    ASSERT_TRUE(values) << values.error().message;
    EXPECT_TRUE(stats.passMs.contains("sky_caches"));
    const glm::vec3 albedo = b.bake.surfels[0].albedo;
    int lightmapCaches = 0, gridCaches = 0;
    for (size_t c = 0; c < b.bake.caches.size(); ++c) {
        const Cache& cache = b.bake.caches[c];
        if (cache.kind == gpu::kCacheKindLightmap) {
            ++lightmapCaches;
            expectVecNear(cacheIrradiance(**values, c, cache.normal), kPi * sky, 0.03f,
                          "light-map cache");
        } else if (std::abs(cache.position.x) < 0.6f && std::abs(cache.position.z) < 0.6f &&
                   cache.position.y > 0.05f && cache.position.y < 0.4f) {
            ++gridCaches;
            expectVecNear(cacheIrradiance(**values, c, {0, 1, 0}), kPi * sky, 0.05f,
                          "grid cache facing up");
            expectVecNear(cacheIrradiance(**values, c, {0, -1, 0}), kPi * albedo * sky, 0.12f,
                          "grid cache facing down");
        }
        if (HasFailure()) break;
    }
    EXPECT_GT(lightmapCaches, 10);
    EXPECT_GT(gridCaches, 0);
}

TEST(SkyFurnace, AClosedBoxSeesNoSky) {
    const test::BakedScene& b = baked("closed_box");
    ASSERT_TRUE(b.ok);
    auto runtime = createCpuRuntime(b.scene, *b.rays, b.bake, BounceParams{});
    ASSERT_TRUE(runtime) << runtime.error().message;
    auto values = (*runtime)->setLights(skyOnly(glm::vec3(1.0f), 100.0f), nullptr);
    ASSERT_TRUE(values) << values.error().message;
    // Grid caches on the walls' planes may look out through the seams: only those inside.
    for (size_t c = 0; c < b.bake.caches.size(); ++c) {
        const glm::vec3 p = b.bake.caches[c].position;
        const bool inside = glm::all(glm::lessThan(glm::abs(p - glm::vec3(0.0f, 0.5f, 0.0f)),
                                                   glm::vec3(0.49f)));
        if (b.bake.caches[c].kind == gpu::kCacheKindGrid && !inside) continue;
        ASSERT_EQ((*values)->y[c * (*values)->bandsY * (*values)->bandsY], 0.0f) << "cache " << c;
    }
}

/// A scratch copy of a baked scene whose folder holds an environment image.
class SkyRelight : public ::testing::Test {
protected:
    void SetUp() override {
        mDir = std::filesystem::temp_directory_path() /
               ("pic_sky_relight_" + std::to_string(::getpid()));
        std::filesystem::create_directories(mDir);
        // A dim sky with a bright patch towards the image's +X column, high up.
        Image image(32, 16);
        for (glm::vec3& texel : image.pixels) texel = glm::vec3(0.2f);
        for (uint32_t x = 6; x < 10; ++x)
            for (uint32_t y = 3; y < 6; ++y) image.at(x, y) = glm::vec3(20.0f, 15.0f, 10.0f);
        ASSERT_TRUE(writeImage((mDir / "patch.exr").string(), image));
    }
    void TearDown() override { std::filesystem::remove_all(mDir); }
    std::filesystem::path mDir;
};

TEST_F(SkyRelight, RotatingOrBrighteningTheSkyNeedsNoRebake) {
    const test::BakedScene& b = baked("cornell");
    ASSERT_TRUE(b.ok);
    Scene scene = b.scene;
    scene.sourcePath = (mDir / "cornell.gltf").string();
    auto make = [&] {
        auto runtime = createCpuRuntime(scene, *b.rays, b.bake, BounceParams{.bounces = 2});
        EXPECT_TRUE(runtime) << runtime.error().message;
        return std::move(*runtime);
    };
    auto runtime = make();
    auto first = runtime->setLights(skyOnly(glm::vec3(1.0f), 1.0f, "patch.exr", 0.0f), nullptr);
    ASSERT_TRUE(first) << first.error().message;
    const CacheValues unturned = **first;
    auto turned = runtime->setLights(skyOnly(glm::vec3(1.0f), 1.0f, "patch.exr", 90.0f), nullptr);
    ASSERT_TRUE(turned) << turned.error().message;
    const CacheValues quarter = **turned;
    // The box opens towards +Z: the patch, turned from +X to −Z, lights it differently.
    EXPECT_NE(quarter.y, unturned.y);
    // A runtime that saw only the turned sky gives the same caches, bit for bit.
    auto other = make();
    auto fresh = other->setLights(skyOnly(glm::vec3(1.0f), 1.0f, "patch.exr", 90.0f), nullptr);
    ASSERT_TRUE(fresh);
    EXPECT_EQ((*fresh)->y, quarter.y);
    EXPECT_EQ((*fresh)->co, quarter.co);
    // Turned back, the first caches again; three times as bright, three times the light.
    auto back = runtime->setLights(skyOnly(glm::vec3(1.0f), 1.0f, "patch.exr", 0.0f), nullptr);
    ASSERT_TRUE(back);
    EXPECT_EQ((*back)->y, unturned.y);
    auto bright = runtime->setLights(skyOnly(glm::vec3(1.0f), 3.0f, "patch.exr", 0.0f), nullptr);
    ASSERT_TRUE(bright);
    double maxY = 0.0;
    for (float v : unturned.y) maxY = std::max(maxY, double(std::abs(v)));
    ASSERT_GT(maxY, 0.0);
    for (size_t i = 0; i < unturned.y.size(); ++i)
        ASSERT_NEAR((*bright)->y[i], 3.0f * unturned.y[i], 1e-5 * maxY) << "coefficient " << i;
}

TEST_F(SkyRelight, RefusesASkyTheBakeCannotLightAndAMissingEnvironment) {
    const test::BakedScene& noSky = baked("cornell", 0);
    ASSERT_TRUE(noSky.ok);
    EXPECT_TRUE(noSky.bake.surfelSky.empty());
    auto runtime = createCpuRuntime(noSky.scene, *noSky.rays, noSky.bake, BounceParams{});
    ASSERT_TRUE(runtime);
    auto refused = (*runtime)->setLights(skyOnly(glm::vec3(1.0f), 1.0f), nullptr);
    ASSERT_FALSE(refused);
    EXPECT_EQ(refused.error().code, ErrorCode::InvalidInput);
    EXPECT_NE(refused.error().message.find("--sky-rays"), std::string::npos)
        << refused.error().message;
    // Without a sky the same runtime lights as before.
    EXPECT_TRUE((*runtime)->setLights(defaultLightSet(noSky.scene), nullptr));

    const test::BakedScene& b = baked("cornell");
    Scene scene = b.scene;
    scene.sourcePath = (mDir / "cornell.gltf").string();
    auto withSky = createCpuRuntime(scene, *b.rays, b.bake, BounceParams{});
    ASSERT_TRUE(withSky);
    auto missing = (*withSky)->setLights(skyOnly(glm::vec3(1.0f), 1.0f, "absent.hdr"), nullptr);
    ASSERT_FALSE(missing);
    EXPECT_EQ(missing.error().code, ErrorCode::NotFound);
    EXPECT_NE(missing.error().message.find("absent.hdr"), std::string::npos);
}

}  // namespace
}  // namespace pic
