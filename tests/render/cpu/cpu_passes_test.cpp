// Each CPU twin pass alone on tiny hand-built inputs with known answers: one surfel under
// one light, a three-level hierarchy, one cache with one link, a 2×1×2 grid and a 3×1 map.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "core/bake_data.h"
#include "core/cache_values.h"
#include "core/color.h"
#include "core/geometry.h"
#include "core/light_set.h"
#include "core/sh.h"
#include "rays/embree_scene.h"
#include "render/cpu/cache_lighting.h"
#include "render/cpu/lightmap_copy.h"
#include "render/cpu/pull.h"
#include "render/cpu/surfel_lighting.h"

namespace pic {
namespace {

constexpr double kPi = std::numbers::pi;

/// Adds the quad a, b, c, d (counter-clockwise seen from its front) as two triangles.
void addQuad(Scene& scene, glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d,
             uint32_t material) {
    const uint32_t first = static_cast<uint32_t>(scene.vertices.size());
    for (const glm::vec3& p : {a, b, c, d}) {
        Vertex v;
        v.position = p;
        scene.vertices.push_back(v);
        scene.bounds.extend(p);
    }
    scene.triangles.push_back(Triangle{{first, first + 1, first + 2}, material, 0});
    scene.triangles.push_back(Triangle{{first, first + 2, first + 3}, material, 0});
}

/// A 2 m floor at y = 0 facing +y (triangles 0, 1), material 0 "floor", material 1 "glow".
Scene floorScene() {
    Scene scene;
    scene.materials = {Material{.name = "floor"}, Material{.name = "glow"}};
    addQuad(scene, {-1, 0, -1}, {-1, 0, 1}, {1, 0, 1}, {1, 0, -1}, 0);
    return scene;
}

/// One surfel on triangle 0 of floorScene, as a complete one-node bake.
BakeData oneSurfelBake(const glm::vec3& position) {
    BakeData bake;
    Surfel s{};
    s.position = position;
    s.area = 0.01f;
    s.normal = {0, 1, 0};
    s.material = 0;
    s.albedo = {0.5f, 0.25f, 0.8f};
    s.radius = std::sqrt(s.area / float(kPi));
    s.emission = {0, 0, 0};
    s.triangle = 0;
    bake.surfels = {s};
    Node leaf{};
    leaf.center = s.position;
    leaf.area = s.area;
    leaf.normal = s.normal;
    leaf.left = leaf.right = leaf.parent = kNoNode;
    leaf.surfelCount = 1;
    bake.nodes = {leaf};
    bake.levelOffsets = {1};
    return bake;
}

Light pointLight(glm::vec3 position, float intensity, glm::vec3 color) {
    Light light;
    light.id = "lamp";
    light.type = LightType::Point;
    light.position = position;
    light.intensity = intensity;
    light.color = color;
    return light;
}

void expectVecNear(const glm::vec3& actual, const glm::dvec3& expected, double relative) {
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(actual[c], expected[c], relative * std::abs(expected[c]) + 1e-12)
            << "channel " << c;
}

TEST(SurfelLighting, PointLightGivesAlbedoAreaIntensityCosineOverDistanceSquared) {
    Scene scene = floorScene();
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays) << rays.error().message;
    const glm::vec3 position(0.2f, 0.0f, 0.1f);
    BakeData bake = oneSurfelBake(position);
    LightSet lights;
    const glm::vec3 lamp(0.5f, 2.0f, -0.3f);
    lights.lights = {pointLight(lamp, 3.0f, {1.0f, 0.5f, 0.25f})};

