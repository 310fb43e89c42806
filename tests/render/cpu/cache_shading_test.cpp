// Shading from caches against analytic answers: constant incident radiance, a point light over
// a plane with a hard shadow, emission per component, and determinism.

#include "render/cpu/cache_shading.h"

#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

#include "core/camera.h"
#include "core/parallel.h"
#include "core/sh.h"
#include "tests/support/baked_scene.h"

namespace pic {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

/// The cornell test scene and a small bake of it, shared by the tests that need a real bake.
const test::BakedScene& cornell() {
    return test::bakedScene("cornell", test::smallBakeOptions(4096, 64, 0.2f, 0.1f));
}

/// Cache values whose every cache holds the constant radiance L (grey): band-0 Y = L·2√π.
CacheValues constantValues(const BakeData& bake, float radiance) {
    CacheValues values =
        CacheValues::zeros(bake.caches.size(), bake.params.bandsY, bake.params.bandsC);
    const size_t countY = size_t{values.bandsY} * values.bandsY;
    for (size_t c = 0; c < bake.caches.size(); ++c)
        values.y[c * countY] = radiance * 2.0f * std::sqrt(kPi);
    return values;
}

TEST(CacheShading, ConstantRadianceGivesAlbedoTimesRadiance) {
    const test::BakedScene& f = cornell();
    ASSERT_TRUE(f.rays);
    constexpr float kRadiance = 0.75f;
    const CacheValues values = constantValues(f.bake, kRadiance);
    const Camera& camera = f.scene.cameras.at(0);
    ShadeParams params;
    params.width = 48;
    params.height = 40;
    params.component = ShadeComponent::Indirect;
    auto image =
        shadeFromCaches(f.scene, *f.rays, f.bake, values, defaultLightSet(f.scene), camera, params);
    ASSERT_TRUE(image.has_value()) << image.error().message;

    // E = π·L on every surface, so the cache term is ρ/π·π·L = ρ·L wherever the primary ray
    // hits; a miss is black.
    const CameraRays cameraRays(camera, params.width, params.height);
    int hits = 0;
    for (uint32_t y = 0; y < params.height; ++y) {
        for (uint32_t x = 0; x < params.width; ++x) {
            const glm::vec3 direction = cameraRays.direction(float(x) + 0.5f, float(y) + 0.5f);
            const auto hit = f.rays->intersect(cameraRays.origin(), direction, 0.0f, INFINITY);
            const glm::vec3 expected =
                hit ? kRadiance * f.scene.albedoAt(hit->triangle, hit->b1, hit->b2)
                    : glm::vec3(0.0f);
            hits += hit ? 1 : 0;
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(image->at(x, y)[c], expected[c], 1e-4f * expected[c] + 1e-7f)
                    << "pixel " << x << "," << y << " channel " << c;
        }
    }
    EXPECT_GT(hits, int(params.width * params.height) / 2);
}

TEST(CacheShading, GlossyLobeOfConstantRadianceIsThatRadiance) {
    const test::BakedScene& f = cornell();
    ASSERT_TRUE(f.rays);
    constexpr float kRadiance = 0.5f;
    constexpr float kWeight = 0.3f;
    const CacheValues values = constantValues(f.bake, kRadiance);
    const Camera& camera = f.scene.cameras.at(0);
    ShadeParams params;
    params.width = 16;
    params.height = 16;
    params.component = ShadeComponent::Indirect;
    params.glossyExponent = 20.0f;
    params.glossyWeight = kWeight;
    auto image =
        shadeFromCaches(f.scene, *f.rays, f.bake, values, defaultLightSet(f.scene), camera, params);
    ASSERT_TRUE(image.has_value()) << image.error().message;
    // The normalised lobe averages the incident radiance: ρ·L + w·L.
    const CameraRays cameraRays(camera, params.width, params.height);
    for (uint32_t y = 0; y < params.height; ++y) {
        for (uint32_t x = 0; x < params.width; ++x) {
            const auto hit = f.rays->intersect(
                cameraRays.origin(), cameraRays.direction(float(x) + 0.5f, float(y) + 0.5f), 0.0f,
                INFINITY);
            if (!hit) continue;
            const glm::vec3 expected =
                kRadiance * f.scene.albedoAt(hit->triangle, hit->b1, hit->b2) + kWeight * kRadiance;
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(image->at(x, y)[c], expected[c], 1e-4f * expected[c]);
        }
    }
}

/// A hand-built scene: quads given by a corner and two edges, one material each.
struct HandScene {
    Scene scene;

