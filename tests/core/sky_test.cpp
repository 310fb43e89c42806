// The sky (core/sky.h): its image convention and rotation, its SH projection, the Gaunt
// coefficients against brute-force quadrature, the cache weights they fold into, and the
// checks on environment images.

#include "core/sky.h"

#include <cmath>
#include <filesystem>
#include <numbers>
#include <random>

#include <gtest/gtest.h>
#include <unistd.h>

#include "core/color.h"
#include "core/sh.h"

namespace pic {
namespace {

namespace fs = std::filesystem;

constexpr float kPi = std::numbers::pi_v<float>;

void expectVecNear(const glm::vec3& a, const glm::vec3& b, float tolerance) {
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c], b[c], tolerance) << "component " << c;
}

/// A scratch folder holding a scene path, removed with the test.
class SkyFolder : public ::testing::Test {
protected:
    void SetUp() override {
        mDir = fs::temp_directory_path() /
               ("pic_sky_test_" + std::to_string(::getpid()) + "_" +
                ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::create_directories(mDir);
    }
    void TearDown() override { fs::remove_all(mDir); }
    std::string scenePath() const { return (mDir / "scene.gltf").string(); }
    std::string write(const std::string& name, const Image& image) {
        auto written = writeImage((mDir / name).string(), image);
        EXPECT_TRUE(written) << written.error().message;
        return name;
    }
    fs::path mDir;
};

TEST(SkyImage, ConventionIsPlusYUpAndMinusZAtUZero) {
    expectVecNear(skyDirection(0.0f, 0.5f), {0.0f, 0.0f, -1.0f}, 1e-6f);
    expectVecNear(skyDirection(0.25f, 0.5f), {1.0f, 0.0f, 0.0f}, 1e-6f);
    expectVecNear(skyDirection(0.5f, 0.5f), {0.0f, 0.0f, 1.0f}, 1e-6f);
    expectVecNear(skyDirection(0.75f, 0.5f), {-1.0f, 0.0f, 0.0f}, 1e-6f);
    expectVecNear(skyDirection(0.3f, 0.0f), {0.0f, 1.0f, 0.0f}, 1e-6f);
    expectVecNear(skyDirection(0.3f, 1.0f), {0.0f, -1.0f, 0.0f}, 1e-6f);
    // skyUv inverts skyDirection away from the poles.
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
    for (int i = 0; i < 100; ++i) {
        const glm::vec2 uv(uniform(rng) * 0.999f, 0.01f + 0.98f * uniform(rng));
        const glm::vec2 back = skyUv(skyDirection(uv.x, uv.y));
        EXPECT_NEAR(back.x, uv.x, 1e-5f);
        EXPECT_NEAR(back.y, uv.y, 1e-5f);
    }
}

TEST(SkyImage, RotationTurnsCounterClockwiseSeenFromAbove) {
    const Sky sky(glm::vec3(1.0f), nullptr, 90.0f);
    // The image's −Z column looks along −X after a quarter turn, its +X column along −Z.
    expectVecNear(sky.direction(0.0f, 0.5f), {-1.0f, 0.0f, 0.0f}, 1e-6f);
    expectVecNear(sky.direction(0.25f, 0.5f), {0.0f, 0.0f, -1.0f}, 1e-6f);
    const glm::vec2 uv = sky.uv({-1.0f, 0.0f, 0.0f});
    EXPECT_NEAR(uv.x, 0.0f, 1e-6f);
    EXPECT_NEAR(uv.y, 0.5f, 1e-6f);
}

TEST(SkyProjection, ConstantSkyIsItsDcTerm) {
    const glm::vec3 radiance(1.5f, 0.5f, 2.0f);
    const auto sh = Sky(radiance, nullptr, 0.0f).project();
    expectVecNear(sh[0], 2.0f * std::sqrt(kPi) * radiance, 1e-5f);
    for (int k = 1; k < kSkyCoefficients; ++k) expectVecNear(sh[k], glm::vec3(0.0f), 0.0f);
    // A constant image times the radiance projects the same, to the texel quadrature's error.
    auto image = std::make_shared<Image>(64, 32);
    for (glm::vec3& texel : image->pixels) texel = glm::vec3(1.0f);
    const auto imaged = Sky(radiance, image, 30.0f).project();
    for (int k = 0; k < kSkyCoefficients; ++k) expectVecNear(imaged[k], sh[k], 8e-3f);
}

TEST(SkyProjection, OneBrightTexelProjectsAsItsSolidAngleTimesTheBasis) {
    // One texel of radiance 100 in a black 32 × 16 image: s_k = 100·Ω·y_k(d) at its centre d
    // (the projection reads the basis at texel centres).
    auto image = std::make_shared<Image>(32, 16);
    const uint32_t x = 5, y = 4;
    image->at(x, y) = glm::vec3(100.0f, 50.0f, 0.0f);
    const Sky sky(glm::vec3(1.0f), image, 45.0f);
    const auto sh = sky.project();
    const double theta0 = std::numbers::pi * y / 16.0, theta1 = std::numbers::pi * (y + 1) / 16.0;
    const float solidAngle = float(2.0 * std::numbers::pi / 32.0 * (std::cos(theta0) - std::cos(theta1)));
    float basis[kSkyCoefficients];
    const glm::vec3 d = sky.direction((x + 0.5f) / 32.0f, (y + 0.5f) / 16.0f);
    shEvaluate(kSkyBands, d, basis);
    for (int k = 0; k < kSkyCoefficients; ++k)
        expectVecNear(sh[k], glm::vec3(100.0f, 50.0f, 0.0f) * solidAngle * basis[k], 1e-4f);
    // And the sky reads that texel back along d.
    expectVecNear(sky.radiance(d), {100.0f, 50.0f, 0.0f}, 0.0f);
    expectVecNear(sky.radiance(-d), {0.0f, 0.0f, 0.0f}, 0.0f);
}

/// Calls visit(direction, solid angle) at the nodes of a midpoint rule over the sphere,
/// nz × nphi cells in (cos θ, φ) of equal solid angle.
template <class Visit>
void forSphereCells(int nz, int nphi, Visit&& visit) {
    const double dOmega = (2.0 / nz) * (2.0 * std::numbers::pi / nphi);
    for (int a = 0; a < nz; ++a) {
        const double z = -1.0 + 2.0 * (a + 0.5) / nz;
        const double s = std::sqrt(1.0 - z * z);
        for (int b = 0; b < nphi; ++b) {
            const double phi = 2.0 * std::numbers::pi * (b + 0.5) / nphi;
            visit(glm::vec3(float(s * std::cos(phi)), float(s * std::sin(phi)), float(z)), dOmega);
        }
    }
}

/// ∫ y_i y_j y_k over the sphere by a fine midpoint rule.
double bruteForceGaunt(int i, int j, int k) {
    double sum = 0.0;
    float basis[64];
    forSphereCells(400, 800, [&](const glm::vec3& direction, double dOmega) {
        shEvaluate(8, direction, basis);
        sum += double(basis[i]) * double(basis[j]) * double(basis[k]) * dOmega;
    });
    return sum;
}

TEST(SkyGaunt, MatchesBruteForceQuadrature) {
    const int bandsI = 4, bandsK = 6;
    const std::vector<float> gaunt = gauntCoefficients(bandsI, bandsK);
    const int countK = shCount(bandsK);
    ASSERT_EQ(gaunt.size(), size_t(shCount(bandsI)) * kSkyCoefficients * countK);
    // y_0 is the constant 1/(2√π): G_0jk = δ_jk/(2√π).
    for (int j = 0; j < kSkyCoefficients; ++j)
        for (int k = 0; k < countK; ++k)
            EXPECT_NEAR(gaunt[size_t(j) * countK + k], j == k ? 0.5 / std::sqrt(std::numbers::pi) : 0.0,
                        1e-6);
    std::mt19937 rng(3);
    for (int trial = 0; trial < 12; ++trial) {
        const int i = int(rng() % shCount(bandsI)), j = int(rng() % kSkyCoefficients);
        const int k = int(rng() % countK);
        EXPECT_NEAR(gaunt[(size_t(i) * kSkyCoefficients + j) * countK + k],
                    bruteForceGaunt(i, j, k), 2e-4)
            << "G(" << i << ", " << j << ", " << k << ")";
    }
    // A selection rule: y_1 y_1 y_4 (bands 1, 1 and 2) integrates to a non-zero value.
    EXPECT_GT(std::abs(gaunt[(size_t(shIndex(1, 1)) * kSkyCoefficients + shIndex(1, 1)) * countK +
                             shIndex(2, 2)]),
              0.05f);
}

TEST(SkyCacheWeights, FoldTheSkyTimesTheVisibility) {
    // c_i = ∫ y_i L V for a band-limited sky L (3 bands) and visibility V (5 bands): compare
    // the fold against the product integrated by brute force.
    const int bandsY = 3, bandsC = 2;
    std::array<glm::vec3, kSkyCoefficients> sky{};
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
    for (glm::vec3& s : sky) s = glm::vec3(uniform(rng), uniform(rng), uniform(rng));
    sky[0] += glm::vec3(4.0f);
    const SkyCacheWeights w = skyCacheWeights(sky, bandsY, bandsC);
    ASSERT_EQ(w.visibilityBands, skyVisibilityBands(bandsY));
    const int nV = shCount(w.visibilityBands);
    ASSERT_EQ(w.y.size(), size_t(shCount(bandsY)) * nV);
    ASSERT_EQ(w.co.size(), size_t(shCount(bandsC)) * nV);
    std::vector<float> visibility(nV);
    for (float& v : visibility) v = uniform(rng);

    std::vector<glm::dvec3> expected(shCount(bandsY), glm::dvec3(0.0));
    float basis[64];
    forSphereCells(200, 400, [&](const glm::vec3& direction, double dOmega) {
        shEvaluate(w.visibilityBands, direction, basis);
        glm::dvec3 radiance(0.0);
        for (int j = 0; j < kSkyCoefficients; ++j) radiance += glm::dvec3(sky[j]) * double(basis[j]);
        double v = 0.0;
        for (int k = 0; k < nV; ++k) v += double(visibility[k]) * basis[k];
        for (int i = 0; i < shCount(bandsY); ++i) expected[i] += radiance * v * double(basis[i]) * dOmega;
    });
    for (int i = 0; i < shCount(bandsY); ++i) {
        const glm::vec3 ycocg = rgbToYCoCg(glm::vec3(expected[i]));
        float y = 0.0f, co = 0.0f, cg = 0.0f;
        for (int k = 0; k < nV; ++k) {
            y += w.y[size_t(i) * nV + k] * visibility[k];
            if (i < shCount(bandsC)) {
                co += w.co[size_t(i) * nV + k] * visibility[k];
                cg += w.cg[size_t(i) * nV + k] * visibility[k];
            }
        }
        EXPECT_NEAR(y, ycocg.x, 2e-3f) << "coefficient " << i;
        if (i < shCount(bandsC)) {
            EXPECT_NEAR(co, ycocg.y, 2e-3f) << "coefficient " << i;
            EXPECT_NEAR(cg, ycocg.z, 2e-3f) << "coefficient " << i;
        }
    }
}

TEST(SkyCacheWeights, AConstantSkyPassesTheVisibilityThrough) {
    // s = 2√π·L in band 0 only: c_i = L·v_i for i < lY².
    std::array<glm::vec3, kSkyCoefficients> sky{};
    sky[0] = 2.0f * std::sqrt(kPi) * glm::vec3(3.0f);
    const SkyCacheWeights w = skyCacheWeights(sky, 4, 2);
    const int nV = shCount(w.visibilityBands);
    for (int i = 0; i < shCount(4); ++i)
        for (int k = 0; k < nV; ++k)
            EXPECT_NEAR(w.y[size_t(i) * nV + k], i == k ? 3.0f : 0.0f, 1e-5f);
}

TEST(SkyVisibilityBands, AddTheSkysBandsUpToEight) {
    EXPECT_EQ(skyVisibilityBands(1), 3);
    EXPECT_EQ(skyVisibilityBands(3), 5);
    EXPECT_EQ(skyVisibilityBands(6), 8);
    EXPECT_EQ(skyVisibilityBands(8), 8);
}

TEST_F(SkyFolder, ReadsAnEnvironmentNextToTheSceneAndSharesIt) {
    Image image(8, 4);
    image.at(2, 1) = glm::vec3(5.0f);
    const std::string name = write("sky.exr", image);
    auto first = loadEnvironment(scenePath(), name);
    ASSERT_TRUE(first) << first.error().message;
    EXPECT_EQ((*first)->width, 8u);
    expectVecNear((*first)->at(2, 1), glm::vec3(5.0f), 0.0f);
    auto second = loadEnvironment(scenePath(), name);
    ASSERT_TRUE(second);
    EXPECT_EQ(first->get(), second->get());

    SkyLight light;
    light.intensity = 2.0f;
    light.color = {1.0f, 0.5f, 0.25f};
    light.environment = name;
    auto sky = resolveSky(light, scenePath());
    ASSERT_TRUE(sky) << sky.error().message;
    expectVecNear(sky->texelRadiance(2, 1), glm::vec3(10.0f, 5.0f, 2.5f), 1e-6f);
    expectVecNear(sky->texelRadiance(0, 0), glm::vec3(0.0f), 0.0f);
}

TEST_F(SkyFolder, RefusesMissingAndBadEnvironments) {
    auto missing = loadEnvironment(scenePath(), "nowhere.exr");
    ASSERT_FALSE(missing);
    EXPECT_EQ(missing.error().code, ErrorCode::NotFound);
    EXPECT_NE(missing.error().message.find("nowhere.exr"), std::string::npos);

    Image negative(4, 2);
    for (glm::vec3& texel : negative.pixels) texel = glm::vec3(1.0f);
    negative.at(3, 1) = glm::vec3(1.0f, -2.0f, 1.0f);
    auto bad = loadEnvironment(scenePath(), write("negative.exr", negative));
    ASSERT_FALSE(bad);
    EXPECT_EQ(bad.error().code, ErrorCode::InvalidInput);
    EXPECT_NE(bad.error().message.find("texel (3, 1)"), std::string::npos) << bad.error().message;

    Image infinite = negative;
    infinite.at(3, 1) = glm::vec3(1.0f);
    infinite.at(0, 0).x = std::numeric_limits<float>::infinity();
    auto inf = loadEnvironment(scenePath(), write("infinite.exr", infinite));
    ASSERT_FALSE(inf);
    EXPECT_NE(inf.error().message.find("texel (0, 0)"), std::string::npos) << inf.error().message;
}

}  // namespace
}  // namespace pic
