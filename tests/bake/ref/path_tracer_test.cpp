// The reference path tracer against analytic answers: a white furnace (components and bounce
// limits), lamps near the wall of a closed sphere (uniform indirect light), point, spot and
// directional lights over a plane, a square emitter's view factor, determinism, and the
// ideal caches of a furnace.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "bake/ref/path_tracer.h"
#include "bake/ref/probes.h"
#include "core/color.h"
#include "core/geometry.h"
#include "core/gltf_loader.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "core/image.h"
#include "core/sh.h"
#include "core/sky.h"
#include "rays/embree_scene.h"
#include "tests/support/baked_scene.h"
#include "tests/support/command.h"
#include "tests/support/lights.h"

namespace pic {
namespace {

constexpr double kPi = std::numbers::pi;
using Component = PathTraceParams::Component;

/// Builds small scenes directly as Scene structs.
class SceneBuilder {
public:
    /// A material with albedo `albedo` and emitted radiance `emission`; returns its index.
    uint32_t material(const std::string& name, glm::vec3 albedo,
                      glm::vec3 emission = glm::vec3(0.0f)) {
        Material m;
        m.name = name;
        m.baseColorFactor = glm::vec4(albedo, 1.0f);
        m.emission = emission;
        mScene.materials.push_back(m);
        return uint32_t(mScene.materials.size() - 1);
    }

    /// A square of side 2·halfSize centred at `center` whose counter-clockwise normal (its
    /// emitting side) is `normal`.
    void square(glm::vec3 center, glm::vec3 normal, float halfSize, uint32_t material) {
        glm::vec3 u, v;
        orthonormalBasis(normal, u, v);
        if (glm::dot(glm::cross(u, v), normal) < 0.0f) std::swap(u, v);
        u *= halfSize;
        v *= halfSize;
        uint32_t base = uint32_t(mScene.vertices.size());
        for (glm::vec3 corner : {center - u - v, center + u - v, center + u + v, center - u + v}) {
            Vertex vertex;
            vertex.position = corner;
            vertex.normal = normal;
            mScene.vertices.push_back(vertex);
            mScene.bounds.extend(corner);
        }
        mScene.triangles.push_back({{base, base + 1, base + 2}, material, 0});
        mScene.triangles.push_back({{base, base + 2, base + 3}, material, 0});
    }

    /// One triangle, counter-clockwise as given.
    void triangle(glm::vec3 a, glm::vec3 b, glm::vec3 c, uint32_t material) {
        uint32_t base = uint32_t(mScene.vertices.size());
        for (glm::vec3 corner : {a, b, c}) {
            Vertex vertex;
            vertex.position = corner;
            mScene.vertices.push_back(vertex);
            mScene.bounds.extend(corner);
        }
        mScene.triangles.push_back({{base, base + 1, base + 2}, material, 0});
    }

    Scene build() {
        for (uint32_t t = 0; t < mScene.triangles.size(); ++t)
            mScene.totalArea += mScene.triangleArea(t);
        mScene.sourcePath = "hand-built";
        return std::move(mScene);
    }

private:
    Scene mScene;
};

/// White furnace: a closed cube [−1, 1]³ whose inner faces all have albedo ρ and emit L_e.
constexpr glm::vec3 kFurnaceAlbedo{0.5f, 0.6f, 0.3f};
constexpr glm::vec3 kFurnaceEmission{1.0f, 0.5f, 2.0f};

Scene furnaceScene() {
    SceneBuilder builder;
    uint32_t wall = builder.material("wall", kFurnaceAlbedo, kFurnaceEmission);
    for (int axis = 0; axis < 3; ++axis)
        for (float side : {-1.0f, 1.0f}) {
            glm::vec3 center(0.0f);
            center[axis] = side;
            builder.square(center, -center, 1.0f, wall);  // facing inwards
        }
    return builder.build();
}

/// Radiance the furnace delivers to any point by paths of k reflections, k in [minK, maxK].
glm::dvec3 furnaceRadiance(int minK, int maxK) {
    glm::dvec3 sum(0.0);
    for (int k = minK; k <= maxK; ++k)
        sum += glm::dvec3(kFurnaceEmission) * glm::pow(glm::dvec3(kFurnaceAlbedo), glm::dvec3(k));
    return sum;
}
/// All of it: Σ_k ρ^k L_e = L_e / (1 − ρ).
glm::dvec3 furnaceRadianceTotal() {
    return glm::dvec3(kFurnaceEmission) / (1.0 - glm::dvec3(kFurnaceAlbedo));
}

/// Mean and standard error of the mean over an image's pixels, per channel. Every pixel of
/// the analytic set-ups has the same expectation, so pixels are independent samples of it.
struct PixelStatistics {
    glm::dvec3 mean{0.0};
    glm::dvec3 standardError{0.0};
};
PixelStatistics pixelStatistics(const Image& image) {
    PixelStatistics s;
    glm::dvec3 sum(0.0), sumSquares(0.0);
    for (const glm::vec3& p : image.pixels) {
        sum += glm::dvec3(p);
        sumSquares += glm::dvec3(p) * glm::dvec3(p);
    }
    double n = double(image.pixels.size());
    s.mean = sum / n;
    glm::dvec3 variance =
        glm::max(sumSquares / n - s.mean * s.mean, glm::dvec3(0.0)) * (n / (n - 1.0));
    s.standardError = glm::sqrt(variance / n);
    return s;
}

/// The estimate lies within 4.5 standard errors of the truth, and is precise to `precision`
/// (relative) so that the check means something.
void expectConverged(const PixelStatistics& s, const glm::dvec3& expected, double precision,
                     const std::string& what) {
    for (int c = 0; c < 3; ++c) {
        EXPECT_LT(s.standardError[c], precision * expected[c]) << what << " channel " << c;
        EXPECT_NEAR(s.mean[c], expected[c], 4.5 * s.standardError[c] + 1e-6)
            << what << " channel " << c;
    }
}

void expectValid(const Image& image) {
    for (const glm::vec3& p : image.pixels)
        ASSERT_TRUE(isValidRadiance(p)) << p.x << " " << p.y << " " << p.z;
}

Camera furnaceCamera() {
    Camera camera;
    camera.eye = {0.1f, -0.2f, 0.3f};
    camera.target = {0.6f, 0.3f, -1.0f};
    camera.up = {0.0f, 1.0f, 0.0f};
    camera.fovyDegrees = 100.0f;
    return camera;
}

class PathTracerTest : public ::testing::Test {
protected:
    void SetUp() override { Progress::setEnabled(false); }

