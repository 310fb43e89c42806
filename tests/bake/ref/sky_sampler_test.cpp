// The sky's sampler for next-event estimation: texels drawn in proportion to luminance × solid
// angle (a χ² test), densities that agree between sample() and pdf(), and a constant sky
// sampled by the cosine.

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <numbers>
#include <vector>

#include "bake/ref/sky_sampler.h"
#include "core/color.h"
#include "core/sampling.h"
#include "core/sky.h"

namespace pic {
namespace {

constexpr double kPi = std::numbers::pi;

/// An 8 × 4 environment whose texels differ (one black), turned by 30°.
Sky checkerSky() {
    auto image = std::make_shared<Image>(8, 4);
    for (uint32_t y = 0; y < 4; ++y)
        for (uint32_t x = 0; x < 8; ++x)
            image->at(x, y) = glm::vec3(0.2f + 0.3f * float(x), 1.0f + float(y), 0.5f);
    image->at(5, 2) = glm::vec3(0.0f);
    image->at(1, 0) = glm::vec3(20.0f, 10.0f, 5.0f);
    return Sky(glm::vec3(1.0f, 0.5f, 2.0f), std::move(image), 30.0f);
}

/// Solid angle of a texel of row y in a width × height image.
double texelSolidAngle(uint32_t y, uint32_t width, uint32_t height) {
    return 2.0 * kPi / width * (std::cos(kPi * y / height) - std::cos(kPi * (y + 1) / height));
}

TEST(SkySampler, TexelsComeInProportionToLuminanceTimesSolidAngle) {
    // 32 texels, one black: χ² of the counts per texel against N·luminance·Ω/Σ(luminance·Ω)
    // over the 31 others stays below 61.1 (the 0.1 % quantile of 30 degrees of freedom) and the
    // black texel is never drawn. Each sample's density is the luminance over Σ(luminance·Ω).
    const Sky sky = checkerSky();
    const SkySampler sampler(sky);
    constexpr uint32_t kWidth = 8, kHeight = 4;
    double total = 0.0;
    for (uint32_t y = 0; y < kHeight; ++y)
        for (uint32_t x = 0; x < kWidth; ++x)
            total +=
                double(luminance(sky.texelRadiance(x, y))) * texelSolidAngle(y, kWidth, kHeight);

    constexpr int kSamples = 200000;
    std::vector<int> counts(kWidth * kHeight, 0);
    const glm::vec3 normal = glm::normalize(glm::vec3(0.2f, 1.0f, -0.3f));
    Rng rng(17);
    int mismatched = 0;
    for (int i = 0; i < kSamples; ++i) {
        const float u1 = rng.uniform(), u2 = rng.uniform(), u3 = rng.uniform(), u4 = rng.uniform();
        const SkySampler::Sample s = sampler.sample(normal, u1, u2, u3, u4);
        ASSERT_GT(s.pdf, 0.0f);
        ASSERT_NEAR(glm::length(s.direction), 1.0f, 1e-5f);
        const glm::vec2 uv = sky.uv(s.direction);
        const uint32_t x = std::min(uint32_t(uv.x * kWidth), kWidth - 1);
        const uint32_t y = std::min(uint32_t(uv.y * kHeight), kHeight - 1);
        ++counts[y * kWidth + x];
        // Round-off may put a direction on a texel's edge into its neighbour; rarely.
        if (s.radiance != sky.radiance(s.direction) ||
            std::abs(s.pdf - sampler.pdf(normal, s.direction)) > 1e-5f * s.pdf) {
            ++mismatched;
            continue;
        }
        EXPECT_NEAR(s.pdf, luminance(s.radiance) / total, 1e-5 * s.pdf);
    }
    EXPECT_LT(mismatched, 10);

    double chiSquare = 0.0;
    for (uint32_t y = 0; y < kHeight; ++y)
        for (uint32_t x = 0; x < kWidth; ++x) {
            const double p = double(luminance(sky.texelRadiance(x, y))) *
                             texelSolidAngle(y, kWidth, kHeight) / total;
            const int count = counts[y * kWidth + x];
            if (p == 0.0) {
                EXPECT_EQ(count, 0) << x << "," << y;
                continue;
            }
            const double expected = kSamples * p;
            chiSquare += (count - expected) * (count - expected) / expected;
        }
    EXPECT_LT(chiSquare, 61.1);
    EXPECT_EQ(sampler.pdf(normal, sky.direction((5 + 0.5f) / 8.0f, (2 + 0.5f) / 4.0f)), 0.0f);
}

TEST(SkySampler, DensityIntegratesToOneOverTheSphere) {
    // Σ over equal-solid-angle cells of pdf·dω = 1 (the black texel's cells add nothing).
    const Sky sky = checkerSky();
    const SkySampler sampler(sky);
    const glm::vec3 normal(0.0f, 1.0f, 0.0f);
    constexpr int kZ = 1000, kPhi = 2000;
    double sum = 0.0;
    for (int i = 0; i < kZ; ++i)
        for (int j = 0; j < kPhi; ++j) {
            const double z = 1.0 - 2.0 * (i + 0.5) / kZ, phi = 2.0 * kPi * (j + 0.5) / kPhi;
            const double r = std::sqrt(1.0 - z * z);
            const glm::vec3 w(float(r * std::cos(phi)), float(z), float(r * std::sin(phi)));
            sum += sampler.pdf(normal, w);
        }
    EXPECT_NEAR(sum * 4.0 * kPi / (kZ * kPhi), 1.0, 2e-3);
}

TEST(SkySampler, ConstantSkyIsSampledByTheCosine) {
    const Sky sky(glm::vec3(2.0f, 1.0f, 0.5f), nullptr, 0.0f);
    const SkySampler sampler(sky);
    const glm::vec3 normal = glm::normalize(glm::vec3(1.0f, 2.0f, 3.0f));
    Rng rng(5);
    double cosine = 0.0;
    constexpr int kSamples = 100000;
    for (int i = 0; i < kSamples; ++i) {
        const float u1 = rng.uniform(), u2 = rng.uniform();
        const SkySampler::Sample s = sampler.sample(normal, u1, u2, 0.5f, 0.5f);
        const float c = glm::dot(normal, s.direction);
        ASSERT_GE(c, -1e-6f);
        EXPECT_NEAR(s.pdf, std::max(0.0f, c) / float(kPi), 1e-6f);
        EXPECT_EQ(s.radiance, glm::vec3(2.0f, 1.0f, 0.5f));
        EXPECT_EQ(sampler.pdf(normal, s.direction), s.pdf);
        cosine += c;
    }
    // E[cos θ] under the density cos θ/π is 2/3.
    EXPECT_NEAR(cosine / kSamples, 2.0 / 3.0, 3e-3);
    EXPECT_EQ(sampler.pdf(normal, -normal), 0.0f);
}

}  // namespace
}  // namespace pic