    std::vector<glm::vec3> flux(1);
    lightSurfels(scene, **rays, bake, lights, nullptr, flux);
    const glm::dvec3 toLamp = glm::dvec3(lamp) - glm::dvec3(position);
    const double d = glm::length(toLamp);
    const double cosTheta = toLamp.y / d;
    const glm::dvec3 expected = glm::dvec3(0.5, 0.25, 0.8) * 0.01 * 3.0 *
                                glm::dvec3(1.0, 0.5, 0.25) * cosTheta / (d * d);
    expectVecNear(flux[0], expected, 1e-5);
}

TEST(SurfelLighting, DirectionalLightGivesAlbedoAreaIrradianceCosine) {
    Scene scene = floorScene();
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays);
    BakeData bake = oneSurfelBake({0.0f, 0.0f, 0.0f});
    Light sun;
    sun.id = "sun";
    sun.type = LightType::Directional;
    sun.direction = glm::normalize(glm::vec3(0.0f, -1.0f, -1.0f));
    sun.intensity = 2.0f;
    LightSet lights;
    lights.lights = {sun};
    std::vector<glm::vec3> flux(1);
    directSurfelFlux(scene, **rays, bake, lights, flux);
    expectVecNear(flux[0], glm::dvec3(0.5, 0.25, 0.8) * 0.01 * 2.0 * std::sqrt(0.5), 1e-5);
}

TEST(SurfelLighting, OccludedLightGivesNothing) {
    Scene scene = floorScene();
    // A blocker at y = 1 between the surfel and the lamp (facing down: both sides block).
    addQuad(scene, {-0.5f, 1, -0.5f}, {0.5f, 1, -0.5f}, {0.5f, 1, 0.5f}, {-0.5f, 1, 0.5f}, 0);
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays);
    BakeData bake = oneSurfelBake({0.0f, 0.0f, 0.0f});
    LightSet lights;
    lights.lights = {pointLight({0.1f, 2.0f, 0.0f}, 5.0f, glm::vec3(1.0f))};
    std::vector<glm::vec3> flux(1, glm::vec3(-1.0f));
    directSurfelFlux(scene, **rays, bake, lights, flux);
    EXPECT_EQ(flux[0], glm::vec3(0.0f));

    // Below the blocker's edge the same lamp shines again: the blocker, not the pass, is dark.
    lights.lights = {pointLight({0.9f, 2.0f, 0.0f}, 5.0f, glm::vec3(1.0f))};
    bake.surfels[0].position = {0.9f, 0.0f, 0.0f};
    directSurfelFlux(scene, **rays, bake, lights, flux);
    EXPECT_GT(flux[0].x, 0.0f);
}

TEST(SurfelLighting, VisibilityBitsAreWhereTheDirectFluxIsLit) {
    // 70 surfels along x (three words, the last one partly used), the middle ones under a
    // blocker; a spot whose cone leaves out the far end. Bit i is set exactly where the
    // direct flux of that light is positive, whatever its colour and intensity.
    Scene scene = floorScene();
    addQuad(scene, {-0.2f, 1, -0.5f}, {0.2f, 1, -0.5f}, {0.2f, 1, 0.5f}, {-0.2f, 1, 0.5f}, 0);
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays);
    BakeData bake = oneSurfelBake({0.0f, 0.0f, 0.0f});
    const Surfel first = bake.surfels[0];
    bake.surfels.clear();
    for (int i = 0; i < 70; ++i) {
        Surfel s = first;
        s.position = {-0.95f + 0.0275f * float(i), 0.0f, 0.0f};
        bake.surfels.push_back(s);
    }
    Light spot = pointLight({0.0f, 2.0f, 0.0f}, 4.0f, {1.0f, 0.0f, 0.5f});
    spot.type = LightType::Spot;
    spot.direction = glm::normalize(glm::vec3(-0.3f, -1.0f, 0.0f));
    spot.outerConeAngle = 0.45f;
    spot.innerConeAngle = 0.3f;
    LightSet lights;
    lights.lights = {spot};
    std::vector<glm::vec3> flux(bake.surfels.size());
    directSurfelFlux(scene, **rays, bake, lights, flux);
    std::vector<uint32_t> bits(visibilityWords(bake.surfels.size()), ~0u);
    ASSERT_EQ(bits.size(), 3u);
    surfelVisibility(**rays, bake, spot, bits);
    int lit = 0, blocked = 0;
    for (size_t i = 0; i < bake.surfels.size(); ++i) {
        const bool bit = (bits[i / 32] >> (i % 32)) & 1u;
        EXPECT_EQ(bit, flux[i].r > 0.0f) << "surfel " << i;
        lit += bit;
        blocked += std::abs(bake.surfels[i].position.x) < 0.15f && !bit;
    }
    EXPECT_GT(lit, 10);
    EXPECT_GT(blocked, 5);
    EXPECT_LT(lit + blocked, 70);  // the cone leaves some out
    EXPECT_EQ(bits[2] >> 6, 0u);   // bits past the last surfel stay clear

    // Colour and intensity do not change what the light reaches.
    Light dim = spot;
    dim.intensity = 0.0f;
    dim.color = {0.0f, 1.0f, 0.0f};
    std::vector<uint32_t> dimBits(bits.size());
    surfelVisibility(**rays, bake, dim, dimBits);
    EXPECT_EQ(dimBits, bits);
}