    /// Renders `scene` and checks the image has no invalid pixel and no sample was rejected.
    Image render(const Scene& scene, const LightSet& lights, const Camera& camera,
                 PathTraceParams params) {
        auto rays = EmbreeScene::create(scene);
        EXPECT_TRUE(rays.has_value());
        if (!rays) return {};
        PathTraceStats stats;
        auto image = pathTrace(scene, **rays, lights, camera, params, &stats);
        EXPECT_TRUE(image.has_value()) << image.error().message;
        if (!image) return {};
        EXPECT_EQ(stats.samples, uint64_t(params.width) * params.height * params.spp);
        EXPECT_EQ(stats.rejected, 0u);
        expectValid(*image);
        return std::move(*image);
    }

    static PathTraceParams params(uint32_t size, uint32_t spp, Component component,
                                  int bounces = -1) {
        PathTraceParams p;
        p.width = size;
        p.height = size;
        p.spp = spp;
        p.component = component;
        p.bounces = bounces;
        p.seed = 7;
        return p;
    }
};

TEST_F(PathTracerTest, WhiteFurnaceConvergesToEmissionOverOneMinusAlbedo) {
    // Full: Σ_k ρ^k L_e = L_e / (1 − ρ) wherever one looks in a closed furnace.
    Scene scene = furnaceScene();
    Image image = render(scene, LightSet{}, furnaceCamera(), params(32, 64, Component::Full));
    expectConverged(pixelStatistics(image), furnaceRadianceTotal(), 0.005, "full");
}

TEST_F(PathTracerTest, WhiteFurnaceComponentsSplitByReflectionCount) {
    // Direct: exactly one reflection, ρ·L_e. Indirect: two or more, L_e/(1 − ρ) − L_e − ρ·L_e
    // = ρ²·L_e/(1 − ρ). Neither sees the emitting walls themselves.
    Scene scene = furnaceScene();
    Image direct = render(scene, LightSet{}, furnaceCamera(), params(32, 32, Component::Direct));
    expectConverged(pixelStatistics(direct), furnaceRadiance(1, 1), 0.005, "direct");
    Image indirect =
        render(scene, LightSet{}, furnaceCamera(), params(32, 64, Component::Indirect));
    glm::dvec3 expected = furnaceRadianceTotal() - glm::dvec3(kFurnaceEmission) -
                          glm::dvec3(kFurnaceAlbedo) * glm::dvec3(kFurnaceEmission);
    expectConverged(pixelStatistics(indirect), expected, 0.01, "indirect");
}

TEST_F(PathTracerTest, CachedIsWhatTheCachesCarryTheEmittersFirstReflectionAndTheRest) {
    // In the furnace every light is an emitting surface: Cached keeps paths of k ≥ 1
    // reflections, L_e/(1 − ρ) − L_e = ρ·L_e/(1 − ρ).
    Scene scene = furnaceScene();
    Image cached = render(scene, LightSet{}, furnaceCamera(), params(32, 64, Component::Cached));
    expectConverged(pixelStatistics(cached), furnaceRadianceTotal() - glm::dvec3(kFurnaceEmission), 0.005,
                    "cached");
}

TEST_F(PathTracerTest, CachedLeavesOutThePunctualLightsReflectedOnce) {
    // Where no surface emits, Cached and Indirect are the same paths, sampled alike: the same
    // image to the bit. A plane under a lamp reflects nothing back onto itself: black.
    Scene scene = furnaceScene();
    for (Material& m : scene.materials) m.emission = glm::vec3(0.0f);
    LightSet lights;
    lights.lights.push_back(test::pointLight({0.1f, 0.2f, 0.0f}, 2.0f, glm::vec3(1.0f)));
    Image cached = render(scene, lights, furnaceCamera(), params(8, 16, Component::Cached));
    Image indirect = render(scene, lights, furnaceCamera(), params(8, 16, Component::Indirect));
    ASSERT_EQ(cached.pixels.size(), indirect.pixels.size());
    double sum = 0.0;
    for (size_t i = 0; i < cached.pixels.size(); ++i) {
        EXPECT_EQ(cached.pixels[i], indirect.pixels[i]) << i;
        sum += cached.pixels[i].r;
    }
    EXPECT_GT(sum, 0.0);
}

// The normalised Phong lobe's sampler: E[cos α] = ∫ cos α · (n+1)/(2π) cos^n α dω =
// (n+1)/(n+2), E[cos² α] = (n+1)/(n+3), and no direction leaves the lobe's hemisphere.
TEST(PhongLobe, SamplesHaveTheLobesMoments) {
    const glm::vec3 axis = glm::normalize(glm::vec3(0.3f, -0.5f, 0.8f));
    for (const float n : {1.0f, 10.0f, 30.0f}) {
        Rng rng(3, uint64_t(n));
        constexpr int kSamples = 200000;
        double first = 0.0, second = 0.0;
        for (int i = 0; i < kSamples; ++i) {
            const float u1 = rng.uniform(), u2 = rng.uniform();
            const glm::vec3 w = samplePhongLobe(axis, n, u1, u2);
            ASSERT_NEAR(glm::length(w), 1.0f, 1e-5f);
            const double c = glm::dot(w, axis);
            ASSERT_GE(c, -1e-6);
            first += c;
            second += c * c;
        }
        EXPECT_NEAR(first / kSamples, (n + 1.0) / (n + 2.0), 2e-3) << n;
        EXPECT_NEAR(second / kSamples, (n + 1.0) / (n + 3.0), 3e-3) << n;
    }
}

TEST_F(PathTracerTest, GlossyLobeInTheFurnaceIsItsWeightTimesTheRadiance) {
    // Every direction above a furnace wall brings L_e/(1 − ρ). Seen nearly head-on (a narrow
    // view at the far wall), the whole lobe of exponent 20 lies above the surface (its part
    // more than 76° from the mirror direction is below 10⁻¹²), so the lobe's term is
    // w·L_e/(1 − ρ). Full adds it to what the camera sees without a lobe.
    Scene scene = furnaceScene();
    Camera camera;
    camera.eye = {0.0f, 0.0f, 0.9f};
    camera.target = {0.0f, 0.0f, -1.0f};
    camera.fovyDegrees = 20.0f;
    PathTraceParams glossy = params(24, 32, Component::Glossy);
    glossy.glossyExponent = 20.0f;
    glossy.glossyWeight = 0.5f;
    Image lobe = render(scene, LightSet{}, camera, glossy);
    expectConverged(pixelStatistics(lobe), 0.5 * furnaceRadianceTotal(), 0.005, "glossy");
    PathTraceParams full = glossy;
    full.component = Component::Full;
    Image both = render(scene, LightSet{}, camera, full);
    expectConverged(pixelStatistics(both), 1.5 * furnaceRadianceTotal(), 0.005, "full + glossy");
    // The glossy component needs a lobe.
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays);
    PathTraceParams noLobe = glossy;
    noLobe.glossyWeight = 0.0f;
    auto refused = pathTrace(scene, **rays, LightSet{}, camera, noLobe);
    ASSERT_FALSE(refused);
    EXPECT_EQ(refused.error().code, ErrorCode::InvalidInput);
    EXPECT_NE(refused.error().message.find("needs a lobe"), std::string::npos);
}

TEST_F(PathTracerTest, BounceLimitKeepsPathsOfAtMostBPlusOneReflections) {
    // --bounces B: the camera-visible surface's reflection plus up to B more.
    Scene scene = furnaceScene();
    for (int bounces : {0, 1, 3}) {
        Image full =
            render(scene, LightSet{}, furnaceCamera(), params(24, 32, Component::Full, bounces));
        expectConverged(pixelStatistics(full), furnaceRadiance(0, bounces + 1), 0.005,
                        "full, bounces " + std::to_string(bounces));
    }
    Image indirect =
        render(scene, LightSet{}, furnaceCamera(), params(24, 32, Component::Indirect, 1));
    expectConverged(pixelStatistics(indirect), furnaceRadiance(2, 2), 0.01, "indirect, bounces 1");
    // With no bounce there is no indirect light at all: exactly zero, not just small.
    Image none = render(scene, LightSet{}, furnaceCamera(), params(8, 4, Component::Indirect, 0));
    for (const glm::vec3& p : none.pixels) EXPECT_EQ(p, glm::vec3(0.0f));
}

using test::pointLight;

/// A closed sphere of radius 1 about the origin (an icosahedron subdivided `levels` times,
/// vertices pushed onto the sphere) of albedo ρ.
constexpr glm::vec3 kSphereAlbedo{0.5f, 0.7f, 0.3f};
Scene sphereScene(int levels) {
    SceneBuilder builder;
    uint32_t wall = builder.material("wall", kSphereAlbedo);
    const float g = (1.0f + std::sqrt(5.0f)) / 2.0f;
    std::vector<glm::vec3> v = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0},
                                {0, -1, g}, {0, 1, g}, {0, -1, -g}, {0, 1, -g},
                                {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
    for (glm::vec3& p : v) p = glm::normalize(p);
    std::vector<glm::uvec3> faces = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                     {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                     {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                     {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
    std::vector<std::array<glm::vec3, 3>> triangles;
    for (const glm::uvec3& f : faces) triangles.push_back({v[f.x], v[f.y], v[f.z]});
    for (int level = 0; level < levels; ++level) {
        std::vector<std::array<glm::vec3, 3>> finer;
        for (const auto& [a, b, c] : triangles) {
            // Midpoints depend only on the (commutative) sum, so shared edges stay watertight.
            glm::vec3 ab = glm::normalize(a + b), bc = glm::normalize(b + c),
                      ca = glm::normalize(c + a);
            finer.push_back({a, ab, ca});
            finer.push_back({ab, b, bc});
            finer.push_back({ca, bc, c});
            finer.push_back({ab, bc, ca});
        }
        triangles = std::move(finer);
    }
    for (const auto& [a, b, c] : triangles) builder.triangle(a, b, c, wall);
    return builder.build();
}

TEST_F(PathTracerTest, LampNearTheWallOfASphereGivesUniformIndirectLight) {
    // Inside a sphere of radius R every surface element sees any other with the form factor
    // dA'/(4πR²), so light reflected once is spread evenly whatever its first distribution:
    // a light of flux Φ anywhere inside gives every wall point the indirect radiance (paths of
    // ≥ 2 reflections) ρ²·Φ / (4π²·R²·(1 − ρ)). With the lamps 5 cm under the wall their
    // bright spots test the light-vertex strategy and its MIS weights.
    Scene scene = sphereScene(4);  // 5120 facets: within 0.1 % of a sphere's answer (3: 0.5 %)
    Camera camera;
    camera.eye = {0.2f, -0.3f, 0.1f};
    camera.target = {0.0f, 0.5f, -1.0f};
    camera.fovyDegrees = 120.0f;
    glm::dvec3 rho(kSphereAlbedo);

    // A point light: Φ = 4π·I.
    LightSet point;
    point.lights.push_back(pointLight({0.0f, 0.95f, 0.0f}, 2.0f, glm::vec3(1.0f)));
    Image pointImage = render(scene, point, camera, params(32, 64, Component::Indirect));
    expectConverged(pixelStatistics(pointImage), rho * rho * 2.0 / (kPi * (1.0 - rho)), 0.01,
                    "point");

    // A tilted spot with cones 20° / 40°: Φ = 2π·I·((1 − cos inner) + (cos inner − cos outer)/3)
    // with the squared linear ramp of the falloff.
    const double inner = 20.0 * kPi / 180.0, outer = 40.0 * kPi / 180.0;
    LightSet spot;
    Light light = pointLight({0.0f, 0.9f, 0.0f}, 3.0f, glm::vec3(1.0f, 0.5f, 0.25f));
    light.type = LightType::Spot;
    light.direction = glm::normalize(glm::vec3(0.3f, 1.0f, 0.0f));
    light.innerConeAngle = float(inner);
    light.outerConeAngle = float(outer);
    spot.lights.push_back(light);
    double flux =
        2.0 * kPi * 3.0 * ((1.0 - std::cos(inner)) + (std::cos(inner) - std::cos(outer)) / 3.0);
    glm::dvec3 expected =
        glm::dvec3(light.color) * rho * rho * flux / (4.0 * kPi * kPi * (1.0 - rho));
    Image spotImage = render(scene, spot, camera, params(32, 64, Component::Indirect));
    expectConverged(pixelStatistics(spotImage), expected, 0.01, "spot");
}

/// A 200 m square plane of albedo ρ at y = 0 facing +y.
constexpr glm::vec3 kPlaneAlbedo{0.6f, 0.4f, 0.8f};
Scene planeScene(SceneBuilder builder = {}) {
    uint32_t floor = builder.material("floor", kPlaneAlbedo);
    builder.square(glm::vec3(0.0f), glm::vec3(0.0f, 1.0f, 0.0f), 100.0f, floor);
    return builder.build();
}

TEST_F(PathTracerTest, PointLightAbovePlaneGivesAlbedoIntensityOverPiDistanceSquared) {
    // Radiance straight below a point light of intensity I at height d: ρ·I / (π·d²).
    constexpr float kIntensity = 5.0f, kHeight = 2.0f;
    const glm::vec3 color{1.0f, 0.8f, 0.5f};
    Scene scene = planeScene();
    LightSet lights;
    lights.lights.push_back(pointLight({0.0f, kHeight, 0.0f}, kIntensity, color));
    // A 0.1° view of the point below the light from 5 m above: the pixels see it within 7 mm,
    // where cos³θ (θ < 0.0035 rad from the light's axis) differs from 1 by less than 2e-5.
    Camera camera;
    camera.eye = {0.0f, 5.0f, 0.0f};
    camera.target = {0.0f, 0.0f, 0.0f};
    camera.up = {0.0f, 0.0f, -1.0f};
    camera.fovyDegrees = 0.1f;
    glm::dvec3 expected =
        glm::dvec3(kPlaneAlbedo * color) * double(kIntensity) / (kPi * kHeight * kHeight);
    for (Component component : {Component::Full, Component::Direct}) {
        Image image = render(scene, lights, camera, params(3, 4, component));
        for (const glm::vec3& p : image.pixels)
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(p[c], expected[c], 1e-4 * expected[c]);
    }
    // A lone plane reflects nothing back onto itself.
    Image indirect = render(scene, lights, camera, params(3, 16, Component::Indirect));
    for (const glm::vec3& p : indirect.pixels) EXPECT_EQ(p, glm::vec3(0.0f));
}

TEST_F(PathTracerTest, OccluderCastsAShadow) {
    // A 0.4 m square halfway between the lamp and the floor: the point below gets no direct
    // light, while a point far outside the shadow gets ρ·I·cos³θ/(π·d²).
    SceneBuilder builder;
    uint32_t blocker = builder.material("blocker", glm::vec3(0.5f));
    builder.square({0.0f, 1.0f, 0.0f}, {0.0f, -1.0f, 0.0f}, 0.2f, blocker);
    Scene scene = planeScene(builder);
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays);
    LightSet lights;
    lights.lights.push_back(pointLight({0.0f, 2.0f, 0.0f}, 3.0f, glm::vec3(1.0f)));
    PathTracer tracer(scene, **rays, lights);
    Rng rng(1);
    glm::vec3 down(0.0f, -1.0f, 0.0f);
    glm::vec3 shadowed = tracer.traceRadiance({0.0f, 0.5f, 0.0f}, down, -1, Component::Direct, rng);
    EXPECT_EQ(shadowed, glm::vec3(0.0f));
    glm::vec3 lit = tracer.traceRadiance({2.0f, 0.5f, 0.0f}, down, -1, Component::Direct, rng);
    double cosTheta = 2.0 / std::sqrt(8.0);
    double expected = 3.0 * std::pow(cosTheta, 3) / (kPi * 4.0);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(lit[c], kPlaneAlbedo[c] * expected, 1e-5);
}

TEST_F(PathTracerTest, SpotLightFollowsItsConeAndSmoothFalloff) {
    // Spot at height d pointing down, cones 20° / 30°: inside the inner cone it is a point
    // light, outside the outer one dark, in between the KHR_lights_punctual falloff
    // ((cosθ − cos outer)/(cos inner − cos outer))².
    constexpr double kHeight = 1.0, kIntensity = 4.0;
    const double inner = 20.0 * kPi / 180.0, outer = 30.0 * kPi / 180.0;
    Scene scene = planeScene();
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays);
    LightSet lights;
    Light spot = pointLight({0.0f, float(kHeight), 0.0f}, float(kIntensity), glm::vec3(1.0f));
    spot.type = LightType::Spot;
    spot.direction = {0.0f, -1.0f, 0.0f};
    spot.innerConeAngle = float(inner);
    spot.outerConeAngle = float(outer);
    lights.lights.push_back(spot);
    PathTracer tracer(scene, **rays, lights);
    Rng rng(3);
    for (double degrees : {0.0, 10.0, 19.0, 22.0, 25.0, 28.0, 31.0, 40.0}) {
        double theta = degrees * kPi / 180.0;
        double cosTheta = std::cos(theta);
        double ramp = std::clamp((cosTheta - std::cos(outer)) / (std::cos(inner) - std::cos(outer)),
                                 0.0, 1.0);
        double expected =
            kIntensity * std::pow(cosTheta, 3) / (kPi * kHeight * kHeight) * ramp * ramp;
        glm::vec3 origin(float(kHeight * std::tan(theta)), 0.5f, 0.0f);
        glm::vec3 radiance =
            tracer.traceRadiance(origin, {0.0f, -1.0f, 0.0f}, -1, Component::Full, rng);
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(radiance[c], kPlaneAlbedo[c] * expected, 2e-4 * expected + 1e-7)
                << degrees << "° channel " << c;
    }
}

TEST_F(PathTracerTest, DirectionalLightGivesAlbedoIrradianceCosineOverPi) {
    // Sun of irradiance E at 60° from the zenith: ρ·E·cos60°/π on the lit side; the plane's
    // back is shaded with its normal flipped towards the viewer, which faces away from the sun.
    constexpr double kIrradiance = 3.0;
    const double zenith = 60.0 * kPi / 180.0;
    Scene scene = planeScene();
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays);
    LightSet lights;
    Light sun;
    sun.id = "sun";
    sun.type = LightType::Directional;
    sun.direction =
        glm::normalize(glm::vec3(float(std::sin(zenith)), -float(std::cos(zenith)), 0.0f));
    sun.intensity = float(kIrradiance);
    lights.lights.push_back(sun);
    PathTracer tracer(scene, **rays, lights);
    Rng rng(5);
    glm::vec3 above = tracer.traceRadiance(
        {1.0f, 3.0f, 2.0f}, glm::normalize(glm::vec3(0.3f, -1.0f, 0.1f)), -1, Component::Full, rng);
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(above[c], kPlaneAlbedo[c] * kIrradiance * std::cos(zenith) / kPi, 1e-5);
    glm::vec3 below =
        tracer.traceRadiance({1.0f, -3.0f, 2.0f}, {0.0f, 1.0f, 0.0f}, -1, Component::Full, rng);
    EXPECT_EQ(below, glm::vec3(0.0f));
}

TEST_F(PathTracerTest, SquareEmitterLightsThePlaneByItsViewFactor) {
    // A black square emitter of side s at height h facing down over the plane: the point below
    // its centre receives E = π·L·F with the view factor F of four s/2 × s/2 rectangles sharing
    // the corner above the point, so its radiance is ρ·L·F. This checks next-event estimation
    // of emitters and its MIS pairing with BSDF sampling.
    constexpr double kSide = 0.5, kHeight = 1.0, kEmission = 4.0;
    SceneBuilder builder;
    uint32_t panel = builder.material("panel", glm::vec3(0.0f), glm::vec3(float(kEmission)));
    builder.square({0.0f, float(kHeight), 0.0f}, {0.0f, -1.0f, 0.0f}, float(kSide / 2), panel);
    Scene scene = planeScene(builder);
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays);
    PathTracer tracer(scene, **rays, LightSet{});
    ASSERT_EQ(tracer.emitterCount(), 2u);

