// The G-buffer pass on lavapipe (or the machine's GPU) against the camera rays it stands in
// for: its clip-from-world matrix puts pixel centres on CameraRays' directions, and each pixel
// holds what its centre's ray hits (position, normal facing the camera, albedo with the hit
// flag, emission of front faces, light-map UV) or zeros where the ray misses.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <vector>

#include "core/bake_data.h"
#include "core/camera.h"
#include "gpu/kernel.h"
#include "gpu/resources.h"
#include "render/passes/gbuffer_pass.h"
#include "spirv/gbuffer_readback_comp.h"
#include "tests/render/renderer_fixture.h"

namespace pic {
namespace {

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

/// A planar rectangle corner + u·edgeU + v·edgeV (u, v in [0, 1]) as two triangles wound
/// counter-clockwise around `normal` = normalize(edgeU × edgeV).
struct Rectangle {
    glm::vec3 corner, edgeU, edgeV;
    uint32_t material;
    bool lightmapped;

    glm::vec3 normal() const { return glm::normalize(glm::cross(edgeU, edgeV)); }
    /// The light-map UV of a lightmapped rectangle's point (u, v): an affine map, which the
    /// rasteriser's perspective-correct interpolation must reproduce.
    glm::vec2 lightmapUv(float u, float v) const { return {0.1f + 0.8f * u, 0.2f + 0.5f * v}; }
};

/// Where the ray origin + t·direction meets a rectangle's plane: t and the point's (u, v).
struct PlaneHit {
    float t;
    float u, v;
};

std::optional<PlaneHit> hitPlane(const Rectangle& r, const glm::vec3& origin,
                                 const glm::vec3& direction) {
    const glm::vec3 n = r.normal();
    const float along = glm::dot(direction, n);
    if (std::abs(along) < 1e-6f) return std::nullopt;
    const float t = glm::dot(r.corner - origin, n) / along;
    if (!(t > 0.0f)) return std::nullopt;
    const glm::vec3 d = origin + t * direction - r.corner;
    return PlaneHit{t, glm::dot(d, r.edgeU) / glm::dot(r.edgeU, r.edgeU),
                    glm::dot(d, r.edgeV) / glm::dot(r.edgeV, r.edgeV)};
}

/// The four targets of a G-buffer pass, read back through a test kernel: target-major,
/// row-major, row 0 at the top.
std::vector<glm::vec4> readTargets(gpu::Context& context, const gpu::GbufferPass& pass) {
    const uint32_t pixels = pass.width() * pass.height();
    gpu::KernelLayout layout;
    layout.bindings.assign(gpu::kGbufferTargets, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER);
    layout.bindings.push_back(VK_DESCRIPTOR_TYPE_STORAGE_BUFFER);
    layout.pushBytes = 2 * sizeof(uint32_t);
    auto kernel = gpu::Kernel::create(context, kSpirvGbufferReadbackComp, layout,
                                      "gbuffer_readback.comp");
    EXPECT_TRUE(kernel) << kernel.error().message;
    const VkDeviceSize bytes = VkDeviceSize{gpu::kGbufferTargets} * pixels * sizeof(glm::vec4);
    auto texels = gpu::Buffer::create(context, bytes, 0, gpu::MemoryUse::Readback, "G-buffer read-back");
    EXPECT_TRUE(texels) << texels.error().message;
    if (!kernel || !texels) return {};
    const VkSampler sampler = context.nearestSampler();
    const gpu::BindingResource resources[] = {
        gpu::BindingResource::image(0, pass.target(0).view(), sampler),
        gpu::BindingResource::image(1, pass.target(1).view(), sampler),
        gpu::BindingResource::image(2, pass.target(2).view(), sampler),
        gpu::BindingResource::image(3, pass.target(3).view(), sampler),
        gpu::BindingResource::storage(4, *texels)};
    auto set = kernel->makeSet(resources);
    EXPECT_TRUE(set) << set.error().message;
    if (!set) return {};
    const uint32_t push[2] = {pass.width(), pass.height()};
    auto submitted = context.submit([&](VkCommandBuffer cmd) {
        kernel->dispatch(cmd, *set, push, gpu::groupsFor(pixels, 64));
    });
    EXPECT_TRUE(submitted) << submitted.error().message;
    std::vector<glm::vec4> out(size_t{gpu::kGbufferTargets} * pixels);
    auto downloaded = context.download(*texels, out.data(), bytes);
    EXPECT_TRUE(downloaded) << downloaded.error().message;
    return out;
}

TEST(GbufferPass, PixelsHoldWhatTheirCameraRaysHit) {
    // An emissive, light-mapped panel facing the camera, in front of a grid-shaded, tilted
    // wall that faces away from it (the camera sees its back: normal flipped, no emission),
    // with sky around both.
    const Rectangle rectangles[2] = {
        {{-0.6f, -0.4f, 0.0f}, {1.2f, 0.0f, 0.0f}, {0.0f, 0.8f, 0.0f}, 0, true},
        {{-1.5f, 1.0f, -0.55f}, {3.0f, 0.0f, -0.9f}, {0.0f, -2.0f, 0.0f}, 1, false}};
    Scene scene;
    scene.materials = {Material{.name = "panel", .baseColorFactor = {0.8f, 0.5f, 0.25f, 1.0f},
                                .emission = {2.0f, 1.0f, 0.5f}},
                       Material{.name = "wall", .baseColorFactor = {0.3f, 0.6f, 0.9f, 1.0f},
                                .emission = {1.0f, 1.0f, 1.0f}}};
    std::vector<glm::vec2> triangleUvs;
    for (const Rectangle& r : rectangles) {
        const uint32_t first = uint32_t(scene.vertices.size());
        const glm::vec2 corners[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
        for (const glm::vec2& c : corners) {
            Vertex v;
            v.position = r.corner + c.x * r.edgeU + c.y * r.edgeV;
            v.normal = r.normal();
            scene.vertices.push_back(v);
            scene.bounds.extend(v.position);
        }
        for (const uint32_t k : {0u, 1u, 2u, 0u, 2u, 3u})
            triangleUvs.push_back(r.lightmapped ? r.lightmapUv(corners[k].x, corners[k].y)
                                                : glm::vec2(kNotLightmapped));
        scene.triangles.push_back(Triangle{{first, first + 1, first + 2}, r.material, 0});
        scene.triangles.push_back(Triangle{{first, first + 2, first + 3}, r.material, 0});
    }
    ASSERT_GT(glm::dot(rectangles[0].normal(), glm::vec3(0, 0, 1)), 0.9f);
    ASSERT_LT(glm::dot(rectangles[1].normal(), glm::vec3(0, 0, 1)), -0.9f);

    gpu::Context* context = test::sharedContext();
    ASSERT_TRUE(context);
    auto pass =
        gpu::createPass<gpu::GbufferPass>(*context, {.scene = &scene, .triangleUvs = triangleUvs});
    ASSERT_TRUE(pass) << pass.error().message;
    Camera camera;
    camera.eye = {0.15f, 0.2f, 2.5f};
    camera.target = {0.0f, 0.0f, -0.3f};
    camera.fovyDegrees = 50.0f;
    constexpr uint32_t kWidth = 64, kHeight = 48;
    LightSet lights;
    lights.emissiveScale["panel"] = 0.5f;
    bool reallocated = false;
    ASSERT_TRUE((*pass)->prepare(kWidth, kHeight, lights, reallocated));
    EXPECT_TRUE(reallocated);
    const gpu::GbufferPush push = gpu::gbufferPushOf(camera, kWidth, kHeight, 1e-3f);
    ASSERT_TRUE(
        context->submit([&](VkCommandBuffer cmd) { (*pass)->record(cmd, {.gbuffer = push}); }));
    const std::vector<glm::vec4> targets = readTargets(*context, **pass);
    ASSERT_EQ(targets.size(), size_t{gpu::kGbufferTargets} * kWidth * kHeight);

    // Each pixel against its centre's camera ray, except where the ray passes within 1 % of
    // a rectangle's side of its border (there the rasteriser's coverage rule decides).
    const CameraRays rays(camera, kWidth, kHeight);
    int compared[3] = {0, 0, 0};  // panel, wall (back face), sky
    for (uint32_t y = 0; y < kHeight; ++y)
        for (uint32_t x = 0; x < kWidth; ++x) {
            const glm::vec3 direction = rays.direction(float(x) + 0.5f, float(y) + 0.5f);
            std::optional<PlaneHit> nearest;
            int hitRectangle = -1;
            bool nearBorder = false;
            for (int r = 0; r < 2; ++r) {
                const auto hit = hitPlane(rectangles[r], rays.origin(), direction);
                if (!hit) continue;
                const float margin = std::min({std::abs(hit->u), std::abs(1.0f - hit->u),
                                               std::abs(hit->v), std::abs(1.0f - hit->v)});
                nearBorder |= margin < 0.01f;
                const bool inside = hit->u >= 0.0f && hit->u <= 1.0f && hit->v >= 0.0f &&
                                    hit->v <= 1.0f;
                if (inside && (!nearest || hit->t < nearest->t)) {
                    nearest = hit;
                    hitRectangle = r;
                }
            }
            if (nearBorder) continue;
            const size_t i = size_t(y) * kWidth + x;
            const glm::vec4 positionU = targets[i];
            const glm::vec4 normalV = targets[size_t{kWidth} * kHeight + i];
            const glm::vec4 albedo = targets[2 * size_t{kWidth} * kHeight + i];
            const glm::vec4 emission = targets[3 * size_t{kWidth} * kHeight + i];
            SCOPED_TRACE(testing::Message() << "pixel " << x << "," << y);
            if (hitRectangle < 0) {  // sky: the cleared zeros, hit flag 0
                EXPECT_EQ(positionU, glm::vec4(0.0f));
                EXPECT_EQ(normalV, glm::vec4(0.0f));
                EXPECT_EQ(albedo, glm::vec4(0.0f));
                EXPECT_EQ(emission, glm::vec4(0.0f));
                ++compared[2];
                continue;
            }
            const Rectangle& r = rectangles[hitRectangle];
            const Material& material = scene.materials[r.material];
            const glm::vec3 p = rays.origin() + nearest->t * direction;
            const bool backFace = glm::dot(r.normal(), direction) > 0.0f;
            const glm::vec3 normal = backFace ? -r.normal() : r.normal();
            const glm::vec2 uv = r.lightmapped ? r.lightmapUv(nearest->u, nearest->v)
                                               : glm::vec2(kNotLightmapped);
            const glm::vec3 emitted =
                backFace ? glm::vec3(0.0f)
                         : material.emission * lights.emissiveScaleOf(material.name);
            for (int c = 0; c < 3; ++c) {
                EXPECT_NEAR(positionU[c], p[c], 2e-4f) << "position " << c;
                EXPECT_NEAR(normalV[c], normal[c], 1e-6f) << "normal " << c;
                // The vertex colour (1) is interpolated too.
                EXPECT_NEAR(albedo[c], material.baseColorFactor[c], 1e-6f) << "albedo " << c;
                EXPECT_EQ(emission[c], emitted[c]) << "emission " << c;
            }
            EXPECT_NEAR(positionU.w, uv.x, 2e-4f);
            EXPECT_NEAR(normalV.w, uv.y, 2e-4f);
            EXPECT_EQ(albedo.w, 1.0f);
            ++compared[hitRectangle];
        }
    // Each kind of pixel is well represented (385, 835 and 1623 of the 3072 here).
    EXPECT_GT(compared[0], 300);
    EXPECT_GT(compared[1], 600);
    EXPECT_GT(compared[2], 1000);
    EXPECT_EQ(context->validationMessages(), 0u);
}

TEST(GbufferPass, TexturedAlbedoIsTheCpuFootprintAverage) {
    // A floor 6 m × 40 m carrying a 64 × 64 texture of random texels once per metre, seen from
    // half a metre above it towards the horizon: footprints from one texel (magnified, near) to
    // whole textures (grazing), many of them long enough for anisotropic taps. Each pixel's
    // albedo against Scene::albedoOverFootprint of its centre ray's footprint on the CPU.
    const Rectangle floor{{-3.0f, 0.0f, 2.0f}, {6.0f, 0.0f, 0.0f}, {0.0f, 0.0f, -40.0f}, 0, false};
    Scene scene;
    Texture random;
    random.name = "random";
    random.width = random.height = 64;
    uint32_t state = 12345u;
    for (int i = 0; i < 64 * 64; ++i) {
        glm::vec4 texel(1.0f);
        for (int c = 0; c < 3; ++c) {
            state = state * 1664525u + 1013904223u;  // a fixed LCG: the same texels everywhere
            texel[c] = float(state >> 8) / float(1u << 24);
        }
        random.texels.push_back(texel);
    }
    buildMipChain(random);
    scene.textures.push_back(std::move(random));
    scene.materials = {Material{
        .name = "floor", .baseColorFactor = {0.9f, 0.8f, 1.0f, 1.0f}, .baseColorTexture = 0}};
    const glm::vec2 corners[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    for (const glm::vec2& c : corners) {
        Vertex v;
        v.position = floor.corner + c.x * floor.edgeU + c.y * floor.edgeV;
        v.normal = floor.normal();
        v.uv0 = c * glm::vec2(6.0f, 40.0f);  // one texture repeat per metre
        scene.vertices.push_back(v);
        scene.bounds.extend(v.position);
    }
    scene.triangles.push_back(Triangle{{0, 1, 2}, 0, 0});
    scene.triangles.push_back(Triangle{{0, 2, 3}, 0, 0});
    const std::vector<glm::vec2> triangleUvs(6, glm::vec2(kNotLightmapped));

    gpu::Context* context = test::sharedContext();
    ASSERT_TRUE(context);
    auto pass =
        gpu::createPass<gpu::GbufferPass>(*context, {.scene = &scene, .triangleUvs = triangleUvs});
    ASSERT_TRUE(pass) << pass.error().message;
    Camera camera;
    camera.eye = {0.1f, 0.5f, 2.5f};
    camera.target = {0.0f, 0.3f, -3.0f};
    camera.fovyDegrees = 50.0f;
    constexpr uint32_t kWidth = 96, kHeight = 64;
    bool reallocated = false;
    ASSERT_TRUE((*pass)->prepare(kWidth, kHeight, LightSet{}, reallocated));
    const gpu::GbufferPush push = gpu::gbufferPushOf(camera, kWidth, kHeight, 1e-3f);
    ASSERT_TRUE(
        context->submit([&](VkCommandBuffer cmd) { (*pass)->record(cmd, {.gbuffer = push}); }));
    const std::vector<glm::vec4> targets = readTargets(*context, **pass);
    ASSERT_EQ(targets.size(), size_t{gpu::kGbufferTargets} * kWidth * kHeight);

    const CameraRays rays(camera, kWidth, kHeight);
    int compared = 0, close = 0, filtered = 0;
    float worst = 0.0f;
    for (uint32_t y = 0; y < kHeight; ++y)
        for (uint32_t x = 0; x < kWidth; ++x) {
            const glm::vec3 direction = rays.direction(float(x) + 0.5f, float(y) + 0.5f);
            const auto hit = hitPlane(floor, rays.origin(), direction);
            if (!hit || std::min({hit->u, 1.0f - hit->u, hit->v, 1.0f - hit->v}) < 0.01f)
                continue;  // off the floor or at its border (the coverage rule decides)
            const glm::vec3 p = rays.origin() + hit->t * direction;
            // Triangle 0 holds u ≥ v of the rectangle, triangle 1 the rest (see Rectangle).
            const bool first = hit->u >= hit->v;
            const float b1 = first ? hit->u - hit->v : hit->u;
            const float b2 = first ? hit->v : hit->v - hit->u;
            const PixelFootprint footprint = rays.footprintOnPlane(p, floor.normal());
            const glm::vec3 expected =
                scene.albedoOverFootprint(first ? 0 : 1, b1, b2, footprint.dPdx, footprint.dPdy);
            const glm::vec4 albedo = targets[2 * size_t{kWidth} * kHeight + size_t(y) * kWidth + x];
            float error = 0.0f;
            for (int c = 0; c < 3; ++c) error = std::max(error, std::abs(albedo[c] - expected[c]));
            worst = std::max(worst, error);
            close += error <= 2e-3f;
            // Footprints over a texel across: the lookup is more than one bilinear tap.
            filtered += glm::length(footprint.dPdx) * 64.0f > 1.0f ||
                        glm::length(footprint.dPdy) * 64.0f > 1.0f;
            ++compared;
        }
    std::printf("textured floor: %d pixels compared, %d filtered, %d within 2e-3, worst %.4f\n",
                compared, filtered, close, worst);
    EXPECT_GT(compared, 2500);
    EXPECT_GT(filtered, compared / 2);
    // The twins agree but for float rounding; a rare pixel may differ where a tap count or
    // a level boundary falls between the two roundings.
    EXPECT_GE(close, compared - compared / 200);
    EXPECT_LT(worst, 0.05f);
    EXPECT_EQ(context->validationMessages(), 0u);
}

}  // namespace
}  // namespace pic