    void addQuad(const glm::vec3& corner, const glm::vec3& edgeU, const glm::vec3& edgeV,
                 uint32_t material) {
        const uint32_t first = uint32_t(scene.vertices.size());
        const glm::vec3 normal = glm::normalize(glm::cross(edgeU, edgeV));
        for (const glm::vec3& p :
             {corner, corner + edgeU, corner + edgeU + edgeV, corner + edgeV}) {
            Vertex v;
            v.position = p;
            v.normal = normal;
            scene.vertices.push_back(v);
            scene.bounds.extend(p);
        }
        // Counter-clockwise around edgeU × edgeV.
        scene.triangles.push_back(Triangle{{first, first + 1, first + 2}, material, 0});
        scene.triangles.push_back(Triangle{{first, first + 2, first + 3}, material, 0});
    }
    uint32_t addMaterial(const std::string& name, const glm::vec3& albedo,
                         const glm::vec3& emission) {
        Material m;
        m.name = name;
        m.baseColorFactor = glm::vec4(albedo, 1.0f);
        m.emission = emission;
        scene.materials.push_back(m);
        return uint32_t(scene.materials.size() - 1);
    }
    /// A bake without caches (every surface grid-shaded, the grid empty): the cache term is 0.
    BakeData emptyBake() const {
        BakeData bake;
        bake.sceneHash = scene.hash;
        bake.lightmap.triangleUvs.assign(3 * scene.triangles.size(), glm::vec2(kNotLightmapped));
        return bake;
    }
};

TEST(CacheShading, DirectLightOfAPointLightOverAPlaneWithAShadow) {
    // Floor y = 0 (ρ = (0.8, 0.5, 0.2)) lit by a point light of I = 2 W/sr at (0, 1, 0); an
    // occluder at y = 0.5 over x ∈ [0.2, 0.4], z ∈ [−0.1, 0.1] shadows x ∈ [0.4, 0.8],
    // z ∈ [−0.2, 0.2] of the floor (the segment to the light crosses y = 0.5 halfway).
    HandScene hand;
    const glm::vec3 floorAlbedo(0.8f, 0.5f, 0.2f);
    const glm::vec3 occluderAlbedo(0.3f);
    const uint32_t floor = hand.addMaterial("floor", floorAlbedo, glm::vec3(0.0f));
    const uint32_t occluder = hand.addMaterial("occluder", occluderAlbedo, glm::vec3(0.0f));
    hand.addQuad({-5, 0, 5}, {10, 0, 0}, {0, 0, -10}, floor);
    hand.addQuad({0.2f, 0.5f, 0.1f}, {0.2f, 0, 0}, {0, 0, -0.2f}, occluder);
    const Scene& scene = hand.scene;
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays.has_value());
    const BakeData bake = hand.emptyBake();
    const CacheValues values = CacheValues::zeros(0, 3, 3);
    Light lamp;
    lamp.position = glm::vec3(0.0f, 1.0f, 0.0f);
    lamp.intensity = 2.0f;
    LightSet lights;
    lights.lights = {lamp};
    Camera camera;
    camera.eye = glm::vec3(0.0f, 3.0f, 0.0f);
    camera.target = glm::vec3(0.0f);
    camera.up = glm::vec3(0.0f, 0.0f, -1.0f);
    camera.fovyDegrees = 60.0f;
    ShadeParams params;
    params.width = 64;
    params.height = 64;
    params.component = ShadeComponent::Direct;
    auto image = shadeFromCaches(scene, **rays, bake, values, lights, camera, params);
    ASSERT_TRUE(image.has_value()) << image.error().message;