    double a = kSide / 2 / kHeight;  // both sides of each corner rectangle, over h
    double root = std::sqrt(1.0 + a * a);
    double cornerFactor = (2.0 * a / root * std::atan(a / root)) / (2.0 * kPi);
    double expected = kEmission * 4.0 * cornerFactor;

    constexpr int kSamples = 40000;
    glm::dvec3 sum(0.0), sumSquares(0.0);
    glm::vec3 origin(0.0f, 0.5f, 0.0f), down(0.0f, -1.0f, 0.0f);
    for (int i = 0; i < kSamples; ++i) {
        Rng rng(11, uint64_t(i));
        glm::dvec3 radiance(tracer.traceRadiance(origin, down, -1, Component::Direct, rng));
        sum += radiance;
        sumSquares += radiance * radiance;
    }
    glm::dvec3 mean = sum / double(kSamples);
    glm::dvec3 standardError =
        glm::sqrt((sumSquares / double(kSamples) - mean * mean) / double(kSamples));
    for (int c = 0; c < 3; ++c) {
        EXPECT_LT(standardError[c], 0.01 * kPlaneAlbedo[c] * expected);
        EXPECT_NEAR(mean[c], kPlaneAlbedo[c] * expected, 4.5 * standardError[c]) << "channel " << c;
    }