TEST(SurfelLighting, EmissiveSurfelGivesPiRadianceAreaScale) {
    Scene scene = floorScene();
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays);
    BakeData bake = oneSurfelBake({0.0f, 0.0f, 0.0f});
    bake.surfels[0].material = 1;
    bake.surfels[0].emission = {2.0f, 3.0f, 4.0f};
    LightSet lights;
    lights.emissiveScale["glow"] = 0.5f;
    std::vector<glm::vec3> flux(1);
    directSurfelFlux(scene, **rays, bake, lights, flux);
    expectVecNear(flux[0], kPi * glm::dvec3(2.0, 3.0, 4.0) * 0.01 * 0.5, 1e-6);

    // Scales of other materials do not apply; an unlisted material emits at scale 1.
    lights.emissiveScale = {{"floor", 7.0f}};
    directSurfelFlux(scene, **rays, bake, lights, flux);
    expectVecNear(flux[0], kPi * glm::dvec3(2.0, 3.0, 4.0) * 0.01, 1e-6);
}

TEST(SurfelLighting, BounceAddsAlbedoAreaTimesCacheIrradiance) {
    // Every grid vertex holds one cache of constant grey radiance L: irradiance is π·L, so
    // the bounce adds ρ·A·π·L to the direct flux.
    Scene scene = floorScene();
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays);
    BakeData bake = oneSurfelBake({0.3f, 0.0f, -0.2f});
    bake.params.bandsY = 3;
    bake.params.bandsC = 2;
    bake.caches.resize(1);
    bake.grid.origin = {-1.0f, -1.0f, -1.0f};
    bake.grid.cellSize = 2.0f;
    bake.grid.dims = {2, 2, 2};
    bake.grid.cacheIndex.assign(8, 0u);
    CacheValues values = CacheValues::zeros(1, 3, 2);
    const double radiance = 0.75;
    values.y[0] = float(radiance * 2.0 * std::sqrt(kPi));  // L / y_0^0

    LightSet lights;
    lights.lights = {pointLight({0.0f, 1.0f, 0.0f}, 1.0f, glm::vec3(1.0f))};
    std::vector<glm::vec3> direct(1), bounced(1), combined(1);
    directSurfelFlux(scene, **rays, bake, lights, direct);
    bounceSurfelFlux(scene, bake, direct, values, bounced);
    lightSurfels(scene, **rays, bake, lights, &values, combined);
    const glm::dvec3 expected =
        glm::dvec3(direct[0]) + glm::dvec3(0.5, 0.25, 0.8) * 0.01 * kPi * radiance;
    expectVecNear(bounced[0], expected, 1e-5);
    EXPECT_EQ(bounced[0], combined[0]);
}