    const CameraRays cameraRays(camera, params.width, params.height);
    int shadowed = 0;
    int lit = 0;
    for (uint32_t y = 0; y < params.height; ++y) {
        for (uint32_t x = 0; x < params.width; ++x) {
            const glm::vec3 d = cameraRays.direction(float(x) + 0.5f, float(y) + 0.5f);
            // Analytic primary hit: the occluder's top if the ray crosses it, else the floor.
            const glm::vec3 atOccluder = camera.eye + ((camera.eye.y - 0.5f) / -d.y) * d;
            const bool onOccluder =
                atOccluder.x >= 0.2f && atOccluder.x <= 0.4f && std::abs(atOccluder.z) <= 0.1f;
            const glm::vec3 p = onOccluder ? atOccluder : camera.eye + (camera.eye.y / -d.y) * d;
            const glm::vec3 albedo = onOccluder ? occluderAlbedo : floorAlbedo;
            // Pixels within a millimetre of an edge could go either way: skip them.
            const glm::vec3 mid = 0.5f * (p + lamp.position);
            const float edgeDistance = onOccluder
                                           ? std::min({atOccluder.x - 0.2f, 0.4f - atOccluder.x,
                                                       0.1f - std::abs(atOccluder.z)})
                                           : std::min(std::abs(std::abs(mid.x - 0.3f) - 0.1f),
                                                      std::abs(std::abs(mid.z) - 0.1f));
            if (edgeDistance < 1e-3f) continue;
            const bool inShadow =
                !onOccluder && std::abs(mid.x - 0.3f) < 0.1f && std::abs(mid.z) < 0.1f;
            const glm::vec3 toLight = lamp.position - p;
            const float d2 = glm::dot(toLight, toLight);
            const float cosTheta = toLight.y / std::sqrt(d2);
            const glm::vec3 expected =
                inShadow ? glm::vec3(0.0f) : albedo * lamp.intensity * cosTheta / (kPi * d2);
            (inShadow ? shadowed : lit)++;
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(image->at(x, y)[c], expected[c], 1e-4f * expected[c] + 1e-7f)
                    << "pixel " << x << "," << y << (inShadow ? " (shadow)" : "");
        }
    }
    EXPECT_GT(shadowed, 10);
    EXPECT_GT(lit, 1000);
}

TEST(CacheShading, EmissionIsVisibleInFullOnlyFromTheFront) {
    // A black emitter filling the view; the light set scales its emission by 3.
    HandScene hand;
    const glm::vec3 emission(2.0f, 1.0f, 0.5f);
    const uint32_t panel = hand.addMaterial("panel", glm::vec3(0.0f), emission);
    hand.addQuad({-10, -10, 0}, {20, 0, 0}, {0, 20, 0}, panel);  // faces +z
    const Scene& scene = hand.scene;
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays.has_value());
    const BakeData bake = hand.emptyBake();
    const CacheValues values = CacheValues::zeros(0, 3, 3);
    LightSet lights;
    lights.emissiveScale["panel"] = 3.0f;
    Camera front;
    front.eye = glm::vec3(0.0f, 0.0f, 2.0f);
    front.target = glm::vec3(0.0f);
    Camera back = front;
    back.eye = glm::vec3(0.0f, 0.0f, -2.0f);
    ShadeParams params;
    params.width = 8;
    params.height = 8;
    for (ShadeComponent component :
         {ShadeComponent::Full, ShadeComponent::Direct, ShadeComponent::Indirect}) {
        params.component = component;
        for (const Camera* camera : {&front, &back}) {
            auto image = shadeFromCaches(scene, **rays, bake, values, lights, *camera, params);
            ASSERT_TRUE(image.has_value()) << image.error().message;
            const glm::vec3 expected = component == ShadeComponent::Full && camera == &front
                                           ? 3.0f * emission
                                           : glm::vec3(0.0f);
            for (const glm::vec3& pixel : image->pixels)
                for (int c = 0; c < 3; ++c) EXPECT_NEAR(pixel[c], expected[c], 1e-6f);
        }
    }
}