    // The panel emits from its front only, reflects nothing, and is seen only in `full`.
    Rng rng(2);
    glm::vec3 up(0.0f, 1.0f, 0.0f);
    EXPECT_EQ(tracer.traceRadiance(origin, up, -1, Component::Full, rng),
              glm::vec3(float(kEmission)));
    EXPECT_EQ(tracer.traceRadiance(origin, up, -1, Component::Direct, rng), glm::vec3(0.0f));
    EXPECT_EQ(tracer.traceRadiance({0.0f, 2.0f, 0.0f}, down, -1, Component::Full, rng),
              glm::vec3(0.0f));
}

TEST_F(PathTracerTest, ImagesDependOnTheSeedOnlyNotOnThreads) {
    auto scene = loadScene(test::testScenePath("cornell"));
    ASSERT_TRUE(scene) << scene.error().message;
    auto camera = sceneCamera(*scene, 0);
    ASSERT_TRUE(camera) << camera.error().message;
    LightSet lights = defaultLightSet(*scene);
    PathTraceParams p = params(24, 4, Component::Full);
    setWorkerCount(1);
    Image one = render(*scene, lights, *camera, p);
    setWorkerCount(2);
    Image two = render(*scene, lights, *camera, p);
    p.seed += 1;
    Image other = render(*scene, lights, *camera, p);
    setWorkerCount(0);
    ASSERT_EQ(one.pixels.size(), two.pixels.size());
    EXPECT_TRUE(one.pixels == two.pixels);
    EXPECT_FALSE(one.pixels == other.pixels);
    double sum = 0.0;
    for (const glm::vec3& px : one.pixels) sum += luminance(px);
    EXPECT_GT(sum, 0.0);
}