TEST(Pull, InnerNodesHoldExactSumsOfTheirLeaves) {
    // Leaves 0..4; level 1: 5 = (0, 1), 6 = (2, 3); level 2: 7 = (5, 4); level 3: 8 = (7, 6).
    BakeData bake;
    bake.surfels.resize(5);
    bake.nodes.resize(9);
    const uint32_t children[4][2] = {{0, 1}, {2, 3}, {5, 4}, {7, 6}};
    for (uint32_t k = 0; k < 4; ++k) {
        bake.nodes[5 + k].left = children[k][0];
        bake.nodes[5 + k].right = children[k][1];
    }
    bake.levelOffsets = {5, 7, 8, 9};
    // Leaf values far apart in magnitude: any other summation would still be exact for these
    // dyadic numbers, so equality tests the tree, not the rounding.
    std::vector<glm::vec3> flux(9, glm::vec3(-1.0f));
    flux[0] = {1.0f, 0.5f, 0.0f};
    flux[1] = {2.0f, 0.25f, 1.0f};
    flux[2] = {4.0f, 0.125f, 1024.0f};
    flux[3] = {8.0f, 0.0625f, 0.0f};
    flux[4] = {16.0f, 0.03125f, 2.0f};
    pullFlux(bake, flux);
    EXPECT_EQ(flux[5], glm::vec3(3.0f, 0.75f, 1.0f));
    EXPECT_EQ(flux[6], glm::vec3(12.0f, 0.1875f, 1024.0f));
    EXPECT_EQ(flux[7], glm::vec3(19.0f, 0.78125f, 3.0f));
    EXPECT_EQ(flux[8], glm::vec3(31.0f, 0.96875f, 1027.0f));
    EXPECT_EQ(flux[0], glm::vec3(1.0f, 0.5f, 0.0f));  // leaves untouched
}

/// A bake of one cache over a one-node hierarchy with nL links of the given mode.
BakeData oneCacheBake(LinkMode mode, uint32_t bandsY, uint32_t bandsC, uint32_t nL,
                      uint32_t surfels) {
    BakeData bake;
    bake.params.bandsY = bandsY;
    bake.params.bandsC = bandsC;
    bake.params.linkMode = mode;
    bake.surfels.resize(surfels);
    bake.nodes.resize(2 * surfels - 1);
    bake.caches.resize(1);
    bake.links.mode = mode;
    bake.links.linksPerCache = nL;
    if (mode == LinkMode::Sh) {
        bake.links.bands = bandsY;
        bake.links.shNodes.assign(nL, 0u);
        bake.links.shCoefficients.assign(size_t{nL} * bandsY * bandsY, floatToHalf(0.0f));
    } else {
        bake.links.rtp.assign(nL, RtpLink{0, 0.0f, 0, 0.0f});
    }
    return bake;
}

/// Radiance SH of `flux`·factor·indicator(cone of 1 − cos α = u around d), projected by
/// midpoint quadrature over the cone in a frame around d: an oracle independent of core/sh.h's
/// zonal factors.
std::vector<double> coneProjection(int bands, const glm::vec3& d, double u, double scale) {
    glm::vec3 t, b;
    orthonormalBasis(d, t, b);
    const int nTheta = 400, nPhi = 256;
    const double alpha = std::acos(1.0 - u);
    std::vector<double> sum(shCount(bands), 0.0);
    std::vector<float> basis(shCount(bands));
    for (int i = 0; i < nTheta; ++i) {
        const double theta = alpha * (i + 0.5) / nTheta;
        const double weight = std::sin(theta) * (alpha / nTheta) * (2.0 * kPi / nPhi);
        for (int j = 0; j < nPhi; ++j) {
            const double phi = 2.0 * kPi * (j + 0.5) / nPhi;
            const glm::vec3 w = float(std::cos(theta)) * d +
                                float(std::sin(theta)) *
                                    (float(std::cos(phi)) * t + float(std::sin(phi)) * b);
            shEvaluate(bands, glm::normalize(w), basis.data());
            for (int k = 0; k < shCount(bands); ++k) sum[k] += scale * weight * basis[k];
        }
    }
    return sum;
}

