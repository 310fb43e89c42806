// The cache-shading pass through the thin client's Renderer on lavapipe (or the machine's GPU)
// against its CPU twin, render/cpu/cache_shading.h, on the same scene, bake, caches, lights
// and camera: the cache term on light-mapped and on grid-shaded surfaces, the glossy lobe,
// direct light through shadow maps against exact shadow rays, and texture-mapped albedo.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <ostream>
#include <string>
#include <utility>

#include "core/bake_data.h"
#include "core/camera.h"
#include "core/gltf_loader.h"
#include "core/light_set.h"
#include "core/scene_objects.h"
#include "rays/embree_scene.h"
#include "render/cpu/cache_shading.h"
#include "tests/render/renderer_fixture.h"
#include "tests/support/baked_scene.h"

namespace pic {
namespace {

/// Fraction of the image's pixel centres whose primary ray hits a light-mapped triangle.
double lightmappedFraction(const test::LitScene& b, const Camera& camera, uint32_t width,
                           uint32_t height, const BakeData& bake) {
    const CameraRays rays(camera, width, height);
    int lightmapped = 0;
    for (uint32_t y = 0; y < height; ++y)
        for (uint32_t x = 0; x < width; ++x) {
            const auto hit = b.rays->intersect(
                rays.origin(), rays.direction(float(x) + 0.5f, float(y) + 0.5f), 0.0f, INFINITY);
            lightmapped += hit && bake.lightmap.triangleUvs[3 * hit->triangle].x != kNotLightmapped;
        }
    return double(lightmapped) / double(width * height);
}

/// The cornell scene camera looks straight down the box's axis: at an even image width its
/// corner edges run exactly through pixel centres, where a ray meets two walls at the same
/// depth and each renderer keeps one by its own tie-break (a flip of the whole pixel). An odd
/// width moves the image centre off the pixel grid; the oblique view has no such symmetry.
constexpr uint32_t kAxisWidth = 127;
constexpr uint32_t kAxisHeight = 112;

/// A view into the cornell box from its front right, above the short box.
Camera obliqueCornellCamera() {
    Camera camera;
    camera.name = "oblique";
    camera.eye = {0.35f, 0.75f, 1.2f};
    camera.target = {-0.1f, 0.3f, -0.2f};
    camera.fovyDegrees = 50.0f;
    return camera;
}

/// The cache term of `bake` (its own light-map UVs or grid-only ones) from the scene camera
/// and an oblique one, against the CPU twin.
void expectIndirectMatches(const test::LitScene& b, const BakeData& bake, const char* what) {
    auto renderer = test::rendererFor(b.scene, bake, b.values);
    ASSERT_TRUE(renderer);
    ShadeParams params;
    params.component = ShadeComponent::Indirect;
    const std::pair<Camera, glm::uvec2> views[] = {
        {b.scene.cameras.at(0), {kAxisWidth, kAxisHeight}}, {obliqueCornellCamera(), {128, 96}}};
    for (const auto& [camera, size] : views) {
        params.width = size.x;
        params.height = size.y;
        const test::Comparison c = test::compare(*renderer, b.scene, *b.rays, bake, b.values,
                                     defaultLightSet(b.scene), camera, params);
        const std::string label = std::string(what) + ", cornell " + camera.name + " " +
                                  std::to_string(size.x) + "x" + std::to_string(size.y);
        test::report(label.c_str(), c);
        EXPECT_LE(c.error.relativeRmse, 0.01) << label;
        EXPECT_NEAR(c.error.meanRatio, 1.0, 0.002) << label;
        EXPECT_GT(test::expectFiniteNonNegative(c.gpu, what), int(size.x * size.y) / 2) << label;
    }
    EXPECT_EQ(test::sharedContext()->validationMessages(), 0u);
}

TEST(RendererIndirect, LightMappedSurfacesMatchTheCpuShading) {
    const test::LitScene& b = test::litScene("cornell");
    ASSERT_TRUE(b.ok);
    // Most of the view reads the light map.
    EXPECT_GT(lightmappedFraction(b, b.scene.cameras.at(0), 32, 32, b.bake), 0.8);
    expectIndirectMatches(b, b.bake, "indirect, light map");
}

TEST(RendererIndirect, GridShadedSurfacesMatchTheCpuShading) {
    const test::LitScene& b = test::litScene("cornell");
    ASSERT_TRUE(b.ok);
    // The same caches, every triangle shaded from the grid.
    BakeData gridOnly = b.bake;
    for (glm::vec2& uv : gridOnly.lightmap.triangleUvs) uv = glm::vec2(kNotLightmapped);
    expectIndirectMatches(b, gridOnly, "indirect, grid");
}

TEST(RendererIndirect, GlossyLobeMatchesTheCpuShading) {
    const test::LitScene& b = test::litScene("cornell");
    ASSERT_TRUE(b.ok);
    auto renderer = test::rendererFor(b.scene, b.bake, b.values);
    ASSERT_TRUE(renderer);
    ShadeParams params;
    params.width = 95;
    params.height = 96;
    params.component = ShadeComponent::Indirect;
    params.glossyExponent = 12.0f;
    params.glossyWeight = 0.4f;
    const test::Comparison c = test::compare(*renderer, b.scene, *b.rays, b.bake, b.values,
                                 defaultLightSet(b.scene), b.scene.cameras.at(0), params);
    test::report("indirect + glossy (cornell 96x96)", c);
    EXPECT_LE(c.error.relativeRmse, 0.01);
    test::expectFiniteNonNegative(c.gpu, "glossy");

    // The lobe's part alone: the same in both twins, and what the lobe adds to the indirect.
    params.component = ShadeComponent::Glossy;
    const test::Comparison lobe = test::compare(*renderer, b.scene, *b.rays, b.bake, b.values,
                                                defaultLightSet(b.scene), b.scene.cameras.at(0),
                                                params);
    test::report("glossy lobe alone (cornell 96x96)", lobe);
    EXPECT_LE(lobe.error.relativeRmse, 0.01);
    params.component = ShadeComponent::Indirect;
    params.glossyExponent = 0.0f;
    auto diffuse = renderer->render(defaultLightSet(b.scene), b.scene.cameras.at(0), params);
    ASSERT_TRUE(diffuse) << diffuse.error().message;
    for (size_t i = 0; i < c.gpu.pixels.size(); ++i)
        for (int ch = 0; ch < 3; ++ch)
            ASSERT_NEAR(c.gpu.pixels[i][ch], diffuse->pixels[i][ch] + lobe.gpu.pixels[i][ch],
                        1e-5f * (1.0f + c.gpu.pixels[i][ch]))
                << "pixel " << i;
}

// The light set's indirect scales (paper 001 §4) act where the cache term is reconstructed,
// alike in both twins: luma and chroma apart, the glossy lobe too, and scaling both by s
// scales the cache term by s.
TEST(RendererIndirect, IndirectScalesMatchTheCpuShading) {
    const test::LitScene& b = test::litScene("cornell");
    ASSERT_TRUE(b.ok);
    auto renderer = test::rendererFor(b.scene, b.bake, b.values);
    ASSERT_TRUE(renderer);
    ShadeParams params;
    params.width = kAxisWidth;
    params.height = kAxisHeight;
    params.component = ShadeComponent::Indirect;
    params.glossyExponent = 12.0f;
    params.glossyWeight = 0.4f;
    LightSet lights = defaultLightSet(b.scene);
    auto unscaled = renderer->render(lights, b.scene.cameras.at(0), params);
    ASSERT_TRUE(unscaled) << unscaled.error().message;
    for (const IndirectScale scale : {IndirectScale{0.5f, 2.5f}, IndirectScale{1.0f, 0.0f},
                                      IndirectScale{2.0f, 2.0f}}) {
        lights.indirectScale = scale;
        const test::Comparison c = test::compare(*renderer, b.scene, *b.rays, b.bake, b.values,
                                                 lights, b.scene.cameras.at(0), params);
        const std::string label = "indirect + glossy, y " + std::to_string(scale.y) + " cocg " +
                                  std::to_string(scale.cocg);
        test::report(label.c_str(), c);
        EXPECT_LE(c.error.relativeRmse, 0.01) << label;
        EXPECT_NEAR(c.error.meanRatio, 1.0, 0.002) << label;
        if (scale.y == scale.cocg) {
            for (size_t i = 0; i < c.gpu.pixels.size(); ++i)
                for (int ch = 0; ch < 3; ++ch)
                    ASSERT_NEAR(c.gpu.pixels[i][ch], scale.y * unscaled->pixels[i][ch],
                                1e-5f * (1.0f + c.gpu.pixels[i][ch]))
                        << label << ", pixel " << i;
        }
    }
    EXPECT_EQ(test::sharedContext()->validationMessages(), 0u);
}

// A dynamic object (core/scene_objects.h) joins the view in both twins alike: its triangles
// are grid-shaded, it casts shadows and is lit through the shadow maps, as the CPU's rays do.
TEST(RendererObjects, DynamicObjectsMatchTheCpuShading) {
    const test::LitScene& b = test::litScene("cornell");
    ASSERT_TRUE(b.ok);
    ObjectPlacement box;
    box.path = test::testScenePath("object_box");
    box.translation = {0.05f, 0.55f, 0.05f};
    box.rotationDegrees = {20.0f, 35.0f, 0.0f};
    box.scale = 0.22f;
    auto placed = placeObjects(b.scene, {box});
    ASSERT_TRUE(placed) << placed.error().message;
    auto rays = EmbreeScene::create(*placed);
    ASSERT_TRUE(rays);
    BakeData bake = b.bake;
    bake.sceneHash = placed->hash;
    bake.lightmap.triangleUvs.resize(3 * placed->triangles.size(), glm::vec2(kNotLightmapped));
    auto renderer = test::rendererFor(*placed, bake, b.values);
    ASSERT_TRUE(renderer);
    ShadeParams params;
    params.width = kAxisWidth;
    params.height = kAxisHeight;
    for (const ShadeComponent component : {ShadeComponent::Indirect, ShadeComponent::Full}) {
        params.component = component;
        const test::Comparison c = test::compare(*renderer, *placed, **rays, bake, b.values,
                                                 defaultLightSet(*placed),
                                                 b.scene.cameras.at(0), params);
        const std::string label = std::string(component == ShadeComponent::Full ? "full" : "indirect") +
                                  ", cornell with a box placed in it";
        test::report(label.c_str(), c);
        // As without objects: the cache term to float precision, direct light up to the
        // shadow maps' edges (RendererDirect).
        EXPECT_LE(c.error.relativeRmse, component == ShadeComponent::Full ? 0.06 : 0.01) << label;
        EXPECT_LE(c.differing, 0.01) << label;
    }
    // The object is in the image: it differs from the scene without it.
    auto without = test::rendererFor(b.scene, b.bake, b.values);
    ASSERT_TRUE(without);
    auto plain = without->render(defaultLightSet(b.scene), b.scene.cameras.at(0), params);
    auto with = renderer->render(defaultLightSet(*placed), b.scene.cameras.at(0), params);
    ASSERT_TRUE(plain && with);
    size_t changed = 0;
    for (size_t i = 0; i < plain->pixels.size(); ++i)
        changed += glm::any(glm::greaterThan(glm::abs(plain->pixels[i] - with->pixels[i]),
                                             glm::vec3(1e-3f)));
    EXPECT_GT(changed, plain->pixels.size() / 50);
    EXPECT_EQ(test::sharedContext()->validationMessages(), 0u);
}

/// A scene, a view and a component whose direct part is compared with the CPU's exact rays.
struct DirectCase {
    const char* name;  ///< test-name suffix
    const char* scene;
    bool oblique;  ///< the oblique cornell view instead of the scene camera
    ShadeComponent component;
    bool extraLights;  ///< add a narrow spot, a wide spot and a directional light
};

/// gtest and ctest name a case by its name rather than its bytes.
void PrintTo(const DirectCase& c, std::ostream* os) {
    *os << c.name;
}

class RendererDirect : public testing::TestWithParam<DirectCase> {};

TEST_P(RendererDirect, ShadowMapsMatchTheCpuShadowRaysUpToShadowEdges) {
    const DirectCase& param = GetParam();
    const test::LitScene& b = test::litScene(param.scene);
    ASSERT_TRUE(b.ok);
    auto renderer = test::rendererFor(b.scene, b.bake, b.values);
    ASSERT_TRUE(renderer);
    LightSet lights = defaultLightSet(b.scene);
    if (param.extraLights) {
        // One light of every shadow-map kind: cube (wide spot), perspective (narrow spot),
        // orthographic (directional); the caches stay those of the scene's own lights.
        const glm::vec3 c = b.scene.bounds.center();
        Light narrow;
        narrow.id = "narrow";
        narrow.type = LightType::Spot;
        narrow.position = c + glm::vec3(0.1f, 0.35f, 0.2f);
        narrow.direction = glm::normalize(glm::vec3(-0.2f, -1.0f, -0.1f));
        narrow.outerConeAngle = 0.5f;
        narrow.innerConeAngle = 0.3f;
        narrow.intensity = 0.5f;
        Light wide = narrow;
        wide.id = "wide";
        wide.position = c + glm::vec3(-0.2f, 0.3f, 0.25f);
        wide.outerConeAngle = 1.3f;
        wide.innerConeAngle = 1.3f;
        Light sun;
        sun.id = "sun";
        sun.type = LightType::Directional;
        sun.direction = glm::normalize(glm::vec3(0.3f, -1.0f, -0.4f));
        sun.intensity = 0.3f;
        lights.lights.insert(lights.lights.end(), {narrow, wide, sun});
    }
    ShadeParams params;
    params.width = param.oblique ? 128 : kAxisWidth;
    params.height = param.oblique ? 96 : kAxisHeight;
    params.component = param.component;
    const Camera camera = param.oblique ? obliqueCornellCamera() : b.scene.cameras.at(0);
    const test::Comparison c =
        test::compare(*renderer, b.scene, *b.rays, b.bake, b.values, lights, camera, params);
    const std::string label =
        std::string(param.component == ShadeComponent::Full ? "full" : "direct") + ", " +
        param.scene + (param.oblique ? " oblique" : "") +
        (param.extraLights ? " + spots + sun" : "") + " " + std::to_string(params.width) + "x" +
        std::to_string(params.height);
    test::report(label.c_str(), c);
    // Where nothing casts a shadow the two agree to float precision. Shadow maps (1024² per
    // layer, a texel a few millimetres wide here against pixels of about a centimetre) move a
    // shadow boundary by up to a texel plus the normal offset and slope bias, so the pixels
    // whose centres fall in that band flip between lit and shadowed, each by its whole direct
    // value: measured, well under 1 % of the pixels, a relative RMSE of 1–4 % and the mean
    // within 0.5 %. The bounds leave room for other devices' rasterisation of the maps.
    EXPECT_LE(c.differing, 0.01) << label;
    EXPECT_LE(c.error.relativeRmse, 0.06) << label;
    EXPECT_NEAR(c.error.meanRatio, 1.0, 0.01) << label;
    // Some light reaches the view (small_spot lights only the spot's disc on the floor).
    EXPECT_GT(test::expectFiniteNonNegative(c.gpu, label.c_str()), 100);
    EXPECT_EQ(test::sharedContext()->validationMessages(), 0u);
}

INSTANTIATE_TEST_SUITE_P(
    ScenesAndLights, RendererDirect,
    testing::Values(
        DirectCase{"CornellPoint", "cornell", false, ShadeComponent::Direct, false},
        DirectCase{"CornellPointOblique", "cornell", true, ShadeComponent::Direct, false},
        DirectCase{"CornellEveryLightType", "cornell", true, ShadeComponent::Direct, true},
        DirectCase{"SmallSpot", "small_spot", false, ShadeComponent::Direct, false},
        DirectCase{"CornellAreaFullWithEmission", "cornell_area", false, ShadeComponent::Full,
                   false},
        DirectCase{"CornellFullEveryLightType", "cornell", true, ShadeComponent::Full, true}),
    [](const testing::TestParamInfo<DirectCase>& info) { return std::string(info.param.name); });

TEST(RendererAlbedo, TexturesMatchTheScene) {
    // The textured quad (checkerboard through TEXCOORD_0 on the floor, TEXCOORD_1 on the
    // wall) under its lamp: nothing casts a shadow on what the camera sees, so the direct
    // term is the albedo times the same irradiance on both sides.
    auto loaded = loadScene(test::testScenePath("textured_quad"));
    ASSERT_TRUE(loaded) << loaded.error().message;
    const Scene scene = std::move(*loaded);
    ASSERT_FALSE(scene.textures.empty());
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays);
    // No caches: the grid and light map are empty, every surface grid-shaded.
    BakeData bake;
    bake.sceneHash = scene.hash;
    bake.params.bandsY = 3;
    bake.params.bandsC = 2;
    bake.lightmap.triangleUvs.assign(3 * scene.triangles.size(), glm::vec2(kNotLightmapped));
    const CacheValues values = CacheValues::zeros(0, 3, 2);
    auto renderer = test::rendererFor(scene, bake, values);
    ASSERT_TRUE(renderer);
    // The scene camera (texels magnified) and one just above the floor, where footprints
    // stretch over many texels and both twins filter them (mip-mapped, anisotropic).
    Camera grazing;
    grazing.eye = {0.0f, 0.06f, 0.9f};
    grazing.target = {0.0f, 0.02f, -0.5f};
    grazing.fovyDegrees = 50.0f;
    const std::pair<Camera, const char*> views[] = {{scene.cameras.at(0), "scene camera"},
                                                    {grazing, "grazing"}};
    for (const auto& [camera, name] : views) {
        ShadeParams params;
        params.width = 96;
        params.height = 96;
        params.component = ShadeComponent::Full;
        // Pixel centres, and 4 subsamples whose footprints are half the pixel's sides.
        for (const uint32_t n : {1u, 4u}) {
            params.samplesPerPixel = n;
            const test::Comparison c = test::compare(*renderer, scene, **rays, bake, values,
                                                     defaultLightSet(scene), camera, params);
            const std::string label = std::string("full, textured quad, no caches (96x96), ") +
                                      name + ", " + std::to_string(n) + " subsamples";
            test::report(label.c_str(), c);
            // At pixel centres the two agree to float precision. Subsamples read finer mip
            // levels, where the checkerboard's squares have sharp edges: a point a rounding
            // error away on the other side of one changes a pixel's albedo (measured: 2 of
            // 9216 pixels off by more than 5 % of the mean, relative RMSE 0.0066, grazing).
            EXPECT_LE(c.error.relativeRmse, n == 1 ? 0.002 : 0.01) << label;
            EXPECT_LE(c.differing, 0.002) << label;
            EXPECT_GT(test::expectFiniteNonNegative(c.gpu, "textured"),
                      int(params.width * params.height) / 4)
                << label;
        }
    }
}

// Subsamples average the same fixed points of each pixel in both twins, so the anti-aliased
// client image is `picref shade --spp N`'s at the same N: the emitter's edge, the walls'
// silhouettes and the cache term agree as they do at pixel centres; shadow maps still move
// shadow edges by up to a texel, now averaged over the subsamples.
TEST(RendererSubsamples, MatchTheCpuShadingAtTheSameCount) {
    const test::LitScene& b = test::litScene("cornell_area");
    ASSERT_TRUE(b.ok);
    auto renderer = test::rendererFor(b.scene, b.bake, b.values);
    ASSERT_TRUE(renderer);
    ShadeParams params;
    params.width = kAxisWidth;
    params.height = kAxisHeight;
    for (const ShadeComponent component : {ShadeComponent::Indirect, ShadeComponent::Full}) {
        params.component = component;
        for (const uint32_t n : {4u, 9u}) {
            params.samplesPerPixel = n;
            const test::Comparison c = test::compare(*renderer, b.scene, *b.rays, b.bake,
                                                     b.values, defaultLightSet(b.scene),
                                                     b.scene.cameras.at(0), params);
            const std::string label =
                std::string(component == ShadeComponent::Full ? "full" : "indirect") +
                ", cornell_area " + std::to_string(params.width) + "x" +
                std::to_string(params.height) + ", " + std::to_string(n) + " subsamples";
            test::report(label.c_str(), c);
            if (component == ShadeComponent::Indirect) {
                EXPECT_LE(c.error.relativeRmse, 0.01) << label;
                EXPECT_NEAR(c.error.meanRatio, 1.0, 0.002) << label;
            } else {
                EXPECT_LE(c.error.relativeRmse, 0.04) << label;
                EXPECT_NEAR(c.error.meanRatio, 1.0, 0.01) << label;
            }
            EXPECT_LE(c.differing, 0.01) << label;
        }
    }
    EXPECT_EQ(test::sharedContext()->validationMessages(), 0u);
}

// What subsamples are for: at pixel centres the emitter's edge is a staircase, each pixel all
// emitter or all ceiling. Against the CPU shading's 64-subsample image of the same caches,
// the client's error falls as its subsamples grow, most of it where the emitter meets the
// ceiling.
TEST(RendererSubsamples, ConvergeToTheFilteredImage) {
    const test::LitScene& b = test::litScene("cornell_area");
    ASSERT_TRUE(b.ok);
    auto renderer = test::rendererFor(b.scene, b.bake, b.values);
    ASSERT_TRUE(renderer);
    ShadeParams params;
    params.width = kAxisWidth;
    params.height = kAxisHeight;
    params.component = ShadeComponent::Full;
    const LightSet lights = defaultLightSet(b.scene);
    const Camera& camera = b.scene.cameras.at(0);
    ShadeParams filtered = params;
    filtered.samplesPerPixel = 64;
    auto reference = shadeFromCaches(b.scene, *b.rays, b.bake, b.values, lights, camera, filtered);
    ASSERT_TRUE(reference) << reference.error().message;
    double previous = INFINITY;
    double centres = 0.0;
    for (const uint32_t n : {1u, 4u, 16u}) {
        params.samplesPerPixel = n;
        auto image = renderer->render(lights, camera, params);
        ASSERT_TRUE(image) << image.error().message;
        auto error = compareImages(*image, *reference);
        ASSERT_TRUE(error) << error.error().message;
        std::printf("[ measured ] full, cornell_area %ux%u, %u subsamples against the CPU "
                    "shading's 64: relative RMSE %.4f\n",
                    params.width, params.height, n, error->relativeRmse);
        EXPECT_LT(error->relativeRmse, previous) << n << " subsamples";
        previous = error->relativeRmse;
        // Measured: 1.10, 0.45, 0.13 (the emitter is far brighter than the mean, so its
        // staircase dominates the relative RMSE).
        if (n == 1) centres = error->relativeRmse;
        if (n == 16) {
            EXPECT_LT(error->relativeRmse, 0.25 * centres);
        }
    }
}

}  // namespace
}  // namespace pic