TEST_F(PathTracerTest, RejectsEmptySizesAndBadBounces) {
    Scene scene = furnaceScene();
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays);
    PathTraceParams p = params(0, 1, Component::Full);
    EXPECT_FALSE(pathTrace(scene, **rays, LightSet{}, furnaceCamera(), p));
    p = params(4, 0, Component::Full);
    EXPECT_FALSE(pathTrace(scene, **rays, LightSet{}, furnaceCamera(), p));
    p = params(4, 1, Component::Full, -2);
    auto bad = pathTrace(scene, **rays, LightSet{}, furnaceCamera(), p);
    ASSERT_FALSE(bad);
    EXPECT_EQ(bad.error().code, ErrorCode::InvalidInput);
    EXPECT_NE(bad.error().message.find("-2"), std::string::npos);
}

/// A bake holding only caches, enough for pathTraceProbes.
BakeData cachesOnly(const std::vector<Cache>& caches, uint32_t bandsY, uint32_t bandsC) {
    BakeData bake;
    bake.params.bandsY = bandsY;
    bake.params.bandsC = bandsC;
    bake.caches = caches;
    return bake;
}

TEST_F(PathTracerTest, FurnaceProbesHoldTheConstantRadiance) {
    // Constant radiance L over the sphere projects to L·4π·y_0^0 = 2√π·L in band 0 and zero
    // above. Over the upper hemisphere around n (lower half zero): √π·L in band 0,
    // π·sqrt(3/(4π))·L on band 1's component along n, and zero in band 2 (∫₀¹ P₂ = 0).
    Scene scene = furnaceScene();
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays);
    std::vector<Cache> caches;
    for (glm::vec3 p :
         {glm::vec3(0.0f), glm::vec3(0.5f, -0.3f, 0.2f), glm::vec3(-0.7f, 0.6f, -0.8f)})
        caches.push_back(Cache{p, gpu::kCacheKindGrid, glm::vec3(0.0f), 0});
    const float lift = 10.0f * (*rays)->epsilon();
    caches.push_back(
        Cache{{0.2f, -1.0f + lift, 0.1f}, gpu::kCacheKindLightmap, {0.0f, 1.0f, 0.0f}, 0});
    BakeData bake = cachesOnly(caches, 3, 2);
    ProbeParams params;
    params.samples = 4096;
    PathTraceStats stats;
    auto values = pathTraceProbes(scene, **rays, bake, LightSet{}, params, &stats);
    ASSERT_TRUE(values) << values.error().message;
    ASSERT_EQ(values->cacheCount(), caches.size());
    EXPECT_EQ(stats.samples, caches.size() * params.samples);
    EXPECT_EQ(stats.rejected, 0u);

    const glm::vec3 radiance = rgbToYCoCg(glm::vec3(furnaceRadianceTotal()));
    const double sqrtPi = std::sqrt(kPi);
    // Measured over 32 caches at 4096 directions: band 0 scatters by 0.4 % (Y) to 0.5 % (Co)
    // relative, the other coefficients by at most 1.5 % of band 0; the tolerances are 5σ+.
    constexpr double kBand0Tolerance = 0.025, kTolerance = 0.03;
    for (size_t c = 0; c < caches.size(); ++c) {
        const bool hemisphere = caches[c].kind == gpu::kCacheKindLightmap;
        const float* y = &values->y[c * 9];
        const float* co = &values->co[c * 4];
        const float* cg = &values->cg[c * 4];
        const double band0 = hemisphere ? sqrtPi : 2.0 * sqrtPi;
        std::string what = "cache " + std::to_string(c);
        EXPECT_NEAR(y[0], band0 * radiance.x, kBand0Tolerance * band0 * radiance.x) << what;
        EXPECT_NEAR(co[0], band0 * radiance.y, kBand0Tolerance * band0 * std::abs(radiance.y))
            << what;
        EXPECT_NEAR(cg[0], band0 * radiance.z, kBand0Tolerance * band0 * std::abs(radiance.z))
            << what;
        // Index 1 is band 1's y component (core/sh.h), the hemisphere's axis.
        const double band1AlongNormal = hemisphere ? kPi * std::sqrt(3.0 / (4.0 * kPi)) : 0.0;
        for (int j : {1, 2, 3}) {
            const double factor = j == 1 ? band1AlongNormal : 0.0;
            EXPECT_NEAR(y[j], factor * radiance.x, kTolerance * band0 * radiance.x)
                << what << " y " << j;
            EXPECT_NEAR(co[j], factor * radiance.y, kTolerance * band0 * std::abs(radiance.y))
                << what << " co " << j;
            EXPECT_NEAR(cg[j], factor * radiance.z, kTolerance * band0 * std::abs(radiance.z))
                << what << " cg " << j;
        }
        for (int j : {4, 5, 6, 7, 8})
            EXPECT_NEAR(y[j], 0.0, kTolerance * band0 * radiance.x) << what << " coefficient " << j;
    }
}