TEST(CacheLighting, RtpLinkProjectsTheNodeConeWithYCoCgBandSplit) {
    const uint32_t bandsY = 4, bandsC = 2;
    BakeData bake = oneCacheBake(LinkMode::Rtp, bandsY, bandsC, 3, 2);
    const glm::vec3 rgb(3.0f, 2.0f, 1.0f);
    const float factor = 0.7f, u = 0.3f;
    bake.links.rtp[0] = RtpLink{1, factor, encodeOctahedral(glm::vec3(1, 2, -3)), u};
    // Padding: factor 0, here with a node out of range that must never be read.
    bake.links.rtp[1] = RtpLink{12345, 0.0f, encodeOctahedral(glm::vec3(0, 0, 1)), 1.0f};
    bake.links.rtp[2] = RtpLink{0, 0.0f, 0, 0.0f};
    // Node 0 is very bright: padding that read it would show.
    std::vector<glm::vec3> nodeFlux = {glm::vec3(1e6f), rgb, glm::vec3(1e6f)};

    CacheValues values;
    lightCaches(bake, nodeFlux, values);
    ASSERT_EQ(values.cacheCount(), 1u);
    ASSERT_EQ(values.bandsY, bandsY);
    ASSERT_EQ(values.bandsC, bandsC);
    ASSERT_EQ(values.y.size(), 16u);
    ASSERT_EQ(values.co.size(), 4u);

    const glm::vec3 d = decodeOctahedral(bake.links.rtp[0].directionOct);
    const glm::vec3 flux = rgbToYCoCg(rgb);
    const std::vector<double> fluxY = coneProjection(bandsY, d, u, flux.x * factor);
    const std::vector<double> fluxCo = coneProjection(bandsC, d, u, flux.y * factor);
    const std::vector<double> fluxCg = coneProjection(bandsC, d, u, flux.z * factor);
    // The quadrature converges as 1/n²; 1e-4 of the band-0 value is far below any wrong
    // factor, sign or basis orientation.
    const double tolerance = 1e-4 * std::abs(fluxY[0]);
    for (int i = 0; i < 16; ++i) EXPECT_NEAR(values.y[i], fluxY[i], tolerance) << "Y " << i;
    for (int i = 0; i < 4; ++i) {
        EXPECT_NEAR(values.co[i], fluxCo[i], tolerance) << "Co " << i;
        EXPECT_NEAR(values.cg[i], fluxCg[i], tolerance) << "Cg " << i;
    }

    // The closed form Φ·factor·K_l(α)·y_lm(d), and ∫L dω = 2√π·c00 = Φ·factor·Ω.
    float basis[16];
    shEvaluate(bandsY, d, basis);
    for (int l = 0; l < int(bandsY); ++l)
        for (int i = l * l; i < (l + 1) * (l + 1); ++i)
            EXPECT_NEAR(values.y[i], flux.x * factor * coneZonal(l, u) * basis[i], 1e-6)
                << "Y " << i;
    const double solidAngle = 2.0 * kPi * u;
    EXPECT_NEAR(2.0 * std::sqrt(kPi) * values.y[0], flux.x * factor * solidAngle, 1e-5);

    // Back to RGB in the low bands: the RGB flux times the same transport.
    for (int l = 0; l < int(bandsC); ++l) {
        for (int i = l * l; i < (l + 1) * (l + 1); ++i) {
            const glm::vec3 back = yCoCgToRgb({values.y[i], values.co[i], values.cg[i]});
            const double transport = factor * coneZonal(l, u) * basis[i];
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(back[c], rgb[c] * transport, 1e-5) << "coefficient " << i;
        }
    }
}