TEST(CacheShading, IsDeterministicAcrossThreadCounts) {
    const test::BakedScene& f = cornell();
    ASSERT_TRUE(f.rays);
    // Directional radiance per cache, so that every pixel's value depends on its lookup.
    CacheValues values =
        CacheValues::zeros(f.bake.caches.size(), f.bake.params.bandsY, f.bake.params.bandsC);
    for (size_t i = 0; i < values.y.size(); ++i) values.y[i] = 1.0f + 0.5f * std::sin(float(i));
    for (size_t i = 0; i < values.co.size(); ++i) values.co[i] = 0.2f * std::cos(float(i));
    ShadeParams params;
    params.width = 40;
    params.height = 30;
    params.samplesPerPixel = 4;
    params.glossyExponent = 8.0f;
    params.glossyWeight = 0.2f;
    const LightSet lights = defaultLightSet(f.scene);
    setWorkerCount(1);
    auto one =
        shadeFromCaches(f.scene, *f.rays, f.bake, values, lights, f.scene.cameras.at(0), params);
    setWorkerCount(0);
    auto all =
        shadeFromCaches(f.scene, *f.rays, f.bake, values, lights, f.scene.cameras.at(0), params);
    ASSERT_TRUE(one.has_value() && all.has_value());
    double sum = 0.0;
    for (size_t i = 0; i < one->pixels.size(); ++i) {
        for (int c = 0; c < 3; ++c) {
            EXPECT_EQ(one->pixels[i][c], all->pixels[i][c]) << "pixel " << i;
            EXPECT_TRUE(std::isfinite(one->pixels[i][c]) && one->pixels[i][c] >= 0.0f)
                << "pixel " << i;
            sum += one->pixels[i][c];
        }
    }
    EXPECT_GT(sum, 0.0);
}

TEST(CacheShading, RejectsValuesAndParametersThatDoNotFit) {
    const test::BakedScene& f = cornell();
    ASSERT_TRUE(f.rays);
    const LightSet lights = defaultLightSet(f.scene);
    const Camera& camera = f.scene.cameras.at(0);
    ShadeParams params;
    params.width = 8;
    params.height = 8;
    const CacheValues wrongCount =
        CacheValues::zeros(f.bake.caches.size() + 1, f.bake.params.bandsY, f.bake.params.bandsC);
    auto bad = shadeFromCaches(f.scene, *f.rays, f.bake, wrongCount, lights, camera, params);
    ASSERT_FALSE(bad.has_value());
    EXPECT_EQ(bad.error().code, ErrorCode::InvalidInput);
    EXPECT_NE(bad.error().message.find(std::to_string(f.bake.caches.size())), std::string::npos)
        << bad.error().message;

    const CacheValues values = constantValues(f.bake, 1.0f);
    ShadeParams zero = params;
    zero.width = 0;
    EXPECT_FALSE(
        shadeFromCaches(f.scene, *f.rays, f.bake, values, lights, camera, zero).has_value());
    ShadeParams negativeGloss = params;
    negativeGloss.glossyExponent = -2.0f;
    EXPECT_FALSE(shadeFromCaches(f.scene, *f.rays, f.bake, values, lights, camera, negativeGloss)
                     .has_value());
    ShadeParams noSamples = params;
    noSamples.samplesPerPixel = 0;
    EXPECT_FALSE(
        shadeFromCaches(f.scene, *f.rays, f.bake, values, lights, camera, noSamples).has_value());
    BakeData otherScene = f.bake;
    otherScene.sceneHash ^= 1;
    auto mismatch = shadeFromCaches(f.scene, *f.rays, otherScene, values, lights, camera, params);
    ASSERT_FALSE(mismatch.has_value());
    EXPECT_NE(mismatch.error().message.find("different scene"), std::string::npos);
}

}  // namespace
}  // namespace pic