TEST_F(PathTracerTest, ProbesWithPunctualLightsAddTheirDeltas) {
    // Over the lone plane with a point light straight above a grid cache: with the lights
    // included the SH gains E·y(ω_light) with E = I/d², on top of the floor's reflection.
    Scene scene = planeScene();
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays);
    LightSet lights;
    lights.lights.push_back(pointLight({0.0f, 2.0f, 0.0f}, 8.0f, glm::vec3(1.0f)));
    BakeData bake =
        cachesOnly({Cache{{0.0f, 1.0f, 0.0f}, gpu::kCacheKindGrid, glm::vec3(0.0f), 0}}, 2, 1);
    ProbeParams params;
    params.samples = 256;
    auto surfacesOnly = pathTraceProbes(scene, **rays, bake, lights, params);
    params.indirectOnly = false;
    auto withLights = pathTraceProbes(scene, **rays, bake, lights, params);
    ASSERT_TRUE(surfacesOnly && withLights);
    float basis[4];
    shEvaluate(2, {0.0f, 1.0f, 0.0f}, basis);
    const double irradiance = 8.0 / 1.0;  // I / d², d = 1 m
    for (int j = 0; j < 4; ++j)
        EXPECT_NEAR(withLights->y[j] - surfacesOnly->y[j], irradiance * basis[j], 1e-4) << j;
    // Sanity of the reflected part: the floor sits below, so the lower half dominates.
    EXPECT_LT(surfacesOnly->y[1], 0.0f);
}

TEST_F(PathTracerTest, ProbesRefuseABakeOfAnotherScene) {
    Scene scene = furnaceScene();
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays);
    BakeData bake =
        cachesOnly({Cache{glm::vec3(0.0f), gpu::kCacheKindGrid, glm::vec3(0.0f), 0}}, 3, 3);
    bake.sceneHash = 0x1234;
    auto values = pathTraceProbes(scene, **rays, bake, LightSet{}, ProbeParams{});
    ASSERT_FALSE(values);
    EXPECT_NE(values.error().message.find("1234"), std::string::npos);
}

// The sky (LightSet::sky): what escaping rays see, its next-event estimation and its
// importance sampling against analytic irradiance.

/// A constant sky of radiance `radiance` (W/(m²·sr)).
LightSet constantSky(glm::vec3 radiance) {
    LightSet lights;
    lights.sky = SkyLight{};
    lights.sky->color = radiance;
    lights.sky->intensity = 1.0f;
    return lights;
}

/// A 2 km square plane of albedo kPlaneAlbedo through the origin with unit normal `normal`:
/// seen from 1 m above its centre it covers all but 0.06° next to the horizon.
Scene largePlaneScene(glm::vec3 normal) {
    SceneBuilder builder;
    uint32_t floor = builder.material("floor", kPlaneAlbedo);
    builder.square(glm::vec3(0.0f), normal, 1000.0f, floor);
    return builder.build();
}

