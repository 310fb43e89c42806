// The cache-lighting pass on lavapipe (or the machine's GPU): its link packing, and the caches
// it lights against its CPU twin (render/cpu/cache_lighting.h) for every link form and band
// split, per subgroup or per invocation, links read in wide texels or a word at a time.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <tuple>
#include <vector>

#include "core/color.h"
#include "core/light_set.h"
#include "render/cpu/cache_lighting.h"
#include "render/passes/cache_lighting_pass.h"
#include "tests/render/gpu_fixture.h"

namespace pic {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

TEST(GpuCacheLighting, RtpLinksPackIntoSixteenBytes) {
    // factor = V / (π·A) (bake/link_generation.cpp); the GPU keeps V as binary16.
    const float area = 0.37f;
    const uint32_t tint = encodeLinkTint({0.25f, 1.0f, 0.5f}).code;
    const uint32_t point = 0x7F80C1u;  // box point (−63, −128 → −1, 127) / 127
    const glm::vec3 direction = glm::normalize(glm::vec3(0.3f, -0.5f, -0.8f));
    const auto pack = [&](float visible, float oneMinusCos, uint32_t node = 42) {
        const gpu::RtpLink link{node, visible / (kPi * area), encodeOctahedral(direction),
                                oneMinusCos};
        return gpu::packRtpLink(link, tint, point, encodeSpreadShare(0.5f), area);
    };
    const auto visibleOf = [](const gpu::GpuRtpLink& l) {
        return halfToFloat(uint16_t(l.visibleAndCone & 0xFFFFu));
    };
    const auto coneOf = [](const gpu::GpuRtpLink& l) {
        return halfToFloat(uint16_t(l.visibleAndCone >> 16));
    };
    // V above 1: flux weights that favour the part a cache sees (surfel_exposure.h).
    for (const float visible : {5.5f, 1.0f, 0.75f, 0.3f, 1e-3f}) {
        for (const float oneMinusCos : {2.0f, 0.5f, 1e-2f, 3e-5f, 1e-7f}) {
            const gpu::GpuRtpLink l = pack(visible, oneMinusCos);
            EXPECT_EQ(l.nodeAndRed & 0xFFFFFFu, 42u);
            EXPECT_EQ(l.pointAndBlue & 0xFFFFFFu, point);
            // binary16: relative 2^-11 for normal values, 2^-25 absolute below 2^-14.
            EXPECT_NEAR(visibleOf(l), visible, visible / 2048.0f);
            EXPECT_NEAR(coneOf(l), oneMinusCos, std::max(oneMinusCos / 2048.0f, 3e-8f));
        }
    }
    // The tint as unorm8 in the top bytes, within half a step.
    const gpu::GpuRtpLink l = pack(1.0f, 0.1f, (1u << 24) - 1);
    EXPECT_EQ(l.nodeAndRed & 0xFFFFFFu, (1u << 24) - 1);
    const glm::vec3 tint8 =
        glm::vec3(l.nodeAndRed >> 24, l.directionAndGreen >> 24, l.pointAndBlue >> 24) / 255.0f;
    const glm::vec3 expected = decodeLinkTint(tint);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(tint8[c], expected[c], 0.5f / 255.0f + 1e-6f);
    EXPECT_EQ(gpu::packRtpLink({1, 1.0f, 0, 0.1f}, kNeutralLinkTint, 0, 0, 1.0f).nodeAndRed >> 24,
              255u);
    // The spread share's 6-bit code in bits 18-23.
    EXPECT_EQ((l.directionAndGreen >> 18) & 0x3Fu, encodeSpreadShare(0.5f));
    EXPECT_EQ((gpu::packRtpLink({1, 1.0f, 0, 0.1f}, 0, 0, encodeSpreadShare(1.0f), 1.0f)
                   .directionAndGreen >> 18) & 0x3Fu,
              kSpreadShareSteps);
    // The direction as 2 × snorm9, decoded as shaders/lib/sh.glsl decodeOctahedral9 does.
    const auto snorm9 = [](uint32_t bits) {
        return std::max(float(int32_t(bits << 23) >> 23) / 255.0f, -1.0f);
    };
    const uint32_t oct = l.directionAndGreen;
    const float u = snorm9(oct & 0x1FFu), v = snorm9((oct >> 9) & 0x1FFu);
    glm::vec3 decoded(u, v, 1.0f - std::abs(u) - std::abs(v));
    if (decoded.z < 0.0f)
        decoded = {(1.0f - std::abs(v)) * (u >= 0.0f ? 1.0f : -1.0f),
                   (1.0f - std::abs(u)) * (v >= 0.0f ? 1.0f : -1.0f), decoded.z};
    EXPECT_GT(glm::dot(glm::normalize(decoded), direction), std::cos(0.4f * kPi / 180.0f));
    // A link too faint for binary16 keeps its smallest step instead of reading as padding;
    // padding (factor 0) stays 0; V saturates at 65504.
    EXPECT_EQ(pack(1e-9f, 0.1f).visibleAndCone & 0xFFFFu, 1u);
    EXPECT_EQ(pack(0.0f, 0.1f).visibleAndCone & 0xFFFFu, 0u);
    EXPECT_EQ(visibleOf(pack(1e6f, 0.1f)), 65504.0f);

    // SH links: c·π·A in binary16, saturating.
    const float c = 123.5f / (kPi * area);
    EXPECT_NEAR(halfToFloat(gpu::radianceShCoefficient(floatToHalf(c), area)), 123.5f, 0.1f);
    EXPECT_EQ(gpu::radianceShCoefficient(floatToHalf(-60000.0f), 10.0f), floatToHalf(-65504.0f));
    EXPECT_EQ(gpu::radianceShCoefficient(floatToHalf(5.0f), 0.0f), floatToHalf(0.0f));
}

/// Cache lighting for a link form and band split, each cache lit by a subgroup (as on a
/// GPU) or by an invocation (as on a CPU device), the links read in the widest texels the
/// device has or a word at a time.
class GpuCacheLighting : public testing::TestWithParam<
                             std::tuple<std::tuple<LinkMode, uint32_t, uint32_t>, bool, uint32_t>> {
};

TEST_P(GpuCacheLighting, MatchesTheCpuTwinWithinOnePercent) {
    const auto [form, perSubgroup, texelWords] = GetParam();
    const auto [mode, bandsY, bandsC] = form;
    const test::BakedScene& b = test::smallBake("cornell", mode, bandsY, bandsC);
    ASSERT_TRUE(b.ok);
    auto gpu =
        test::gpuFor(b, {}, {.cachePerSubgroup = perSubgroup, .maxLinkTexelWords = texelWords});
    ASSERT_TRUE(gpu);
    // A link is 4 words (RTP) or 3 + ⌈lY²/2⌉ rounded up to a multiple of 4; every device
    // reads single words, and lavapipe texels of 2, 3 and 4 words, of which the pass takes 4
    // or 2 before 3.
    const uint32_t linkWords = mode == LinkMode::Rtp ? 4 : gpu::shLinkWords(bandsY * bandsY);
    EXPECT_EQ(linkWords % gpu->linkTexelWords(), 0u);
    EXPECT_LE(gpu->linkTexelWords(), texelWords);
    if (texelWords == 1) {
        EXPECT_EQ(gpu->linkTexelWords(), 1u);
    }
    if (gpu->context().isCpuDevice() && texelWords == 4) {
        const uint32_t expected = linkWords % 4 == 0   ? 4
                                  : linkWords % 2 == 0 ? 2
                                  : linkWords % 3 == 0 ? 3
                                                       : 1;
        EXPECT_EQ(gpu->linkTexelWords(), expected);
    }
    const std::vector<glm::vec3> nodes = test::cpuNodeFlux(b, defaultLightSet(b.scene));
    CacheValues cpu;
    lightCaches(b.bake, nodes, cpu);
    auto values = gpu->runCacheLighting(nodes);
    ASSERT_TRUE(values) << values.error().message;
    ASSERT_EQ(values->bandsY, bandsY);
    ASSERT_EQ(values->bandsC, bandsC);
    EXPECT_LE(test::relativeL2(*values, cpu), 0.01);
    EXPECT_GT(test::relativeL2(cpu, CacheValues::zeros(cpu.cacheCount(), bandsY, bandsC)), 0.0);
    // The irradiance along the light-map caches' normals (the bounce's), to the same 1 %.
    ASSERT_EQ(values->irradiance.size(), cpu.irradiance.size());
    double difference = 0.0, norm = 0.0;
    for (size_t c = 0; c < cpu.irradiance.size(); ++c) {
        const glm::dvec3 d = glm::dvec3(values->irradiance[c]) - glm::dvec3(cpu.irradiance[c]);
        difference += glm::dot(d, d);
        norm += glm::dot(glm::dvec3(cpu.irradiance[c]), glm::dvec3(cpu.irradiance[c]));
    }
    EXPECT_GT(norm, 0.0);
    EXPECT_LE(std::sqrt(difference / norm), 0.01);
}

INSTANTIATE_TEST_SUITE_P(LinkFormsAndBands, GpuCacheLighting,
                         testing::Combine(testing::Values(std::make_tuple(LinkMode::Rtp, 3u, 2u),
                                                          std::make_tuple(LinkMode::Rtp, 4u, 1u),
                                                          std::make_tuple(LinkMode::Rtp, 2u, 2u),
                                                          std::make_tuple(LinkMode::Sh, 3u, 2u),
                                                          std::make_tuple(LinkMode::Sh, 4u, 2u),
                                                          std::make_tuple(LinkMode::Sh, 1u, 1u)),
                                          testing::Bool(), testing::Values(4u)));
INSTANTIATE_TEST_SUITE_P(WordTexels, GpuCacheLighting,
                         testing::Combine(testing::Values(std::make_tuple(LinkMode::Rtp, 3u, 2u),
                                                          std::make_tuple(LinkMode::Sh, 3u, 2u)),
                                          testing::Bool(), testing::Values(1u)));

}  // namespace
}  // namespace pic
