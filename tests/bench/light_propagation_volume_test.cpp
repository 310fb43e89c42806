// The light propagation volume baseline (bench/light_propagation_volume.h): its SH lobes and
// face transfers against brute-force quadrature, energy through injection and propagation, the
// direction light flows in an empty volume (the sign between the volume's intensity and the
// caches' incident radiance), the reflective shadow maps' flux against closed forms, and the
// caches on cornell against the ideal one-bounce caches.

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "bake/ref/probes.h"
#include "bench/light_propagation_volume.h"
#include "core/cache_values.h"
#include "core/light_set.h"
#include "core/parallel.h"
#include "core/sh.h"
#include "tests/support/baked_scene.h"

namespace pic {
namespace {

constexpr double kPi = std::numbers::pi;

/// The cornell bake the baseline tests share (the same as tests/bench/traced_probes_test.cpp).
const test::BakedScene& cornell() {
    return test::bakedScene("cornell", test::smallBakeOptions(2048, 32), 0.12f, 0.06f);
}

/// A bake of `scene` with no caches and no surfels: enough for an LPV whose VPLs a test reads.
BakeData emptyBake(const Scene& scene) {
    BakeData bake;
    bake.sceneHash = scene.hash;
    bake.params.bandsY = 2;
    bake.params.bandsC = 2;
    return bake;
}

/// Solid angle of the rectangle [y0, y1] × [z0, z1] of the plane x = d seen from the origin
/// (corner formula Σ ± atan(y·z / (d·√(d² + y² + z²)))).
double rectangleSolidAngle(double d, double y0, double y1, double z0, double z1) {
    const auto corner = [d](double y, double z) {
        return std::atan(y * z / (d * std::sqrt(d * d + y * y + z * z)));
    };
    return corner(y1, z1) - corner(y0, z1) - corner(y1, z0) + corner(y0, z0);
}

/// Band-0 luma of cache c: as stored, or for a light-map cache of 2-band values restricted
/// to the hemisphere above its normal n, as the ideal caches are (bake/ref/probes.h). For 2-band radiance
/// L(ω) = a + b·ω (a = L_0·y_0^0, b = √(3/(4π))·(L_x, L_y, L_z)), ∫_{n·ω>0} L·y_0^0 dω =
/// y_0^0·(2π·a + π·b·n).
double band0(const BakeData& bake, const CacheValues& values, size_t c, bool hemisphere) {
    const size_t stride = size_t(values.bandsY) * values.bandsY;
    const float* y = &values.y[c * stride];
    const Cache& cache = bake.caches[c];
    if (!hemisphere || cache.kind != gpu::kCacheKindLightmap || values.bandsY < 2) return y[0];
    const double y00 = 0.5 / std::sqrt(kPi), y1 = std::sqrt(3.0 / (4.0 * kPi));
    const double a = y[0] * y00;
    const double bn = y1 * (y[3] * cache.normal.x + y[1] * cache.normal.y + y[2] * cache.normal.z);
    return y00 * (2.0 * kPi * a + kPi * bn);
}

/// Mean band-0 luma over the caches of one kind (grid, light map) or all (kind < 0).
double meanBand0(const BakeData& bake, const CacheValues& values, int kind, bool hemisphere) {
    double sum = 0.0;
    size_t count = 0;
    for (size_t c = 0; c < bake.caches.size(); ++c) {
        if (kind >= 0 && bake.caches[c].kind != uint32_t(kind)) continue;
        sum += band0(bake, values, c, hemisphere);
        ++count;
    }
    return sum / double(std::max<size_t>(1, count));
}

/// Mean luma irradiance along the normal of the light-map caches, E = Σ K_l L_lm y_lm(n),
/// negative values clamped to 0 as the shader does.
double meanLightmapIrradiance(const BakeData& bake, const CacheValues& values) {
    const int bands = int(values.bandsY);
    const size_t stride = size_t(bands) * bands;
    double sum = 0.0;
    size_t count = 0;
    for (size_t c = 0; c < bake.caches.size(); ++c) {
        if (bake.caches[c].kind != gpu::kCacheKindLightmap) continue;
        sum += std::max(0.0f, shIrradiance(bands, &values.y[c * stride], bake.caches[c].normal));
        ++count;
    }
    return sum / double(std::max<size_t>(1, count));
}

// ---------------------------------------------------------------------------------------------
// SH numerics.

TEST(LpvSh, ClampedCosineLobeMatchesQuadrature) {
    // ∫ max(0, n·ω) y_i(ω) dω by the midpoint rule in (cos θ, φ), uniform in solid angle.
    const glm::vec3 normals[] = {glm::vec3(0, 0, 1), glm::vec3(0, -1, 0),
                                 glm::normalize(glm::vec3(0.3f, -0.5f, 0.8f))};
    constexpr int kZ = 400, kPhi = 800;
    for (const glm::vec3& n : normals) {
        double sum[4] = {};
        for (int i = 0; i < kZ; ++i) {
            const double z = -1.0 + (i + 0.5) * 2.0 / kZ;
            const double r = std::sqrt(1.0 - z * z);
            for (int j = 0; j < kPhi; ++j) {
                const double phi = (j + 0.5) * 2.0 * kPi / kPhi;
                const glm::vec3 w(float(r * std::cos(phi)), float(r * std::sin(phi)), float(z));
                const double cosine = std::max(0.0f, glm::dot(n, w));
                float basis[4];
                shEvaluate(2, w, basis);
                for (int k = 0; k < 4; ++k) sum[k] += cosine * basis[k];
            }
        }
        const auto lobe = lpv::clampedCosineLobe(n);
        const double dOmega = 4.0 * kPi / (double(kZ) * kPhi);
        for (int k = 0; k < 4; ++k) EXPECT_NEAR(lobe[k], sum[k] * dOmega, 2e-4) << k;
        // The closed form: (√π/2, √(π/3)·(n.y, n.z, n.x)).
        EXPECT_NEAR(lobe[0], std::sqrt(kPi) / 2.0, 1e-6);
        EXPECT_NEAR(lobe[3], std::sqrt(kPi / 3.0) * n.x, 1e-6);
    }
}

TEST(LpvSh, FaceSolidAnglesAndTransfersMatchQuadrature) {
    // The far face of the destination, a unit square at distance 1.5: 4·asin(1/10);
    // a side face, at distance 0.5 across, from 0.5 to 1.5 along the travel.
    const double direct = 4.0 * std::asin(0.1);
    const double side = rectangleSolidAngle(0.5, -0.5, 0.5, 0.5, 1.5);
    EXPECT_NEAR(direct, 0.4006696846, 1e-9);
    EXPECT_NEAR(side, 0.4234313544, 1e-9);
    // Together the 5 faces fill what the shared face subtends at distance 0.5: 4·asin(1/2).
    EXPECT_NEAR(direct + 4.0 * side, 2.0 * kPi / 3.0, 1e-12);

    const auto& faces = lpv::propagationFaces();
    for (int k = 0; k < 6; ++k) {
        for (int f = 0; f < 5; ++f) {
            const lpv::Face& face = faces[k][f];
            EXPECT_NEAR(face.solidAngle, f == 0 ? direct : side, 1e-9) << k << " " << f;
            // Brute force: the midpoint rule over the face, dω = cosθ/r² dA.
            const glm::dvec3 centre = glm::dvec3(face.direction) *
                                      (f == 0 ? 1.5 : std::sqrt(1.0 + 0.25));
            const glm::dvec3 n = glm::dvec3(face.normal);
            // Two unit axes spanning the face.
            glm::dvec3 e1(0.0), e2(0.0);
            int axes[2], count = 0;
            for (int a = 0; a < 3; ++a)
                if (n[a] == 0.0) axes[count++] = a;
            e1[axes[0]] = 1.0;
            e2[axes[1]] = 1.0;
            constexpr int kSteps = 300;
            double omega = 0.0, basisSum[4] = {};
            for (int i = 0; i < kSteps; ++i)
                for (int j = 0; j < kSteps; ++j) {
                    const glm::dvec3 p = centre + ((i + 0.5) / kSteps - 0.5) * e1 +
                                         ((j + 0.5) / kSteps - 0.5) * e2;
                    const double r2 = glm::dot(p, p);
                    const glm::dvec3 w = p / std::sqrt(r2);
                    const double dOmega = std::abs(glm::dot(w, n)) / r2 / (kSteps * kSteps);
                    omega += dOmega;
                    float basis[4];
                    shEvaluate(2, glm::vec3(w), basis);
                    for (int b = 0; b < 4; ++b) basisSum[b] += dOmega * basis[b];
                }
            EXPECT_NEAR(face.solidAngle, omega, 1e-5) << k << " " << f;
            for (int b = 0; b < 4; ++b)
                EXPECT_NEAR(face.basisIntegral[b], basisSum[b], 1e-5) << k << " " << f << " " << b;
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Energy and direction in an empty volume.

/// An isotropic-ish source of flux Φ per channel at a cell: six VPLs of Φ/6 facing ±x, ±y, ±z.
std::vector<lpv::Vpl> isotropicSource(uint32_t cell, float flux) {
    std::vector<lpv::Vpl> vpls;
    for (int k = 0; k < 6; ++k) {
        glm::vec3 n(0.0f);
        n[k / 2] = k % 2 == 0 ? 1.0f : -1.0f;
        vpls.push_back({cell, n, glm::vec3(flux / 6.0f)});
    }
    return vpls;
}

TEST(LpvEnergy, InjectedFluxEqualsVplFlux) {
    lpv::Volume volume(glm::vec3(0.0f), 0.25f, glm::uvec3(4, 5, 6));
    const std::vector<lpv::Vpl> vpls = {
        {3, glm::vec3(0, 1, 0), glm::vec3(1.0f, 2.0f, 0.5f)},
        {17, glm::normalize(glm::vec3(1, -2, 3)), glm::vec3(0.25f, 0.0f, 4.0f)},
        {17, glm::vec3(0, 0, -1), glm::vec3(3.0f, 1.0f, 1.0f)},
        {119, glm::vec3(1, 0, 0), glm::vec3(0.0f)}};
    volume.inject(vpls);
    const glm::dvec3 total = volume.totalFlux();
    EXPECT_NEAR(total.x, 4.25, 1e-5);
    EXPECT_NEAR(total.y, 3.0, 1e-5);
    EXPECT_NEAR(total.z, 5.5, 1e-5);
}

TEST(LpvPropagation, OneStepIsTheFaceTransfers) {
    // One step from one cell: each neighbour holds Σ_faces (∫_face I dω)·max(0, n_face·ω)/π.
    lpv::Volume volume(glm::vec3(0.0f), 1.0f, glm::uvec3(3));
    const uint32_t centre = uint32_t(volume.cellIndex(1, 1, 1));
    volume.inject(std::vector<lpv::Vpl>{
        {centre, glm::normalize(glm::vec3(0.3f, 0.9f, -0.2f)), glm::vec3(1.0f, 0.5f, 2.0f)},
        {centre, glm::normalize(glm::vec3(-0.7f, -0.1f, 0.6f)), glm::vec3(0.4f, 1.5f, 0.0f)}});
    const std::vector<float> source(volume.current().begin(), volume.current().end());
    volume.propagate(1, false);
    const auto& faces = lpv::propagationFaces();
    for (int k = 0; k < 6; ++k) {
        glm::ivec3 d(0);
        d[k / 2] = k % 2 == 0 ? 1 : -1;
        const glm::ivec3 c = glm::ivec3(1) + d;
        const float* got = &volume.current()[volume.cellIndex(c.x, c.y, c.z) * lpv::kCellFloats];
        for (int ch = 0; ch < 3; ++ch) {
            float expected[4] = {};
            for (const lpv::Face& face : faces[k]) {
                float flux = 0.0f;
                for (int j = 0; j < 4; ++j)
                    flux += source[centre * lpv::kCellFloats + ch * 4 + j] * face.basisIntegral[j];
                const auto lobe = lpv::clampedCosineLobe(face.normal);
                for (int j = 0; j < 4; ++j) expected[j] += flux * lobe[j] / float(kPi);
            }
            for (int j = 0; j < 4; ++j)
                EXPECT_NEAR(got[ch * 4 + j], expected[j], 1e-6) << k << " " << ch << " " << j;
        }
    }
}

TEST(LpvEnergy, PropagationConservesFluxAwayFromTheBorder) {
    // 8 steps from the centre of 21³ cells never reach the border: no flux leaves.
    lpv::Volume volume(glm::vec3(0.0f), 0.1f, glm::uvec3(21));
    volume.inject(std::vector<lpv::Vpl>{{uint32_t(volume.cellIndex(10, 10, 10)),
                                         glm::normalize(glm::vec3(0.2f, 1.0f, -0.4f)),
                                         glm::vec3(2.0f, 1.0f, 0.5f)}});
    volume.propagate(8, false);
    const glm::dvec3 total = volume.totalFlux();
    EXPECT_NEAR(total.x, 2.0, 2e-4);
    EXPECT_NEAR(total.y, 1.0, 1e-4);
    EXPECT_NEAR(total.z, 0.5, 1e-4);
}

TEST(LpvEnergy, LightFlowsAwayFromTheSourceWithInverseSquareIrradiance) {
    constexpr uint32_t kCells = 31;
    constexpr float kCell = 0.1f;
    constexpr float kFlux = 1.0f;
    lpv::Volume volume(glm::vec3(0.0f), kCell, glm::uvec3(kCells));
    const uint32_t mid = kCells / 2;
    volume.inject(isotropicSource(uint32_t(volume.cellIndex(mid, mid, mid)), kFlux));
    volume.propagate(16, false);
    const glm::vec3 source = (glm::vec3(float(mid)) + 0.5f) * kCell;
    for (int k = 0; k < 6; ++k) {
        glm::vec3 axis(0.0f);
        axis[k / 2] = k % 2 == 0 ? 1.0f : -1.0f;
        for (int cells : {2, 3, 4}) {
            const float d = float(cells) * kCell;
            const glm::vec3 p = source + d * axis;
            float rgb[3][lpv::kCoefficients];
            volume.sampleRadiance(p, rgb);
            // Caches hold radiance by where it comes from: band 1 (y, z, x) points back at
            // the source.
            const glm::vec3 from(rgb[0][3], rgb[0][1], rgb[0][2]);
            EXPECT_GT(glm::dot(from, -axis), 0.9f * glm::length(from)) << k << " " << cells;
            // The volume's intensity is by the direction light travels: away from the source.
            const auto accumulated = volume.accumulated();
            const glm::uvec3 c = glm::uvec3(glm::vec3(mid) + float(cells) * axis);
            const float* cell = &accumulated[volume.cellIndex(c.x, c.y, c.z) * lpv::kCellFloats];
            const glm::vec3 travels(cell[3], cell[1], cell[2]);
            EXPECT_GT(glm::dot(travels, axis), 0.9f * glm::length(travels));
            // Irradiance on a surface facing the source against Φ/(4π d²).
            const float e = shIrradiance(2, rgb[0], -axis);
            const double ratio = e / (kFlux / (4.0 * kPi * d * d));
            EXPECT_GT(ratio, 0.5) << k << " " << cells;
            EXPECT_LT(ratio, 2.0) << k << " " << cells;
            if (k == 0)
                std::printf("isotropic source, %d cells away: E / (Φ/(4π d²)) = %.3f\n", cells,
                            ratio);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Reflective shadow maps against closed forms.

TEST(LpvShadowMaps, PointLightInClosedBoxReflectsAlbedoTimesPower) {
    // Every direction of the sealed white box hits a wall: Σ Φ = ρ·4π·I exactly (the texels'
    // solid angles are exact and tile the sphere).
    const Scene scene = test::loadTestScene("closed_box");
    ASSERT_FALSE(scene.triangles.empty());
    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays);
    const BakeData bake = emptyBake(scene);
    auto lpv = LightPropagationVolume::create(scene, **rays, bake,
                                              {.resolution = 8, .iterations = 1, .rsmSize = 32,
                                               .occlusion = false});
    ASSERT_TRUE(lpv) << lpv.error().message;
    const LightSet lights = defaultLightSet(scene);
    ASSERT_EQ(lights.lights.size(), 1u);
    ASSERT_TRUE((*lpv)->update(lights));
    const LpvStats& stats = (*lpv)->stats();
    const glm::vec3 expected = glm::vec3(0.725f, 0.71f, 0.68f) * float(4.0 * kPi) *
                               lights.lights[0].intensity * lights.lights[0].color;
    EXPECT_EQ(stats.vpls, 6u * 32u * 32u);
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(stats.vplFlux[c], expected[c], 1e-3 * expected[c]) << c;
        EXPECT_NEAR(stats.injectedFlux[c], stats.vplFlux[c], 1e-4 * expected[c]) << c;
    }
}

TEST(LpvShadowMaps, SpotAndDirectionalLightsOnCornell) {
    const test::BakedScene& b = cornell();
    ASSERT_TRUE(b.ok);
    const BakeData bake = emptyBake(b.scene);
    auto lpv = LightPropagationVolume::create(b.scene, *b.rays, bake,
                                              {.resolution = 8, .iterations = 1, .rsmSize = 128,
                                               .occlusion = false});
    ASSERT_TRUE(lpv) << lpv.error().message;
    const glm::vec3 white(0.725f, 0.71f, 0.68f);

    // A hard-edged 20° spot straight down from under the ceiling: its cone (0.35 m wide on
    // the floor) lands on the white floor and boxes only, Σ Φ = ρ·I·2π(1 − cos α) up to the cone's edge on the texel grid.
    LightSet spot;
    Light light;
    light.id = "spot";
    light.type = LightType::Spot;
    light.position = glm::vec3(0.0f, 0.95f, 0.0f);
    light.direction = glm::vec3(0.0f, -1.0f, 0.0f);
    light.intensity = 2.0f;
    light.innerConeAngle = light.outerConeAngle = float(kPi / 9.0);
    spot.lights.push_back(light);
    ASSERT_TRUE((*lpv)->update(spot));
    const double cone = 2.0 * kPi * (1.0 - std::cos(kPi / 9.0));
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR((*lpv)->stats().vplFlux[c], white[c] * 2.0 * cone, 0.02 * white[c] * 2.0 * cone);

    // Sunlight straight down falls on the top of the 1 m² white ceiling (seen from outside,
    // two-sided): Σ Φ = ρ·E·1 m².
    LightSet sun;
    light = Light{};
    light.id = "sun";
    light.type = LightType::Directional;
    light.direction = glm::vec3(0.0f, -1.0f, 0.0f);
    light.intensity = 3.0f;
    sun.lights.push_back(light);
    ASSERT_TRUE((*lpv)->update(sun));
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR((*lpv)->stats().vplFlux[c], white[c] * 3.0, 0.02 * white[c] * 3.0);
}

TEST(LpvShadowMaps, EmissiveSurfelsInjectTheirFlux) {
    // cornell_area has no punctual light, only a 0.25 m square panel of radiance 10: its
    // surfels emit π·L_e·A ≈ π·10·0.0625 W (to the surfels' quantisation of its area), scaled
    // by the light set's emissive scale.
    const test::BakedScene& b =
        test::bakedScene("cornell_area", test::smallBakeOptions(2048, 32), 0.12f, 0.06f);
    ASSERT_TRUE(b.ok);
    auto lpv = LightPropagationVolume::create(b.scene, *b.rays, b.bake,
                                              {.resolution = 8, .iterations = 2, .rsmSize = 8});
    ASSERT_TRUE(lpv) << lpv.error().message;
    LightSet lights = defaultLightSet(b.scene);
    ASSERT_TRUE(lights.lights.empty());
    ASSERT_TRUE((*lpv)->update(lights));
    const double panel = kPi * 10.0 * 0.25 * 0.25;
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR((*lpv)->stats().vplFlux[c], panel, 0.15 * panel) << c;
        EXPECT_NEAR((*lpv)->stats().injectedFlux[c], (*lpv)->stats().vplFlux[c], 1e-4 * panel);
    }
    const double full = (*lpv)->stats().vplFlux.x;
    lights.emissiveScale["light"] = 0.5f;
    ASSERT_TRUE((*lpv)->update(lights));
    EXPECT_NEAR((*lpv)->stats().vplFlux.x, 0.5 * full, 1e-5 * full);
}

// ---------------------------------------------------------------------------------------------
// On cornell with its own lights.

TEST(LightPropagationVolume, CornellWithinFactorTwoOfIdealOneBounceCaches) {
    const test::BakedScene& b = cornell();
    ASSERT_TRUE(b.ok);
    const LightSet lights = defaultLightSet(b.scene);
    auto lpv = LightPropagationVolume::create(b.scene, *b.rays, b.bake, LpvParams{});
    ASSERT_TRUE(lpv) << lpv.error().message;
    auto values = (*lpv)->update(lights);
    ASSERT_TRUE(values) << values.error().message;
    const LpvStats& stats = (*lpv)->stats();
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(stats.injectedFlux[c], stats.vplFlux[c], 1e-4 * stats.vplFlux[c]) << c;
    for (float v : (*values)->y) ASSERT_TRUE(std::isfinite(v));
    for (float v : (*values)->co) ASSERT_TRUE(std::isfinite(v));
    for (float v : (*values)->cg) ASSERT_TRUE(std::isfinite(v));

    ProbeParams probe;
    probe.samples = 256;
    probe.bounces = 1;
    probe.indirectOnly = true;
    auto ideal = pathTraceProbes(b.scene, *b.rays, b.bake, lights, probe);
    ASSERT_TRUE(ideal) << ideal.error().message;
    const auto ratio = [&](int kind, bool hemisphere) {
        return meanBand0(b.bake, **values, kind, hemisphere) /
               meanBand0(b.bake, *ideal, kind, false);
    };
    // The ideal light-map caches hold the hemisphere above the surface only; the LPV's hold
    // its volume's radiance over the whole sphere, including the light its own surface's
    // VPLs send out (arriving "from behind"), which the clamped-cosine lookup of shading
    // barely sees. Like for like: the LPV's light-map radiance restricted to the hemisphere.
    const double all = ratio(-1, true);
    const double grid = ratio(int(gpu::kCacheKindGrid), false);
    const double irradiance =
        meanLightmapIrradiance(b.bake, **values) / meanLightmapIrradiance(b.bake, *ideal);
    std::printf("cornell, %zu caches: LPV / ideal mean band-0 luma %.3f (grid %.3f, light map "
                "%.3f; as stored, light-map caches over the sphere: %.3f), light-map "
                "irradiance along the normal %.3f\n",
                b.bake.caches.size(), all, grid, ratio(int(gpu::kCacheKindLightmap), true),
                ratio(-1, false), irradiance);
    std::printf("cornell: %llu VPLs; update %.1f ms (RSM %.1f, inject %.1f, propagate %.1f, "
                "sample %.1f); %.1f MiB\n",
                (unsigned long long)stats.vpls,
                stats.rsmMs + stats.injectMs + stats.propagateMs + stats.sampleMs, stats.rsmMs,
                stats.injectMs, stats.propagateMs, stats.sampleMs,
                double((*lpv)->memoryBytes()) / (1 << 20));
    for (double r : {all, grid, irradiance}) {
        EXPECT_GT(r, 0.5);
        EXPECT_LT(r, 2.0);
    }
}

TEST(LightPropagationVolume, DeterministicForAnyThreadCount) {
    const test::BakedScene& b = cornell();
    ASSERT_TRUE(b.ok);
    const LightSet lights = defaultLightSet(b.scene);
    const LpvParams params{.resolution = 16, .iterations = 8, .rsmSize = 64, .occlusion = true};
    auto run = [&](int threads) {
        setWorkerCount(threads);
        auto lpv = LightPropagationVolume::create(b.scene, *b.rays, b.bake, params);
        EXPECT_TRUE(lpv);
        auto values = (*lpv)->update(lights);
        EXPECT_TRUE(values);
        CacheValues copy = **values;
        setWorkerCount(0);
        return copy;
    };
    const CacheValues one = run(1), all = run(0);
    EXPECT_EQ(one.y, all.y);
    EXPECT_EQ(one.co, all.co);
    EXPECT_EQ(one.cg, all.cg);
}

TEST(LightPropagationVolume, RejectsBadParamsAndOtherScenes) {
    const test::BakedScene& b = cornell();
    ASSERT_TRUE(b.ok);
    const auto rejects = [&](const LpvParams& params, const BakeData& bake, const char* value) {
        auto lpv = LightPropagationVolume::create(b.scene, *b.rays, bake, params);
        ASSERT_FALSE(lpv);
        EXPECT_EQ(lpv.error().code, ErrorCode::InvalidInput);
        EXPECT_NE(lpv.error().message.find(value), std::string::npos) << lpv.error().message;
    };
    rejects({.resolution = 1}, b.bake, "resolution must be in [2, 256], got 1");
    rejects({.resolution = 257}, b.bake, "got 257");
    rejects({.iterations = 0}, b.bake, "iterations");
    rejects({.rsmSize = 0}, b.bake, "rsmSize");
    BakeData other = emptyBake(b.scene);
    other.sceneHash ^= 1;
    rejects({}, other, "hash");
}

}  // namespace
}  // namespace pic