TEST_F(PathTracerTest, PlaneUnderConstantSkyReflectsAlbedoTimesSky) {
    // A plane open to a constant sky L gets the irradiance π·L and cannot see itself: its
    // radiance is ρ·L, all of it direct (one reflection), nothing indirect. The caches carry
    // the sky's first reflection, so Cached is ρ·L too. Cosine-weighted sky sampling and the
    // cosine-weighted continuation share each path half and half, so every sample is exact up
    // to round-off: the tolerance is round-off, not Monte Carlo.
    const glm::vec3 sky{0.8f, 1.0f, 1.5f};
    Scene scene = largePlaneScene({0.0f, 1.0f, 0.0f});
    LightSet lights = constantSky(sky);
    Camera camera;
    camera.eye = {0.0f, 1.5f, 0.0f};
    camera.target = {0.3f, 0.0f, -0.4f};
    camera.up = {0.0f, 0.0f, -1.0f};
    camera.fovyDegrees = 40.0f;
    const glm::dvec3 expected = glm::dvec3(kPlaneAlbedo) * glm::dvec3(sky);
    for (Component component : {Component::Full, Component::Direct, Component::Cached}) {
        Image image = render(scene, lights, camera, params(8, 8, component));
        for (const glm::vec3& p : image.pixels)
            for (int c = 0; c < 3; ++c)
                ASSERT_NEAR(p[c], expected[c], 1e-5 * expected[c]) << int(component) << " " << c;
    }
    for (int bounces : {0, 2}) {
        Image full = render(scene, lights, camera, params(4, 4, Component::Full, bounces));
        for (const glm::vec3& p : full.pixels)
            for (int c = 0; c < 3; ++c) ASSERT_NEAR(p[c], expected[c], 1e-5 * expected[c]);
    }
    Image indirect = render(scene, lights, camera, params(8, 8, Component::Indirect));
    for (const glm::vec3& p : indirect.pixels) EXPECT_EQ(p, glm::vec3(0.0f));

    // The glossy lobe sees the sky where it escapes: seen head-on, a lobe of exponent 20 lies
    // above the plane (all but 10⁻¹²), so its term is w·L.
    Camera down;
    down.eye = {0.0f, 2.0f, 0.0f};
    down.target = {0.0f, 0.0f, 0.0f};
    down.up = {0.0f, 0.0f, -1.0f};
    down.fovyDegrees = 10.0f;
    PathTraceParams glossy = params(4, 4, Component::Glossy);
    glossy.glossyExponent = 20.0f;
    glossy.glossyWeight = 0.5f;
    Image lobe = render(scene, lights, down, glossy);
    for (const glm::vec3& p : lobe.pixels)
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(p[c], 0.5f * sky[c], 1e-5f * sky[c]);

    // pic's images have no sky background: camera rays that escape are black.
    Camera up = camera;
    up.target = {0.3f, 3.0f, -0.4f};
    Image background = render(scene, lights, up, params(4, 4, Component::Full));
    for (const glm::vec3& p : background.pixels) EXPECT_EQ(p, glm::vec3(0.0f));
}

TEST_F(PathTracerTest, ClosedBoxUnderTheSkyIsDark) {
    // No ray from inside a closed box escapes: the sky adds nothing, not even noise.
    Scene scene = furnaceScene();
    for (Material& m : scene.materials) m.emission = glm::vec3(0.0f);
    Image image = render(scene, constantSky(glm::vec3(5.0f)), furnaceCamera(),
                         params(8, 8, Component::Full));
    for (const glm::vec3& p : image.pixels) EXPECT_EQ(p, glm::vec3(0.0f));
}

TEST_F(PathTracerTest, ProbesSeeTheSkyDirectly) {
    // A grid cache 1 m over the plane under a constant sky L: the upper hemisphere brings L,
    // the lower ρ·L. Band 0 holds √π·L·(1 + ρ); band 1 along +y, y_1 = √(3/(4π))·ω_y, holds
    // π·√(3/(4π))·L·(1 − ρ). Each hemisphere is constant and each sample exact (see above):
    // only the stratified directions' quadrature error remains.
    const glm::vec3 sky{1.0f, 2.0f, 0.5f};
    Scene scene = largePlaneScene({0.0f, 1.0f, 0.0f});
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays);
    BakeData bake =
        cachesOnly({Cache{{0.0f, 1.0f, 0.0f}, gpu::kCacheKindGrid, glm::vec3(0.0f), 0}}, 2, 2);
    ProbeParams params;
    params.samples = 4096;
    auto values = pathTraceProbes(scene, **rays, bake, constantSky(sky), params);
    ASSERT_TRUE(values) << values.error().message;
    const glm::dvec3 rho(kPlaneAlbedo);
    const glm::dvec3 band0 = std::sqrt(kPi) * glm::dvec3(sky) * (1.0 + rho);
    const glm::dvec3 band1 = kPi * std::sqrt(3.0 / (4.0 * kPi)) * glm::dvec3(sky) * (1.0 - rho);
    const glm::vec3 y0 = rgbToYCoCg(glm::vec3(band0)), y1 = rgbToYCoCg(glm::vec3(band1));
    EXPECT_NEAR(values->y[0], y0.x, 2e-3 * y0.x);
    EXPECT_NEAR(values->co[0], y0.y, 2e-3 * y0.x);
    EXPECT_NEAR(values->cg[0], y0.z, 2e-3 * y0.x);
    EXPECT_NEAR(values->y[1], y1.x, 2e-3 * y0.x);
    EXPECT_NEAR(values->co[1], y1.y, 2e-3 * y0.x);
    EXPECT_NEAR(values->cg[1], y1.z, 2e-3 * y0.x);
    for (int j : {2, 3}) EXPECT_NEAR(values->y[j], 0.0, 2e-3 * y0.x) << j;
}

/// Environment images written to a scratch folder, beside a scene file that need not exist.
class SkyEnvironmentTest : public PathTracerTest {
protected:
    /// A width × height environment of `background` radiance with `patch` over columns
    /// [x0, x1) and rows [y0, y1), written as `name` beside sceneFile().
    void writeEnvironment(const std::string& name, uint32_t width, uint32_t height,
                          glm::vec3 background, glm::vec3 patch, glm::uvec2 from, glm::uvec2 to) {
        Image image(width, height);
        for (uint32_t y = 0; y < height; ++y)
            for (uint32_t x = 0; x < width; ++x)
                image.at(x, y) = x >= from.x && x < to.x && y >= from.y && y < to.y ? patch
                                                                                   : background;
        auto written = writeImage((mDir / name).string(), image);
        ASSERT_TRUE(written) << written.error().message;
    }

    std::string sceneFile() const { return (mDir / "scene.gltf").string(); }

    test::ScratchDir mDir{"path_tracer_sky"};
};

