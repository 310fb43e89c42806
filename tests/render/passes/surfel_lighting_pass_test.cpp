// The surfel-lighting pass on lavapipe (or the machine's GPU) against its CPU twin
// (render/cpu/surfel_lighting.h): direct flux of every light type with shadow-map and ray
// visibility, simplified shadow casters keeping the direct flux, and one bounce.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "core/light_set.h"
#include "render/cpu/cache_lighting.h"
#include "render/cpu/surfel_lighting.h"
#include "render/surfel_visibility.h"
#include "tests/render/gpu_fixture.h"

namespace pic {
namespace {

/// Fraction of surfels whose GPU flux differs from the CPU's by more than 1 % of the larger
/// (per channel, ignoring differences below 1e−6 of the brightest surfel).
double fractionDiffering(const std::vector<glm::vec3>& gpu, const std::vector<glm::vec3>& cpu) {
    float brightest = 0.0f;
    for (const glm::vec3& f : cpu) brightest = std::max({brightest, f.r, f.g, f.b});
    size_t differing = 0;
    for (size_t i = 0; i < cpu.size(); ++i) {
        for (int c = 0; c < 3; ++c) {
            const float d = std::abs(gpu[i][c] - cpu[i][c]);
            if (d > 0.01f * std::max(std::abs(cpu[i][c]), std::abs(gpu[i][c])) && d > 1e-6f * brightest) {
                ++differing;
                break;
            }
        }
    }
    return double(differing) / double(cpu.size());
}

/// Relative tolerance of a surfel's direct flux between two devices that evaluate the same
/// formula: float rounding (1e−4), widened inside a spot's soft edge. There the glTF ramp
/// r = (cos − cos_outer)/(cos_inner − cos_outer), squared, turns a cosine that the device
/// rounds a few ulp apart (Vulkan lets it contract into fma and round inversesqrt to 2 ulp)
/// into a relative change of 2·δ/(cos − cos_outer), with δ = 8·2⁻²⁴. Surfels within 2δ of
/// a cone's outer edge may fall either side of it and are not compared.
std::vector<double> fluxTolerance(const BakeData& bake, const LightSet& lights) {
    constexpr double kCosineUlps = 8.0 / double(1 << 24);
    std::vector<double> tolerance(bake.surfels.size(), 1e-4);
    for (const Light& light : lights.lights) {
        if (light.type != LightType::Spot) continue;
        const double cosOuter = std::cos(double(light.outerConeAngle));
        const double cosInner = std::cos(double(light.innerConeAngle));
        const bool hard = light.innerConeAngle >= light.outerConeAngle;
        for (size_t i = 0; i < bake.surfels.size(); ++i) {
            const glm::dvec3 toSurfel = glm::dvec3(bake.surfels[i].position) - glm::dvec3(light.position);
            const double cd = glm::dot(glm::dvec3(light.direction), glm::normalize(toSurfel));
            const double margin = cd - cosOuter;
            if (std::abs(margin) <= 2.0 * kCosineUlps)
                tolerance[i] = std::numeric_limits<double>::infinity();  // either side of the edge
            else if (!hard && margin > 0.0 && cd < cosInner)
                tolerance[i] += 2.0 * kCosineUlps / margin;
        }
    }
    return tolerance;
}

/// Largest difference of a GPU flux from the CPU's over surfels and channels, relative to
/// each surfel's tolerance (1 = at it; differences below 1e−6 of the brightest surfel
/// ignored).
double largestDifference(const std::vector<glm::vec3>& gpu, const std::vector<glm::vec3>& cpu,
                         const std::vector<double>& tolerance) {
    float brightest = 0.0f;
    for (const glm::vec3& f : cpu) brightest = std::max({brightest, f.r, f.g, f.b});
    double largest = 0.0;
    for (size_t i = 0; i < cpu.size(); ++i)
        for (int c = 0; c < 3; ++c) {
            const double d = std::abs(double(gpu[i][c]) - double(cpu[i][c]));
            if (d > 1e-6 * brightest)
                largest = std::max(largest, d / std::max(std::abs(double(cpu[i][c])), 1e-30) /
                                                tolerance[i]);
        }
    return largest;
}

/// Direct surfel flux for a scene and light set, with the visibility of shadow maps (within
/// the bound) and of rays (the CPU twin's own rays: equal to float rounding, within
/// fluxTolerance).
void expectDirectMatches(const test::BakedScene& b, const LightSet& lights) {
    std::vector<glm::vec3> cpu(b.bake.surfels.size());
    directSurfelFlux(b.scene, *b.rays, b.bake, lights, cpu);
    auto rays = test::gpuFor(b, {}, {.directVisibility = gpu::DirectVisibility::Rays});
    ASSERT_TRUE(rays);
    auto traced = rays->runDirect(lights);
    ASSERT_TRUE(traced) << traced.error().message;
    EXPECT_LE(largestDifference(*traced, cpu, fluxTolerance(b.bake, lights)), 1.0);

    auto gpu = test::gpuFor(b, {}, {.directVisibility = gpu::DirectVisibility::ShadowMaps});
    ASSERT_TRUE(gpu);
    auto direct = gpu->runDirect(lights);
    ASSERT_TRUE(direct) << direct.error().message;
    // Shadow maps and exact rays disagree only where a shadow edge crosses a surfel.
    EXPECT_LE(fractionDiffering(*direct, cpu), 0.01);
    double gpuSum = 0.0, cpuSum = 0.0;
    for (size_t i = 0; i < cpu.size(); ++i) {
        gpuSum += (*direct)[i].g;
        cpuSum += cpu[i].g;
    }
    EXPECT_GT(cpuSum, 0.0);
    EXPECT_NEAR(gpuSum / cpuSum, 1.0, 0.01);
}

TEST(GpuSurfelLighting, DirectFluxOfPointLightMatchesRays) {
    const test::BakedScene& b = test::smallBake("cornell", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    expectDirectMatches(b, defaultLightSet(b.scene));
}

TEST(GpuSurfelLighting, DirectFluxOfSpotMatchesRays) {
    const test::BakedScene& b = test::smallBake("small_spot", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    expectDirectMatches(b, defaultLightSet(b.scene));
}

TEST(GpuSurfelLighting, SimplifiedCastersKeepTheDirectFlux) {
    // The atrium's columns are finely tessellated: its sun's orthographic layer draws the
    // coarsest level of detail (ShadowCasters.LevelsOfDetail*). That must not move shadows
    // by more than the map's texels do: against the exact casters, direct flux changes on
    // few surfels, and against the rays it is as good as the exact casters' within 0.2 % of
    // the surfels.
    const test::BakedScene& b = test::smallBake("atrium", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    const LightSet lights = defaultLightSet(b.scene);
    std::vector<glm::vec3> rays(b.bake.surfels.size());
    directSurfelFlux(b.scene, *b.rays, b.bake, lights, rays);
    std::vector<glm::vec3> direct[2];
    for (const bool levels : {false, true}) {
        auto runtime = GpuRuntime::create(b.scene, *b.rays, b.bake, {},
                                          {.casterLevelsOfDetail = levels,
                                           .directVisibility = gpu::DirectVisibility::ShadowMaps});
        ASSERT_TRUE(runtime) << runtime.error().message;
        auto flux = (*runtime)->runDirect(lights);
        ASSERT_TRUE(flux) << flux.error().message;
        direct[levels] = std::move(*flux);
    }
    EXPECT_LE(fractionDiffering(direct[true], direct[false]), 0.005);
    EXPECT_LE(fractionDiffering(direct[true], rays), fractionDiffering(direct[false], rays) + 0.002);
    double exactSum = 0.0, simplifiedSum = 0.0;
    for (size_t i = 0; i < rays.size(); ++i) {
        exactSum += direct[false][i].g;
        simplifiedSum += direct[true][i].g;
    }
    EXPECT_GT(exactSum, 0.0);
    EXPECT_NEAR(simplifiedSum / exactSum, 1.0, 0.005);
}

TEST(GpuSurfelLighting, DirectFluxOfEveryLightTypeMatchesRays) {
    // Two floors, lit by a point light, a narrow spot (one perspective layer), a wide spot
    // (cube) and a directional light (orthographic) at once.
    const test::BakedScene& b = test::smallBake("two_floors", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    LightSet lights = defaultLightSet(b.scene);
    const glm::vec3 c = b.scene.bounds.center();
    Light narrow;
    narrow.id = "narrow";
    narrow.type = LightType::Spot;
    narrow.position = c + glm::vec3(0.3f, 0.2f, 0.1f);
    narrow.direction = glm::normalize(glm::vec3(0.2f, -1.0f, 0.1f));
    narrow.outerConeAngle = 0.5f;
    narrow.innerConeAngle = 0.3f;
    narrow.intensity = 3.0f;
    Light wide = narrow;
    wide.id = "wide";
    wide.position = c + glm::vec3(-0.4f, -0.3f, -0.2f);
    wide.outerConeAngle = 1.4f;
    wide.innerConeAngle = 1.4f;
    Light sun;
    sun.id = "sun";
    sun.type = LightType::Directional;
    sun.direction = glm::normalize(glm::vec3(0.3f, -1.0f, 0.2f));
    sun.intensity = 2.0f;
    lights.lights.insert(lights.lights.end(), {narrow, wide, sun});
    expectDirectMatches(b, lights);
}

TEST(GpuSurfelLighting, BounceMatchesTheCpuTwin) {
    const test::BakedScene& b = test::smallBake("cornell", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    auto gpu = test::gpuFor(b);
    ASSERT_TRUE(gpu);
    const LightSet lights = defaultLightSet(b.scene);
    const std::vector<glm::vec3> nodes = test::cpuNodeFlux(b, lights);
    CacheValues caches;
    lightCaches(b.bake, nodes, caches);
    const std::vector<glm::vec3> direct(nodes.begin(), nodes.begin() + b.bake.surfels.size());
    std::vector<glm::vec3> cpu(direct.size());
    bounceSurfelFlux(b.bake, surfelStencils(b.scene, *b.rays, b.bake), direct, caches, cpu);
    auto leaves = gpu->runBounce(direct, caches);
    ASSERT_TRUE(leaves) << leaves.error().message;
    // The GPU reads the caches as half floats: agreement to ~0.1 %, well inside 1 %.
    EXPECT_LE(fractionDiffering(*leaves, cpu), 0.001);
}

}  // namespace
}  // namespace pic