TEST(CacheLighting, TinyRtpConeIsTheProjectionOfAPointSource) {
    // As α → 0 the cone becomes a delta of power Φ·factor·Ω: c_lm = Φ·factor·Ω·y_lm(d). (A
    // band-limited SH cannot be evaluated back to Φ·factor in direction d; its integral can.)
    const uint32_t bands = 8;
    BakeData bake = oneCacheBake(LinkMode::Rtp, bands, bands, 1, 1);
    const float factor = 2.5f, u = 1e-6f;
    bake.links.rtp[0] = RtpLink{0, factor, encodeOctahedral(glm::vec3(-0.3f, 0.5f, 0.8f)), u};
    std::vector<glm::vec3> nodeFlux = {glm::vec3(4.0f)};
    CacheValues values;
    lightCaches(bake, nodeFlux, values);
    const glm::vec3 d = decodeOctahedral(bake.links.rtp[0].directionOct);
    float basis[64];
    shEvaluate(bands, d, basis);
    const double power = 4.0 * factor * 2.0 * kPi * u;
    for (int i = 0; i < 64; ++i)
        EXPECT_NEAR(values.y[i], power * basis[i], 1e-4 * power) << "Y " << i;
    for (int i = 0; i < 64; ++i) EXPECT_EQ(values.co[i], 0.0f);  // grey flux has no chroma
}

TEST(CacheLighting, ShLinksPassCoefficientsThroughWithChromaTruncated) {
    // Two real links (nodes 1 and 2) and two padding links; dyadic numbers make every product
    // and sum exact, so the coefficients must match exactly.
    const uint32_t bandsY = 3, bandsC = 1, nL = 4;
    BakeData bake = oneCacheBake(LinkMode::Sh, bandsY, bandsC, nL, 2);
    const float c1[9] = {0.5f, -0.25f, 1.5f, 0.125f, -2.0f, 0.75f, 0.0f, 3.0f, -0.5f};
    const float c2[9] = {0.25f, 0.5f, -0.125f, 1.0f, 0.0f, -1.0f, 2.0f, 0.5f, 0.25f};
    bake.links.shNodes = {1, 2, 0, kNoNode};
    for (int i = 0; i < 9; ++i) {
        bake.links.shCoefficients[i] = floatToHalf(c1[i]);
        bake.links.shCoefficients[9 + i] = floatToHalf(c2[i]);
    }
    const glm::vec3 rgb1(4.0f, 2.0f, 1.0f), rgb2(0.5f, 1.0f, 2.0f);
    std::vector<glm::vec3> nodeFlux = {glm::vec3(1e6f), rgb1, rgb2};
    CacheValues values;
    lightCaches(bake, nodeFlux, values);
    ASSERT_EQ(values.y.size(), 9u);
    ASSERT_EQ(values.co.size(), 1u);
    const glm::vec3 f1 = rgbToYCoCg(rgb1), f2 = rgbToYCoCg(rgb2);
    for (int i = 0; i < 9; ++i) EXPECT_EQ(values.y[i], f1.x * c1[i] + f2.x * c2[i]) << i;
    EXPECT_EQ(values.co[0], f1.y * c1[0] + f2.y * c2[0]);
    EXPECT_EQ(values.cg[0], f1.z * c1[0] + f2.z * c2[0]);
    const glm::vec3 back = yCoCgToRgb({values.y[0], values.co[0], values.cg[0]});
    EXPECT_EQ(back, rgb1 * c1[0] + rgb2 * c2[0]);
}

TEST(CacheLighting, HalfRoundingIsTheOnlyLossOfShLinks) {
    BakeData bake = oneCacheBake(LinkMode::Sh, 2, 2, 1, 1);
    const float c[4] = {0.1f, -0.3f, 0.7f, 1e-3f};  // not representable in binary16
    for (int i = 0; i < 4; ++i) bake.links.shCoefficients[i] = floatToHalf(c[i]);
    std::vector<glm::vec3> nodeFlux = {glm::vec3(2.0f)};
    CacheValues values;
    lightCaches(bake, nodeFlux, values);
    for (int i = 0; i < 4; ++i) {
        EXPECT_NEAR(values.y[i], 2.0f * c[i], 2.0f * std::abs(c[i]) * 0x1p-11f) << i;
        EXPECT_EQ(values.y[i], 2.0f * halfToFloat(floatToHalf(c[i]))) << i;
    }
}

