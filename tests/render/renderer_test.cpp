// The thin client's headless Renderer as a whole on lavapipe (or whatever Vulkan device the
// machine has): the full image is emission + direct + indirect, ringing caches give no NaN,
// Inf or negative pixels, bad inputs are refused as InvalidInput, and it resizes between
// frames and takes each cache version. Its passes alone: tests/render/passes/.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/image.h"
#include "core/light_set.h"
#include "render/renderer.h"
#include "tests/render/renderer_fixture.h"

namespace pic {
namespace {

TEST(RendererFull, IsEmissionPlusDirectPlusIndirect) {
    const test::LitScene& b = test::litScene("cornell");
    ASSERT_TRUE(b.ok);
    auto renderer = test::rendererFor(b.scene, b.bake, b.values);
    ASSERT_TRUE(renderer);
    const LightSet lights = defaultLightSet(b.scene);
    const Camera& camera = b.scene.cameras.at(0);
    ShadeParams params;
    params.width = 64;
    params.height = 64;
    Image parts[3];
    const ShadeComponent components[3] = {ShadeComponent::Full, ShadeComponent::Direct,
                                          ShadeComponent::Indirect};
    for (int k = 0; k < 3; ++k) {
        params.component = components[k];
        RenderTimings timings;
        auto image = renderer->render(lights, camera, params, &timings);
        ASSERT_TRUE(image) << image.error().message;
        parts[k] = std::move(*image);
        EXPECT_GT(timings.totalMs, 0.0);
        EXPECT_FALSE(timings.passMs.empty());
        std::string passes;
        for (const auto& [pass, ms] : timings.passMs)
            passes += " " + pass + " " + std::to_string(ms);
        const char* names[3] = {"full", "direct", "indirect"};
        std::printf("[ measured ] %s 64x64: %.2f ms wall; GPU ms:%s\n", names[k], timings.totalMs,
                    passes.c_str());
        test::expectFiniteNonNegative(parts[k], "component");
    }
    // The cornell box has no emitters: full = direct + indirect per pixel.
    for (size_t i = 0; i < parts[0].pixels.size(); ++i)
        for (int c = 0; c < 3; ++c)
            ASSERT_NEAR(parts[0].pixels[i][c], parts[1].pixels[i][c] + parts[2].pixels[i][c],
                        1e-5f * (1.0f + parts[0].pixels[i][c]))
                << "pixel " << i;

    // `picclient render --out` writes the image with core/image.h: EXR keeps it exactly.
    const std::string path = testing::TempDir() + "renderer_test_full.exr";
    ASSERT_TRUE(writeImage(path, parts[0]));
    auto read = readImage(path);
    ASSERT_TRUE(read) << read.error().message;
    EXPECT_EQ(read->pixels, parts[0].pixels);
    std::remove(path.c_str());
}

TEST(Renderer, RingingCachesNeverGiveNegativeOrNonFinitePixels) {
    const test::LitScene& b = test::litScene("cornell");
    ASSERT_TRUE(b.ok);
    // Caches with large alternating higher-band coefficients: their irradiance rings below
    // zero on many surfaces, where both renderers clamp it.
    CacheValues values = b.values;
    for (size_t i = 0; i < values.y.size(); ++i)
        values.y[i] = (i % 9 == 0) ? 0.2f : 3.0f * std::sin(float(i));
    for (size_t i = 0; i < values.co.size(); ++i) values.co[i] = 0.5f * std::cos(float(i));
    for (size_t i = 0; i < values.cg.size(); ++i) values.cg[i] = -0.5f * std::sin(float(3 * i));
    auto renderer = test::rendererFor(b.scene, b.bake, values);
    ASSERT_TRUE(renderer);
    ShadeParams params;
    params.width = 63;
    params.height = 64;
    params.glossyExponent = 4.0f;
    params.glossyWeight = 1.0f;
    for (ShadeComponent component :
         {ShadeComponent::Full, ShadeComponent::Direct, ShadeComponent::Indirect}) {
        params.component = component;
        auto image = renderer->render(defaultLightSet(b.scene), b.scene.cameras.at(0), params);
        ASSERT_TRUE(image) << image.error().message;
        test::expectFiniteNonNegative(*image, "ringing caches");
    }
    params.component = ShadeComponent::Indirect;
    const test::Comparison c = test::compare(*renderer, b.scene, *b.rays, b.bake, values,
                                 defaultLightSet(b.scene), b.scene.cameras.at(0), params);
    test::report("indirect + glossy, ringing caches (cornell 64x64)", c);
    EXPECT_LE(c.error.relativeRmse, 0.01);
}

TEST(Renderer, RefusesBadInputsAsInvalidInput) {
    const test::LitScene& b = test::litScene("cornell");
    ASSERT_TRUE(b.ok);
    gpu::Context* gpu = test::sharedContext();
    ASSERT_TRUE(gpu);
    const ClientLayout layout = clientLayoutOf(b.bake);
    const auto expectInvalid = [](const auto& result, const char* what) {
        ASSERT_FALSE(result.has_value()) << what;
        EXPECT_EQ(result.error().code, ErrorCode::InvalidInput)
            << what << ": " << result.error().message;
    };

    // Layouts that do not fit the scene.
    ClientLayout otherScene = layout;
    otherScene.sceneHash ^= 1;
    expectInvalid(Renderer::create(*gpu, b.scene, otherScene), "other scene");
    ClientLayout fewUvs = layout;
    fewUvs.triangleUvs.pop_back();
    expectInvalid(Renderer::create(*gpu, b.scene, fewUvs), "UV count");
    ClientLayout badBands = layout;
    badBands.bandsC = badBands.bandsY + 1;
    expectInvalid(Renderer::create(*gpu, b.scene, badBands), "bands");
    ClientLayout nanUv = layout;
    nanUv.triangleUvs[4].x = std::nanf("");
    expectInvalid(Renderer::create(*gpu, b.scene, nanUv), "NaN UV");

    auto created = Renderer::create(*gpu, b.scene, layout);
    ASSERT_TRUE(created) << created.error().message;
    Renderer& renderer = **created;
    const CacheTextures good = test::texturesOf(b.bake, b.values);
    ASSERT_TRUE(renderer.setCaches(good));

    // Textures that do not match the layout.
    CacheTextures wrongBands = good;
    wrongBands.bandsY += 1;
    expectInvalid(renderer.setCaches(wrongBands), "texture bands");
    CacheTextures wrongGrid = good;
    wrongGrid.gridDims.x += 1;
    expectInvalid(renderer.setCaches(wrongGrid), "grid size");
    CacheTextures shortLayers = good;
    shortLayers.lightmap[1].pop_back();
    expectInvalid(renderer.setCaches(shortLayers), "light-map layer length");
    CacheTextures noCoverage = good;
    noCoverage.gridCoverage.clear();
    expectInvalid(renderer.setCaches(noCoverage), "grid coverage length");
    CacheTextures halfCoverage = good;
    ASSERT_FALSE(halfCoverage.lightmapCoverage.empty());
    halfCoverage.lightmapCoverage[0] = 0.5f;
    expectInvalid(renderer.setCaches(halfCoverage), "coverage value");
    CacheTextures infinite = good;
    ASSERT_FALSE(infinite.grid[0].empty());
    infinite.grid[0][0] = INFINITY;
    expectInvalid(renderer.setCaches(infinite), "infinite coefficient");

    // Parameters, cameras and lights.
    const LightSet lights = defaultLightSet(b.scene);
    const Camera& camera = b.scene.cameras.at(0);
    ShadeParams params;
    params.width = 16;
    params.height = 16;
    ShadeParams zeroWidth = params;
    zeroWidth.width = 0;
    expectInvalid(renderer.render(lights, camera, zeroWidth), "zero width");
    ShadeParams zeroHeight = params;
    zeroHeight.height = 0;
    expectInvalid(renderer.render(lights, camera, zeroHeight), "zero height");
    ShadeParams huge = params;
    huge.width = 20000;
    expectInvalid(renderer.render(lights, camera, huge), "huge width");
    ShadeParams noSubsamples = params;
    noSubsamples.samplesPerPixel = 0;
    expectInvalid(renderer.render(lights, camera, noSubsamples), "0 subsamples");
    ShadeParams tooManySubsamples = params;
    tooManySubsamples.samplesPerPixel = kMaxSamplesPerPixel + 1;
    expectInvalid(renderer.render(lights, camera, tooManySubsamples), "too many subsamples");
    ShadeParams negativeGloss = params;
    negativeGloss.glossyWeight = -1.0f;
    expectInvalid(renderer.render(lights, camera, negativeGloss), "negative glossy weight");
    Camera degenerate = camera;
    degenerate.target = degenerate.eye;
    expectInvalid(renderer.render(lights, degenerate, params), "eye = target");
    Camera wideOpen = camera;
    wideOpen.fovyDegrees = 180.0f;
    expectInvalid(renderer.render(lights, wideOpen, params), "fovy 180");
    LightSet nanLight = lights;
    ASSERT_FALSE(nanLight.lights.empty());
    nanLight.lights[0].intensity = std::nanf("");
    expectInvalid(renderer.render(nanLight, camera, params), "NaN light");
    LightSet unknownMaterial = lights;
    unknownMaterial.emissiveScale["no such material"] = 2.0f;
    expectInvalid(renderer.render(unknownMaterial, camera, params), "unknown material");

    // The refusals left the renderer working, with the good textures.
    auto image = renderer.render(lights, camera, params);
    ASSERT_TRUE(image) << image.error().message;
    EXPECT_GT(test::expectFiniteNonNegative(*image, "after refusals"), 0);
    EXPECT_EQ(gpu->validationMessages(), 0u);
}

TEST(Renderer, ResizesBetweenFramesAndTakesEachCacheVersion) {
    const test::LitScene& b = test::litScene("cornell");
    ASSERT_TRUE(b.ok);
    gpu::Context* gpu = test::sharedContext();
    ASSERT_TRUE(gpu);
    auto created = Renderer::create(*gpu, b.scene, clientLayoutOf(b.bake));
    ASSERT_TRUE(created) << created.error().message;
    Renderer& renderer = **created;
    ShadeParams params;
    params.component = ShadeComponent::Indirect;
    for (const glm::uvec2 size : {glm::uvec2(8, 8), glm::uvec2(33, 17), glm::uvec2(8, 8)}) {
        params.width = size.x;
        params.height = size.y;
        auto image = renderer.render(defaultLightSet(b.scene), b.scene.cameras.at(0), params);
        ASSERT_TRUE(image) << image.error().message;
        EXPECT_EQ(image->width, size.x);
        EXPECT_EQ(image->height, size.y);
        // No caches yet: the cache term is black.
        EXPECT_EQ(test::expectFiniteNonNegative(*image, "before caches"), 0);
    }

    // Each streamed version replaces the textures: twice the radiance, twice the image (to
    // the half-float rounding of the textures).
    params.width = 31;
    params.height = 32;
    CacheValues doubled = b.values;
    for (std::vector<float>* v : {&doubled.y, &doubled.co, &doubled.cg})
        for (float& x : *v) x *= 2.0f;
    ASSERT_TRUE(renderer.setCaches(test::texturesOf(b.bake, b.values)));
    auto once = renderer.render(defaultLightSet(b.scene), b.scene.cameras.at(0), params);
    ASSERT_TRUE(renderer.setCaches(test::texturesOf(b.bake, doubled)));
    auto twice = renderer.render(defaultLightSet(b.scene), b.scene.cameras.at(0), params);
    ASSERT_TRUE(once && twice);
    EXPECT_GT(test::expectFiniteNonNegative(*once, "first version"), 0);
    for (size_t i = 0; i < once->pixels.size(); ++i)
        for (int c = 0; c < 3; ++c)
            ASSERT_NEAR(twice->pixels[i][c], 2.0f * once->pixels[i][c],
                        2e-3f * once->pixels[i][c] + 1e-6f)
                << "pixel " << i;
    EXPECT_EQ(gpu->validationMessages(), 0u);
}

}  // namespace
}  // namespace pic
