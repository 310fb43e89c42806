// The thin client's headless renderer on lavapipe (or whatever Vulkan device the machine has)
// against its CPU twin, render/cpu/cache_shading.h, on the same scene, bake, caches, lights
// and camera: the cache term on light-mapped and on grid-shaded surfaces, the glossy lobe,
// direct light through shadow maps against exact shadow rays, texture-mapped albedo, no NaN,
// Inf or negative pixels, and bad inputs refused as InvalidInput.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "bake/bake.h"
#include "core/camera.h"
#include "core/gltf_loader.h"
#include "rays/embree_scene.h"
#include "render/cpu/cache_shading.h"
#include "render/cpu/lightmap_copy.h"
#include "render/cpu_runtime.h"
#include "render/passes/gbuffer_pass.h"
#include "render/renderer.h"

namespace pic {
namespace {

/// One Vulkan context for the whole binary, with the validation layer when installed.
gpu::Context* context() {
    static std::unique_ptr<gpu::Context> shared = [] {
        auto created = gpu::Context::create();
        EXPECT_TRUE(created) << created.error().message;
        return created ? std::move(*created) : nullptr;
    }();
    return shared.get();
}

/// A test scene, its rays, a small bake and the caches the CPU runtime lights for the scene's
/// own lights, shared by the tests that use the same scene.
struct Baked {
    Scene scene;
    std::unique_ptr<EmbreeScene> rays;
    BakeData bake;
    CacheValues values;
    bool ok = false;
};

const Baked& baked(const std::string& name) {
    static std::map<std::string, std::unique_ptr<Baked>> cache;
    auto& slot = cache[name];
    if (slot) return *slot;
    slot = std::make_unique<Baked>();
    auto scene = loadScene(std::string(PIC_TEST_SCENE_DIR) + "/" + name + ".gltf");
    EXPECT_TRUE(scene) << name;
    if (!scene) return *slot;
    slot->scene = std::move(*scene);
    auto rays = EmbreeScene::create(slot->scene);
    EXPECT_TRUE(rays);
    if (!rays) return *slot;
    slot->rays = std::move(*rays);
    BakeOptions options;
    options.surfels = 2048;
    options.links = 32;
    const float extent = slot->scene.bounds.diagonal();
    options.gridCell = 0.12f * extent;
    options.lightmapTexel = 0.04f * extent;
    BakeReport report;
    auto bake = runBake(slot->scene, options, report);
    EXPECT_TRUE(bake) << name << ": " << (bake ? "" : bake.error().message);
    if (!bake) return *slot;
    slot->bake = std::move(*bake);
    auto runtime = createCpuRuntime(slot->scene, *slot->rays, slot->bake, BounceParams{});
    EXPECT_TRUE(runtime);
    if (!runtime) return *slot;
    auto values = (*runtime)->setLights(defaultLightSet(slot->scene), nullptr);
    EXPECT_TRUE(values) << (values ? "" : values.error().message);
    if (!values) return *slot;
    slot->values = **values;
    slot->ok = true;
    return *slot;
}

/// The textures a client receives for `values` of `bake`.
CacheTextures texturesOf(const BakeData& bake, const CacheValues& values) {
    CacheTextures textures = makeCacheTextures(bake);
    copyCachesToTextures(bake, values, textures);
    return textures;
}

/// A renderer of `bake`'s layout holding the textures of `values`.
std::unique_ptr<Renderer> rendererFor(const Scene& scene, const BakeData& bake,
                                      const CacheValues& values) {
    gpu::Context* gpu = context();
    if (!gpu) return nullptr;
    auto renderer = Renderer::create(*gpu, scene, clientLayoutOf(bake));
    if (!renderer) {
        ADD_FAILURE() << renderer.error().message;
        return nullptr;
    }
    if (auto ok = (*renderer)->setCaches(texturesOf(bake, values)); !ok) {
        ADD_FAILURE() << ok.error().message;
        return nullptr;
    }
    return std::move(*renderer);
}

/// Every pixel finite and ≥ 0; returns how many are > 0.
int expectFiniteNonNegative(const Image& image, const char* what) {
    int positive = 0;
    for (size_t i = 0; i < image.pixels.size(); ++i) {
        const glm::vec3& p = image.pixels[i];
        for (int c = 0; c < 3; ++c)
            EXPECT_TRUE(std::isfinite(p[c]) && p[c] >= 0.0f)
                << what << ": pixel " << i << " channel " << c << " is " << p[c];
        positive += (p.r > 0.0f || p.g > 0.0f || p.b > 0.0f) ? 1 : 0;
    }
    return positive;
}

/// GPU image and CPU reference of one view, and how they compare.
struct Comparison {
    Image gpu;
    Image cpu;
    ImageError error;
    double differing = 0.0;  ///< fraction of pixels off by more than 5 % of the image mean
};

Comparison compare(Renderer& renderer, const Scene& scene, const EmbreeScene& rays,
                   const BakeData& bake, const CacheValues& values, const LightSet& lights,
                   const Camera& camera, const ShadeParams& params) {
    Comparison out;
    auto gpu = renderer.render(lights, camera, params);
    EXPECT_TRUE(gpu) << (gpu ? "" : gpu.error().message);
    auto cpu = shadeFromCaches(scene, rays, bake, values, lights, camera, params);
    EXPECT_TRUE(cpu) << (cpu ? "" : cpu.error().message);
    if (!gpu || !cpu) return out;
    out.gpu = std::move(*gpu);
    out.cpu = std::move(*cpu);
    auto error = compareImages(out.gpu, out.cpu);
    EXPECT_TRUE(error);
    if (error) out.error = *error;
    double mean = 0.0;
    for (const glm::vec3& p : out.cpu.pixels) mean += (p.r + p.g + p.b) / 3.0;
    mean /= double(out.cpu.pixels.size());
    size_t differing = 0;
    for (size_t i = 0; i < out.cpu.pixels.size(); ++i) {
        const glm::vec3 d = glm::abs(out.gpu.pixels[i] - out.cpu.pixels[i]);
        differing += std::max({d.r, d.g, d.b}) > 0.05 * mean ? 1 : 0;
    }
    out.differing = double(differing) / double(out.cpu.pixels.size());
    return out;
}

/// Reports a comparison in the test output (the figures the README quotes).
void report(const char* what, const Comparison& c) {
    std::printf("[ measured ] %s: relative RMSE %.5f, mean ratio %.5f, pixels off > 5 %%: %.4f\n",
                what, c.error.relativeRmse, c.error.meanRatio, c.differing);
}

/// Fraction of the image's pixel centres whose primary ray hits a light-mapped triangle.
double lightmappedFraction(const Baked& b, const Camera& camera, uint32_t width, uint32_t height,
                           const BakeData& bake) {
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

TEST(ClipFromWorld, PixelCentresLieOnTheCameraRays) {
    Camera camera;
    camera.eye = {0.3f, 1.2f, 2.5f};
    camera.target = {-0.1f, 0.4f, 0.0f};
    camera.up = {0.1f, 1.0f, 0.0f};
    camera.fovyDegrees = 50.0f;
    constexpr uint32_t kWidth = 40, kHeight = 24;
    const glm::mat4 clipFromWorld = gpu::clipFromWorldOf(camera, kWidth, kHeight, 1e-3f);
    const CameraRays rays(camera, kWidth, kHeight);
    for (const glm::vec2 pixel : {glm::vec2(0.5f, 0.5f), glm::vec2(39.5f, 0.5f),
                                  glm::vec2(13.5f, 17.5f), glm::vec2(39.5f, 23.5f)}) {
        for (float distance : {0.01f, 1.0f, 100.0f}) {
            const glm::vec3 p = rays.origin() + distance * rays.direction(pixel.x, pixel.y);
            const glm::vec4 clip = clipFromWorld * glm::vec4(p, 1.0f);
            // Vulkan's viewport transform: framebuffer x = (ndc + 1)/2 · width, row 0 at the top.
            const glm::vec2 framebuffer((clip.x / clip.w + 1.0f) * 0.5f * kWidth,
                                        (clip.y / clip.w + 1.0f) * 0.5f * kHeight);
            EXPECT_NEAR(framebuffer.x, pixel.x, 1e-3f);
            EXPECT_NEAR(framebuffer.y, pixel.y, 1e-3f);
            const float depth = clip.z / clip.w;
            EXPECT_GT(depth, 0.0f);
            EXPECT_LE(depth, 1.0f);
        }
    }
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
void expectIndirectMatches(const Baked& b, const BakeData& bake, const char* what) {
    auto renderer = rendererFor(b.scene, bake, b.values);
    ASSERT_TRUE(renderer);
    ShadeParams params;
    params.component = ShadeComponent::Indirect;
    const std::pair<Camera, glm::uvec2> views[] = {
        {b.scene.cameras.at(0), {kAxisWidth, kAxisHeight}}, {obliqueCornellCamera(), {128, 96}}};
    for (const auto& [camera, size] : views) {
        params.width = size.x;
        params.height = size.y;
        const Comparison c = compare(*renderer, b.scene, *b.rays, bake, b.values,
                                     defaultLightSet(b.scene), camera, params);
        const std::string label = std::string(what) + ", cornell " + camera.name + " " +
                                  std::to_string(size.x) + "x" + std::to_string(size.y);
        report(label.c_str(), c);
        EXPECT_LE(c.error.relativeRmse, 0.01) << label;
        EXPECT_NEAR(c.error.meanRatio, 1.0, 0.002) << label;
        EXPECT_GT(expectFiniteNonNegative(c.gpu, what), int(size.x * size.y) / 2) << label;
    }
    EXPECT_EQ(context()->validationMessages(), 0u);
}

TEST(RendererIndirect, LightMappedSurfacesMatchTheCpuShading) {
    const Baked& b = baked("cornell");
    ASSERT_TRUE(b.ok);
    // Most of the view reads the light map.
    EXPECT_GT(lightmappedFraction(b, b.scene.cameras.at(0), 32, 32, b.bake), 0.8);
    expectIndirectMatches(b, b.bake, "indirect, light map");
}

TEST(RendererIndirect, GridShadedSurfacesMatchTheCpuShading) {
    const Baked& b = baked("cornell");
    ASSERT_TRUE(b.ok);
    // The same caches, every triangle shaded from the grid.
    BakeData gridOnly = b.bake;
    for (glm::vec2& uv : gridOnly.lightmap.triangleUvs) uv = glm::vec2(kNotLightmapped);
    expectIndirectMatches(b, gridOnly, "indirect, grid");
}

TEST(RendererIndirect, GlossyLobeMatchesTheCpuShading) {
    const Baked& b = baked("cornell");
    ASSERT_TRUE(b.ok);
    auto renderer = rendererFor(b.scene, b.bake, b.values);
    ASSERT_TRUE(renderer);
    ShadeParams params;
    params.width = 95;
    params.height = 96;
    params.component = ShadeComponent::Indirect;
    params.glossyExponent = 12.0f;
    params.glossyWeight = 0.4f;
    const Comparison c = compare(*renderer, b.scene, *b.rays, b.bake, b.values,
                                 defaultLightSet(b.scene), b.scene.cameras.at(0), params);
    report("indirect + glossy (cornell 96x96)", c);
    EXPECT_LE(c.error.relativeRmse, 0.01);
    expectFiniteNonNegative(c.gpu, "glossy");
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
    const Baked& b = baked(param.scene);
    ASSERT_TRUE(b.ok);
    auto renderer = rendererFor(b.scene, b.bake, b.values);
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
    const Comparison c =
        compare(*renderer, b.scene, *b.rays, b.bake, b.values, lights, camera, params);
    const std::string label =
        std::string(param.component == ShadeComponent::Full ? "full" : "direct") + ", " +
        param.scene + (param.oblique ? " oblique" : "") +
        (param.extraLights ? " + spots + sun" : "") + " " + std::to_string(params.width) + "x" +
        std::to_string(params.height);
    report(label.c_str(), c);
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
    EXPECT_GT(expectFiniteNonNegative(c.gpu, label.c_str()), 100);
    EXPECT_EQ(context()->validationMessages(), 0u);
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
    auto loaded = loadScene(std::string(PIC_TEST_SCENE_DIR) + "/textured_quad.gltf");
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
    auto renderer = rendererFor(scene, bake, values);
    ASSERT_TRUE(renderer);
    ShadeParams params;
    params.width = 96;
    params.height = 96;
    params.component = ShadeComponent::Full;
    const Comparison c = compare(*renderer, scene, **rays, bake, values, defaultLightSet(scene),
                                 scene.cameras.at(0), params);
    report("full, textured quad, no caches (96x96)", c);
    EXPECT_LE(c.error.relativeRmse, 0.01);
    EXPECT_LE(c.differing, 0.005);
    EXPECT_GT(expectFiniteNonNegative(c.gpu, "textured"), int(params.width * params.height) / 4);
}

TEST(RendererFull, IsEmissionPlusDirectPlusIndirect) {
    const Baked& b = baked("cornell");
    ASSERT_TRUE(b.ok);
    auto renderer = rendererFor(b.scene, b.bake, b.values);
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
        expectFiniteNonNegative(parts[k], "component");
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
    const Baked& b = baked("cornell");
    ASSERT_TRUE(b.ok);
    // Caches with large alternating higher-band coefficients: their irradiance rings below
    // zero on many surfaces, where both renderers clamp it.
    CacheValues values = b.values;
    for (size_t i = 0; i < values.y.size(); ++i)
        values.y[i] = (i % 9 == 0) ? 0.2f : 3.0f * std::sin(float(i));
    for (size_t i = 0; i < values.co.size(); ++i) values.co[i] = 0.5f * std::cos(float(i));
    for (size_t i = 0; i < values.cg.size(); ++i) values.cg[i] = -0.5f * std::sin(float(3 * i));
    auto renderer = rendererFor(b.scene, b.bake, values);
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
        expectFiniteNonNegative(*image, "ringing caches");
    }
    params.component = ShadeComponent::Indirect;
    const Comparison c = compare(*renderer, b.scene, *b.rays, b.bake, values,
                                 defaultLightSet(b.scene), b.scene.cameras.at(0), params);
    report("indirect + glossy, ringing caches (cornell 64x64)", c);
    EXPECT_LE(c.error.relativeRmse, 0.01);
}

TEST(Renderer, RefusesBadInputsAsInvalidInput) {
    const Baked& b = baked("cornell");
    ASSERT_TRUE(b.ok);
    gpu::Context* gpu = context();
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
    const CacheTextures good = texturesOf(b.bake, b.values);
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
    ShadeParams subsamples = params;
    subsamples.samplesPerPixel = 4;
    expectInvalid(renderer.render(lights, camera, subsamples), "subsamples");
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
    EXPECT_GT(expectFiniteNonNegative(*image, "after refusals"), 0);
    EXPECT_EQ(gpu->validationMessages(), 0u);
}

TEST(Renderer, ResizesBetweenFramesAndTakesEachCacheVersion) {
    const Baked& b = baked("cornell");
    ASSERT_TRUE(b.ok);
    gpu::Context* gpu = context();
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
        EXPECT_EQ(expectFiniteNonNegative(*image, "before caches"), 0);
    }

    // Each streamed version replaces the textures: twice the radiance, twice the image (to
    // the half-float rounding of the textures).
    params.width = 31;
    params.height = 32;
    CacheValues doubled = b.values;
    for (std::vector<float>* v : {&doubled.y, &doubled.co, &doubled.cg})
        for (float& x : *v) x *= 2.0f;
    ASSERT_TRUE(renderer.setCaches(texturesOf(b.bake, b.values)));
    auto once = renderer.render(defaultLightSet(b.scene), b.scene.cameras.at(0), params);
    ASSERT_TRUE(renderer.setCaches(texturesOf(b.bake, doubled)));
    auto twice = renderer.render(defaultLightSet(b.scene), b.scene.cameras.at(0), params);
    ASSERT_TRUE(once && twice);
    EXPECT_GT(expectFiniteNonNegative(*once, "first version"), 0);
    for (size_t i = 0; i < once->pixels.size(); ++i)
        for (int c = 0; c < 3; ++c)
            ASSERT_NEAR(twice->pixels[i][c], 2.0f * once->pixels[i][c],
                        2e-3f * once->pixels[i][c] + 1e-6f)
                << "pixel " << i;
    EXPECT_EQ(gpu->validationMessages(), 0u);
}

}  // namespace
}  // namespace pic