TEST(LightmapCopy, TexelsTakeTheirCacheCoefficientsLayerByLayer) {
    BakeData bake;
    bake.params.bandsY = 2;
    bake.params.bandsC = 1;
    bake.caches.resize(2);
    bake.grid.origin = {0.0f, 0.0f, 0.0f};
    bake.grid.cellSize = 1.0f;
    bake.grid.dims = {2, 1, 2};
    bake.grid.cacheIndex = {0, kNoCache, 1, 0};
    bake.lightmap.width = 3;
    bake.lightmap.height = 1;
    bake.lightmap.cacheIndex = {1, kNoCache, 0};
    CacheValues values = CacheValues::zeros(2, 2, 1);
    for (int i = 0; i < 8; ++i) values.y[i] = float(10 + i);  // cache 0: 10..13, cache 1: 14..17
    values.co = {-1.0f, -2.0f};
    values.cg = {0.5f, 0.25f};

    CacheTextures textures = makeCacheTextures(bake);
    copyCachesToTextures(bake, values, textures);
    EXPECT_EQ(textures.layers(0), 4u);
    EXPECT_EQ(textures.layers(1), 1u);
    EXPECT_EQ(textures.gridCoverage, (std::vector<float>{1, 0, 1, 1}));
    EXPECT_EQ(textures.lightmapCoverage, (std::vector<float>{1, 0, 1}));
    // Grid Y: layer k holds coefficient k of each vertex's cache, 0 where there is none.
    EXPECT_EQ(textures.grid[0], (std::vector<float>{10, 0, 14, 10, 11, 0, 15, 11,  //
                                                    12, 0, 16, 12, 13, 0, 17, 13}));
    EXPECT_EQ(textures.grid[1], (std::vector<float>{-1, 0, -2, -1}));
    EXPECT_EQ(textures.grid[2], (std::vector<float>{0.5f, 0, 0.25f, 0.5f}));
    EXPECT_EQ(textures.lightmap[0],
              (std::vector<float>{14, 0, 10, 15, 0, 11, 16, 0, 12, 17, 0, 13}));
    EXPECT_EQ(textures.lightmap[1], (std::vector<float>{-2, 0, -1}));
    EXPECT_EQ(textures.lightmap[2], (std::vector<float>{0.25f, 0, 0.5f}));
}

TEST(LightmapCopy, CoverageRenormalisedTrilinearEqualsTheGridLookup) {
    // A renderer interpolating the textures and dividing by interpolated coverage must see
    // what core/cache_values.h computes.
    BakeData bake;
    bake.params.bandsY = 1;
    bake.params.bandsC = 1;
    bake.caches.resize(3);
    bake.grid.origin = {-1.0f, 0.0f, 2.0f};
    bake.grid.cellSize = 0.5f;
    bake.grid.dims = {2, 2, 2};
    bake.grid.cacheIndex = {0, 1, kNoCache, 2, kNoCache, 0, 1, kNoCache};
    bake.lightmap.width = bake.lightmap.height = 0;
    CacheValues values = CacheValues::zeros(3, 1, 1);
    values.y = {1.0f, 3.0f, 8.0f};
    CacheTextures textures = makeCacheTextures(bake);
    copyCachesToTextures(bake, values, textures);

    const glm::vec3 p(-0.8f, 0.35f, 2.1f);
    const glm::vec3 f = (p - bake.grid.origin) / bake.grid.cellSize;
    double value = 0.0, coverage = 0.0;
    for (int corner = 0; corner < 8; ++corner) {
        const int x = corner & 1, y = (corner >> 1) & 1, z = corner >> 2;
        const double w = (x ? f.x : 1 - f.x) * (y ? f.y : 1 - f.y) * (z ? f.z : 1 - f.z);
        const int index = x + 2 * (y + 2 * z);
        value += w * textures.grid[0][index];
        coverage += w * textures.gridCoverage[index];
    }
    const RadianceSh lookup = lookupGridRadiance(bake, values, p);
    EXPECT_NEAR(lookup.rgb[1][0], value / coverage, 1e-5);
}

}  // namespace
}  // namespace pic