/// Irradiance ∫ L(ω) max(0, n·ω) dω under `sky` on a surface with unit normal n, texel by
/// texel: each texel's radiance times its integral of the clamped cosine, by the midpoint rule
/// on 32 × 32 cells of equal solid angle (equal steps of u and of cos θ) mapped through
/// Sky::direction. The clamped cosine is smooth but for its kink along the horizon of n, so
/// the sum is exact to ~10⁻⁵.
glm::dvec3 skyIrradiance(const Sky& sky, glm::vec3 n) {
    const Image& environment = *sky.environment();
    const uint32_t width = environment.width, height = environment.height;
    constexpr int kCells = 32;
    glm::dvec3 sum(0.0);
    for (uint32_t y = 0; y < height; ++y) {
        const double cos0 = std::cos(kPi * y / height), cos1 = std::cos(kPi * (y + 1) / height);
        const double cellSolidAngle = 2.0 * kPi / width / kCells * (cos0 - cos1) / kCells;
        for (uint32_t x = 0; x < width; ++x) {
            double cosine = 0.0;
            for (int i = 0; i < kCells; ++i)
                for (int j = 0; j < kCells; ++j) {
                    const double u = (x + (i + 0.5) / kCells) / width;
                    const double cosTheta = cos0 - (j + 0.5) / kCells * (cos0 - cos1);
                    const glm::vec3 w = sky.direction(float(u), float(std::acos(cosTheta) / kPi));
                    cosine += std::max(0.0, double(glm::dot(n, w)));
                }
            sum += glm::dvec3(sky.texelRadiance(x, y)) * cosine * cellSolidAngle;
        }
    }
    return sum;
}

TEST_F(SkyEnvironmentTest, ImportanceSampledSkyGivesTheTexelSumsIrradianceAndTurnsWithIt) {
    // A dim 64 × 32 sky with a 4 × 3 texel patch some 1600 times brighter round u = 0.25 (+X),
    // 17°–34° above the horizon, over a plane tilted 45° towards +X. Its radiance, all of it
    // direct, is ρ·E/π with E the texel sum of L·cosθ·dω. Turned by 90° the patch moves to −Z
    // (Sky::direction), so a plane tilted towards −Z then gets what the +X one got before,
    // and the +X one much less. BSDF sampling alone finds the patch (3 % of the cosine's
    // weight, which brings 98 % of the light) too rarely to reach 1 % precision with 20000
    // paths (it would scatter by 4 %); the luminance-proportional texel distribution with MIS
    // does, and the mean must lie within 4.5 standard errors.
    writeEnvironment("sky.exr", 64, 32, {0.05f, 0.1f, 0.2f}, {200.0f, 150.0f, 100.0f}, {14, 10},
                     {18, 13});
    const glm::vec3 towardsX = glm::normalize(glm::vec3(1.0f, 1.0f, 0.0f));
    const glm::vec3 towardsMinusZ = glm::normalize(glm::vec3(0.0f, 1.0f, -1.0f));
    struct Case {
        float rotation;
        glm::vec3 normal;
    };
    std::vector<glm::dvec3> irradiance;
    for (const Case& c : {Case{0.0f, towardsX}, Case{90.0f, towardsMinusZ}, Case{90.0f, towardsX}}) {
        std::string what = "rotation " + std::to_string(c.rotation) + " normal " +
                           std::to_string(c.normal.x) + "," + std::to_string(c.normal.z);
        Scene scene = largePlaneScene(c.normal);
        scene.sourcePath = sceneFile();
        auto rays = EmbreeScene::create(scene);
        ASSERT_TRUE(rays);
        LightSet lights = constantSky({1.0f, 0.9f, 0.8f});
        lights.sky->environment = "sky.exr";
        lights.sky->rotationDegrees = c.rotation;
        auto tracer = PathTracer::create(scene, **rays, lights);
        ASSERT_TRUE(tracer) << tracer.error().message;
        ASSERT_NE(tracer->sky(), nullptr);
        const glm::dvec3 e = skyIrradiance(*tracer->sky(), c.normal);
        irradiance.push_back(e);
        const glm::dvec3 expected = glm::dvec3(kPlaneAlbedo) * e / kPi;

        constexpr int kSamples = 20000;
        glm::dvec3 sum(0.0), sumSquares(0.0);
        for (int i = 0; i < kSamples; ++i) {
            Rng rng(13, uint64_t(i));
            glm::dvec3 radiance(
                tracer->traceRadiance(c.normal, -c.normal, -1, Component::Direct, rng));
            sum += radiance;
            sumSquares += radiance * radiance;
        }
        const glm::dvec3 mean = sum / double(kSamples);
        const glm::dvec3 standardError =
            glm::sqrt((sumSquares / double(kSamples) - mean * mean) / double(kSamples));
        for (int ch = 0; ch < 3; ++ch) {
            EXPECT_LT(standardError[ch], 0.01 * expected[ch]) << what << " channel " << ch;
            EXPECT_NEAR(mean[ch], expected[ch], 4.5 * standardError[ch]) << what << " channel " << ch;
        }
    }
    // The turn moves the light as Sky::direction says: +X goes to −Z.
    for (int ch = 0; ch < 3; ++ch) {
        EXPECT_NEAR(irradiance[1][ch], irradiance[0][ch], 1e-4 * irradiance[0][ch]) << ch;
        EXPECT_LT(irradiance[2][ch], 0.6 * irradiance[0][ch]) << ch;
    }
}

TEST_F(SkyEnvironmentTest, MissingOrBadEnvironmentIsAClearError) {
    Scene scene = largePlaneScene({0.0f, 1.0f, 0.0f});
    scene.sourcePath = sceneFile();
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays);
    LightSet lights = constantSky(glm::vec3(1.0f));
    lights.sky->environment = "nowhere.exr";
    auto missing = pathTrace(scene, **rays, lights, furnaceCamera(), params(2, 1, Component::Full));
    ASSERT_FALSE(missing);
    EXPECT_EQ(missing.error().code, ErrorCode::NotFound);
    EXPECT_NE(missing.error().message.find("nowhere.exr"), std::string::npos)
        << missing.error().message;
    BakeData bake =
        cachesOnly({Cache{{0.0f, 1.0f, 0.0f}, gpu::kCacheKindGrid, glm::vec3(0.0f), 0}}, 2, 1);
    auto probes = pathTraceProbes(scene, **rays, bake, lights, ProbeParams{});
    ASSERT_FALSE(probes);
    EXPECT_EQ(probes.error().code, ErrorCode::NotFound);

    // A negative texel is no radiance.
    writeEnvironment("negative.exr", 8, 4, glm::vec3(1.0f), glm::vec3(-1.0f), {2, 1}, {3, 2});
    lights.sky->environment = "negative.exr";
    auto negative = pathTrace(scene, **rays, lights, furnaceCamera(), params(2, 1, Component::Full));
    ASSERT_FALSE(negative);
    EXPECT_EQ(negative.error().code, ErrorCode::InvalidInput);
    EXPECT_NE(negative.error().message.find("negative.exr"), std::string::npos)
        << negative.error().message;
}

}  // namespace
}  // namespace pic
