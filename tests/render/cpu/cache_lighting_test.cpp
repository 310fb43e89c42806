// The cache-lighting CPU twin (render/cpu/cache_lighting.h) on caches with known links: an
// RTP link projects its node's cone (against quadrature and the closed form, with the YCoCg
// band split), links summed in lanes equal them added one by one, a tiny cone is a point
// source, and SH links pass their coefficients through, losing only their half-float rounding.

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "core/bake_data.h"
#include "core/cache_values.h"
#include "core/color.h"
#include "core/geometry.h"
#include "core/sh.h"
#include "render/cpu/cache_lighting.h"
#include "render/node_spread.h"

namespace pic {
namespace {

constexpr double kPi = std::numbers::pi;


/// A bake of `caches` caches (one by default) over a hierarchy of `surfels` leaves with nL links
/// each of the given mode.
BakeData oneCacheBake(LinkMode mode, uint32_t bandsY, uint32_t bandsC, uint32_t nL,
                      uint32_t surfels, uint32_t caches = 1) {
    BakeData bake;
    bake.params.bandsY = bandsY;
    bake.params.bandsC = bandsC;
    bake.params.linkMode = mode;
    bake.surfels.resize(surfels);
    bake.nodes.resize(2 * surfels - 1);
    for (Node& node : bake.nodes) node.left = node.right = kNoNode;
    bake.caches.resize(caches);
    const size_t links = size_t{nL} * caches;
    bake.links.mode = mode;
    bake.links.linksPerCache = nL;
    bake.links.tint.assign(links, kNeutralLinkTint);
    bake.links.offset.assign(links * 3, 0);
    bake.links.spreadShare.assign(links, encodeSpreadShare(1.0f));
    if (mode == LinkMode::Sh) {
        bake.links.bands = bandsY;
        bake.links.shNodes.assign(links, 0u);
        bake.links.shCoefficients.assign(links * bandsY * bandsY, floatToHalf(0.0f));
    } else {
        bake.links.rtp.assign(links, RtpLink{0, 0.0f, 0, 0.0f});
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

TEST(CacheLighting, RtpLinksSumInLanesAsOneByOne) {
    // Three caches of 70 links each (a block of 64 and a short one; 70 is no multiple of the
    // four lanes, so lanes read the next cache's links and past the last), random nodes,
    // directions, cones and factors, every fifth link padding: each cache is the sum of its
    // links' cones added one by one (core/sh.h shAddCone), tinted ones included.
    const uint32_t bandsY = 3, bandsC = 2, nL = 70, caches = 3, surfels = 5;
    BakeData bake = oneCacheBake(LinkMode::Rtp, bandsY, bandsC, nL, surfels, caches);
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f), signedUnit(-1.0f, 1.0f);
    std::vector<glm::vec3> nodeFlux(bake.nodes.size());
    for (auto& flux : nodeFlux) flux = glm::vec3(unit(rng), unit(rng), unit(rng)) * 5.0f;
    std::vector<float> expectedY(size_t{caches} * 9, 0.0f), expectedCo(size_t{caches} * 4, 0.0f),
        expectedCg(size_t{caches} * 4, 0.0f);
    for (uint32_t slot = 0; slot < caches * nL; ++slot) {
        if (slot % 5 == 4) continue;  // padding: factor 0
        const uint32_t node = uint32_t(rng() % surfels);
        const glm::vec3 direction =
            glm::normalize(glm::vec3(signedUnit(rng), signedUnit(rng), signedUnit(rng)) + 1e-3f);
        const float factor = unit(rng), u = 0.05f + unit(rng);
        bake.links.rtp[slot] = RtpLink{node, factor, encodeOctahedral(direction), u};
        glm::vec3 rgb = nodeFlux[node];
        if (slot % 7 == 0) {
            bake.links.tint[slot] = encodeLinkTint(glm::vec3(0.9f, 0.5f, 0.2f)).code;
            rgb *= decodeLinkTint(bake.links.tint[slot]);
        }
        const glm::vec3 flux = rgbToYCoCg(rgb);
        const glm::vec3 d = decodeOctahedral(bake.links.rtp[slot].directionOct);
        const size_t c = slot / nL;
        shAddCone(int(bandsY), d, u, flux.x * factor, &expectedY[c * 9]);
        shAddCone(int(bandsC), d, u, flux.y * factor, &expectedCo[c * 4]);
        shAddCone(int(bandsC), d, u, flux.z * factor, &expectedCg[c * 4]);
    }
    CacheValues values;
    lightCaches(bake, nodeFlux, values);
    ASSERT_EQ(values.cacheCount(), caches);
    for (uint32_t c = 0; c < caches; ++c) {
        const float scale = std::abs(expectedY[c * 9]);
        for (int i = 0; i < 9; ++i)
            EXPECT_NEAR(values.y[c * 9 + i], expectedY[c * 9 + i], 1e-5f * scale)
                << "cache " << c << " Y " << i;
        for (int i = 0; i < 4; ++i) {
            EXPECT_NEAR(values.co[c * 4 + i], expectedCo[c * 4 + i], 1e-5f * scale)
                << "cache " << c << " Co " << i;
            EXPECT_NEAR(values.cg[c * 4 + i], expectedCg[c * 4 + i], 1e-5f * scale)
                << "cache " << c << " Cg " << i;
        }
    }
}

TEST(CacheLighting, EveryColourReachesTheIrradianceAlongTheNormalThroughTheLumasBands) {
    // A light-map cache facing +z and a grid cache, 40 random links each in both link forms,
    // red, green and blue light from different directions (tints): the light-map cache's
    // irradiance along its normal is, per RGB channel, the clamped-cosine convolution of its
    // links' lY-band projections; the grid cache's is 0. Through the stored SH, whose chroma
    // keeps lC = 2 bands, the colours come out bent.
    const uint32_t bandsY = 3, bandsC = 2, nL = 40, surfels = 3;
    const glm::vec3 normal(0.0f, 0.0f, 1.0f);
    for (const LinkMode mode : {LinkMode::Rtp, LinkMode::Sh}) {
        BakeData bake = oneCacheBake(mode, bandsY, bandsC, nL, surfels, 2);
        bake.caches[0].kind = gpu::kCacheKindLightmap;
        bake.caches[0].normal = normal;
        std::mt19937 rng(5);
        std::uniform_real_distribution<float> unit(0.0f, 1.0f), signedUnit(-1.0f, 1.0f);
        std::vector<glm::vec3> nodeFlux(bake.nodes.size(), glm::vec3(2.0f));
        const glm::vec3 tints[3] = {{1.0f, 0.1f, 0.1f}, {0.1f, 1.0f, 0.1f}, {0.1f, 0.1f, 1.0f}};
        std::array<std::array<float, 9>, 3> rgbSh{};  // the light-map cache's, lY bands per channel
        for (uint32_t slot = 0; slot < 2 * nL; ++slot) {
            const uint32_t node = uint32_t(rng() % surfels);
            const int colour = int(slot % 3);
            // Each colour from its own side of the hemisphere.
            const glm::vec3 direction =
                glm::normalize(glm::vec3(float(colour - 1) + 0.3f * signedUnit(rng),
                                         0.3f * signedUnit(rng), 0.2f + unit(rng)));
            const EncodedLinkTint tint = encodeLinkTint(tints[colour]);
            bake.links.tint[slot] = tint.code;
            std::array<float, 9> projection{};
            if (mode == LinkMode::Rtp) {
                const float factor = 0.2f + unit(rng), u = 0.02f + 0.5f * unit(rng);
                bake.links.rtp[slot] = RtpLink{node, factor, encodeOctahedral(direction), u};
                shAddCone(int(bandsY), decodeOctahedral(bake.links.rtp[slot].directionOct), u,
                          factor, projection.data());
            } else {
                bake.links.shNodes[slot] = node;
                shAddCone(int(bandsY), direction, 0.1f, 0.5f + unit(rng), projection.data());
                for (int i = 0; i < 9; ++i) {
                    bake.links.shCoefficients[slot * 9 + i] = floatToHalf(projection[i]);
                    projection[i] = halfToFloat(bake.links.shCoefficients[slot * 9 + i]);
                }
            }
            if (slot >= nL) continue;  // the grid cache's
            const glm::vec3 rgb = nodeFlux[node] * decodeLinkTint(tint.code);
            for (int c = 0; c < 3; ++c)
                for (int i = 0; i < 9; ++i) rgbSh[c][i] += rgb[c] * projection[i];
        }
        CacheValues values;
        lightCaches(bake, nodeFlux, values);
        ASSERT_EQ(values.irradiance.size(), 2u);
        EXPECT_EQ(values.irradiance[1], glm::vec3(0.0f));
        CacheStencil one;
        one.count = 1;
        one.weight[0] = 1.0f;
        const glm::vec3 throughSh = irradiance(blendCaches(values, one), normal);
        float bent = 0.0f;
        for (int c = 0; c < 3; ++c) {
            const float expected = shIrradiance(int(bandsY), rgbSh[c].data(), normal);
            EXPECT_NEAR(values.irradiance[0][c], expected, 1e-4f * expected)
                << "channel " << c << (mode == LinkMode::Rtp ? " rtp" : " sh");
            bent = std::max(bent, std::abs(throughSh[c] / expected - 1.0f));
        }
        EXPECT_GT(bent, 0.01f) << "the stored SH should bend some colour by more than 1 %";
    }
}

/// oneCacheBake with lY = lC = 2 and one link to node 0: an RTP cone towards +y, or four SH
/// coefficients.
BakeData oneLinkBake(LinkMode mode) {
    BakeData bake = oneCacheBake(mode, 2, 2, 1, 1);
    if (mode == LinkMode::Rtp) {
        bake.links.rtp[0] = RtpLink{0, 0.5f, encodeOctahedral(glm::vec3(0, 1, 0)), 0.2f};
    } else {
        const float c[4] = {0.5f, 0.25f, -0.125f, 0.75f};
        for (int i = 0; i < 4; ++i) bake.links.shCoefficients[i] = floatToHalf(c[i]);
    }
    return bake;
}

TEST(CacheLighting, ALinksTintMultipliesItsNodesFluxPerChannel) {
    // The same link with and without a tint (bake/link_generation.h): every RGB coefficient of
    // the tinted cache is the neutral one's times the tint, in both link forms.
    const glm::vec3 tint(0.25f, 1.0f, 0.5f);
    const uint32_t code = encodeLinkTint(tint).code;
    const glm::vec3 decoded = decodeLinkTint(code);
    for (const LinkMode mode : {LinkMode::Rtp, LinkMode::Sh}) {
        BakeData bake = oneLinkBake(mode);
        const std::vector<glm::vec3> nodeFlux = {glm::vec3(3.0f, 2.0f, 1.0f)};
        CacheValues neutral, tinted;
        lightCaches(bake, nodeFlux, neutral);
        bake.links.tint[0] = code;
        lightCaches(bake, nodeFlux, tinted);
        for (int i = 0; i < 4; ++i) {
            const glm::vec3 a = yCoCgToRgb({neutral.y[i], neutral.co[i], neutral.cg[i]});
            const glm::vec3 b = yCoCgToRgb({tinted.y[i], tinted.co[i], tinted.cg[i]});
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(b[c], a[c] * decoded[c], 1e-5f * std::abs(a[c]) + 1e-7f)
                    << (mode == LinkMode::Rtp ? "rtp" : "sh") << " coefficient " << i << " channel " << c;
        }
    }
}

TEST(CacheLighting, AnExponentialNodeIsReadAtTheLinksPointAndSpreadShare) {
    // Through an exponential node (render/node_spread.h) a link at box point u with spread share
    // ρ carries centre ∘ exp(slopes·u − (1 − ρ)·ln Z) per channel: the same cache as a linear
    // node holding that flux evenly, in both link forms, tinted or not.
    const glm::vec3 u(0.5f, -0.25f, 1.0f);
    const glm::vec3 centre(2.0f, 1.0f, 0.5f), concentration(0.3f, 0.8f, 0.1f);
    glm::mat3 slopes;  // column c: channel c's slopes along the three axes
    slopes[0] = {1.5f, -0.5f, 0.2f};
    slopes[1] = {-2.0f, 0.5f, 0.0f};
    slopes[2] = {0.0f, 0.0f, 3.0f};
    for (const LinkMode mode : {LinkMode::Rtp, LinkMode::Sh}) {
        for (const uint32_t tint : {kNeutralLinkTint, encodeLinkTint({0.25f, 1.0f, 0.5f}).code}) {
            BakeData bake = oneLinkBake(mode);
            bake.links.tint[0] = tint;
            bake.links.spreadShare[0] = encodeSpreadShare(0.25f);
            LinkTable table = unpackLinks(bake, nodeSpread(bake));
            EXPECT_FLOAT_EQ(table.concentrationWeight[0],
                            1.0f - decodeSpreadShare(encodeSpreadShare(0.25f)));
            table.points[0] = u;  // a leaf has no box: put the link inside one
            const float rho = decodeSpreadShare(bake.links.spreadShare[0]);
            std::vector<NodeLight> exponential(1), even(1);
            nodeLight(std::vector<glm::vec3>{centre}, std::vector<glm::mat3>{slopes},
                      std::vector<glm::vec3>{concentration}, std::vector<uint8_t>{1}, exponential);
            glm::vec3 read;
            for (int c = 0; c < 3; ++c)
                read[c] = centre[c] * std::exp(glm::dot(slopes[c], u) - (1.0f - rho) * concentration[c]);
            nodeLight(std::vector<glm::vec3>{read}, std::vector<glm::mat3>{glm::mat3(0.0f)},
                      std::vector<glm::vec3>{glm::vec3(0.0f)}, std::vector<uint8_t>{0}, even);
            CacheValues a, b;
            lightCaches(bake, exponential, table, a);
            lightCaches(bake, even, table, b);
            for (int i = 0; i < 4; ++i) {
                EXPECT_NEAR(a.y[i], b.y[i], 1e-5f * std::abs(b.y[i]) + 1e-7f) << "coefficient " << i;
                EXPECT_NEAR(a.co[i], b.co[i], 1e-5f * std::abs(b.y[i]) + 1e-7f) << "coefficient " << i;
                EXPECT_NEAR(a.cg[i], b.cg[i], 1e-5f * std::abs(b.y[i]) + 1e-7f) << "coefficient " << i;
            }
            EXPECT_GT(std::abs(b.y[0]), 0.0f);
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

}  // namespace
}  // namespace pic
