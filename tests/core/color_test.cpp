#include "core/color.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

namespace pic {
namespace {

/// Deterministic pseudo-random floats in [0, 1) (64-bit LCG, top 24 bits).
class Lcg {
public:
    float next() {
        mState = mState * 6364136223846793005ull + 1442695040888963407ull;
        return float(mState >> 40) * 0x1p-24f;
    }

private:
    uint64_t mState = 0x2545F4914F6CDD1Dull;
};

/// Value of binary16 bits from the IEEE definition, independent of halfToFloat.
double halfReference(uint16_t bits) {
    const int exponent = (bits >> 10) & 0x1f;
    const int mantissa = bits & 0x3ff;
    const double sign = (bits & 0x8000) ? -1.0 : 1.0;
    if (exponent == 0) return sign * std::ldexp(double(mantissa), -24);
    if (exponent == 31)
        return mantissa ? std::numeric_limits<double>::quiet_NaN()
                        : sign * std::numeric_limits<double>::infinity();
    return sign * std::ldexp(1.0 + mantissa / 1024.0, exponent - 15);
}

bool isHalfNan(uint16_t bits) {
    return (bits & 0x7c00) == 0x7c00 && (bits & 0x3ff) != 0;
}

TEST(YCoCg, MatchesPaperEquation) {
    Lcg rng;
    for (int i = 0; i < 1000; ++i) {
        const glm::vec3 rgb(rng.next() * 10.0f, rng.next() * 10.0f, rng.next() * 10.0f);
        const glm::vec3 ycocg = rgbToYCoCg(rgb);
        EXPECT_NEAR(ycocg.x, rgb.r / 4 + rgb.g / 2 + rgb.b / 4, 1e-5f);
        EXPECT_NEAR(ycocg.y, (rgb.r - rgb.b) / 2, 1e-5f);
        EXPECT_NEAR(ycocg.z, (-rgb.r + 2 * rgb.g - rgb.b) / 4, 1e-5f);
    }
    // Grey has no chroma; primaries land where the matrix says.
    EXPECT_EQ(rgbToYCoCg({3, 3, 3}), glm::vec3(3, 0, 0));
    EXPECT_EQ(rgbToYCoCg({1, 0, 0}), glm::vec3(0.25f, 0.5f, -0.25f));
    EXPECT_EQ(rgbToYCoCg({0, 1, 0}), glm::vec3(0.5f, 0.0f, 0.5f));
    EXPECT_EQ(rgbToYCoCg({0, 0, 1}), glm::vec3(0.25f, -0.5f, -0.25f));
}

TEST(YCoCg, InverseIsExact) {
    // Dyadic inputs with few bits make every lifting step exact: the round trip is bit-exact.
    for (int r = 0; r < 16; ++r)
        for (int g = 0; g < 16; ++g)
            for (int b = 0; b < 16; ++b) {
                const glm::vec3 rgb(r * 0.25f - 1.0f, g * 0.5f, b * 0.125f);
                ASSERT_EQ(yCoCgToRgb(rgbToYCoCg(rgb)), rgb);
            }
    // Arbitrary HDR inputs: only float rounding remains, and the inverse undoes the forward
    // transform also from the YCoCg side.
    Lcg rng;
    for (int i = 0; i < 10000; ++i) {
        const glm::vec3 rgb(rng.next() * 100.0f, rng.next() * 100.0f, rng.next() * 100.0f);
        const glm::vec3 back = yCoCgToRgb(rgbToYCoCg(rgb));
        const float scale = std::max({rgb.r, rgb.g, rgb.b});
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(back[c], rgb[c], 4e-7f * scale);
        const glm::vec3 ycocg(rng.next() * 10.0f, rng.next() - 0.5f, rng.next() - 0.5f);
        const glm::vec3 forth = rgbToYCoCg(yCoCgToRgb(ycocg));
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(forth[c], ycocg[c], 4e-6f);
    }
}

TEST(HalfFloat, EveryPatternRoundTrips) {
    for (uint32_t pattern = 0; pattern <= 0xffff; ++pattern) {
        const auto bits = uint16_t(pattern);
        const float value = halfToFloat(bits);
        const double reference = halfReference(bits);
        if (isHalfNan(bits)) {
            ASSERT_TRUE(std::isnan(value)) << std::hex << pattern;
            // The payload moves to the float's top mantissa bits unchanged (no quieting).
            ASSERT_EQ(std::bit_cast<uint32_t>(value), (uint32_t(bits & 0x8000) << 16) |
                                                          0x7f800000u |
                                                          (uint32_t(bits & 0x3ff) << 13))
                << std::hex << pattern;
            const uint16_t back = floatToHalf(value);
            ASSERT_TRUE(isHalfNan(back)) << std::hex << pattern;
            ASSERT_EQ(back & 0x8000, bits & 0x8000);
            // Quiet NaNs keep their payload; signalling ones come back quiet.
            ASSERT_EQ(back, bits | 0x200) << std::hex << pattern;
            continue;
        }
        ASSERT_EQ(double(value), reference) << std::hex << pattern;
        ASSERT_EQ(std::signbit(value), (bits & 0x8000) != 0);
        ASSERT_EQ(floatToHalf(value), bits) << std::hex << pattern;
    }
}

TEST(HalfFloat, RoundsToNearestEven) {
    // Between each pair of neighbouring non-negative halves, the midpoint (exact in float)
    // rounds to the even one and anything off the midpoint to the nearer one.
    for (uint16_t lower = 0; lower < 0x7bff; ++lower) {
        const auto upper = uint16_t(lower + 1);
        const float a = halfToFloat(lower);
        const float b = halfToFloat(upper);
        const float mid = 0.5f * (a + b);
        ASSERT_EQ(double(mid), 0.5 * (double(a) + double(b)));
        const uint16_t even = (lower & 1) ? upper : lower;
        ASSERT_EQ(floatToHalf(mid), even) << std::hex << lower;
        ASSERT_EQ(floatToHalf(std::nextafter(mid, 0.0f)), lower) << std::hex << lower;
        ASSERT_EQ(floatToHalf(std::nextafter(mid, 1e9f)), upper) << std::hex << lower;
        ASSERT_EQ(floatToHalf(-mid), uint16_t(even | 0x8000));
    }
}

TEST(HalfFloat, OverflowUnderflowAndSpecials) {
    const float inf = std::numeric_limits<float>::infinity();
    EXPECT_EQ(floatToHalf(65504.0f), 0x7bff);
    EXPECT_EQ(floatToHalf(65519.99f), 0x7bff);
    EXPECT_EQ(floatToHalf(65520.0f), 0x7c00);  // the tie rounds to even: inf
    EXPECT_EQ(floatToHalf(1e10f), 0x7c00);
    EXPECT_EQ(floatToHalf(-3e38f), 0xfc00);
    EXPECT_EQ(floatToHalf(inf), 0x7c00);
    EXPECT_EQ(floatToHalf(-inf), 0xfc00);
    EXPECT_TRUE(isHalfNan(floatToHalf(std::numeric_limits<float>::quiet_NaN())));
    // A float NaN whose payload lies only in the low bits must not turn into inf.
    EXPECT_TRUE(isHalfNan(floatToHalf(std::bit_cast<float>(0x7f800001u))));
    EXPECT_EQ(floatToHalf(-0.0f), 0x8000);
    EXPECT_EQ(floatToHalf(0x1p-24f), 0x0001);  // smallest subnormal
    EXPECT_EQ(floatToHalf(0x1p-25f), 0x0000);  // tie with 0 -> even (0)
    EXPECT_EQ(floatToHalf(std::nextafter(0x1p-25f, 1.0f)), 0x0001);
    EXPECT_EQ(floatToHalf(1.5f * 0x1p-24f), 0x0002);      // tie 1.5 -> 2
    EXPECT_EQ(floatToHalf(0x1p-14f - 0x1p-25f), 0x0400);  // carries into the normals
    EXPECT_EQ(floatToHalf(1e-40f), 0x0000);               // float subnormal
    EXPECT_EQ(floatToHalf(1.0f), 0x3c00);
    EXPECT_EQ(floatToHalf(-2.0f), 0xc000);
    EXPECT_EQ(floatToHalf(1.0f + 0x1p-11f), 0x3c00);      // tie, 1.0 is even
    EXPECT_EQ(floatToHalf(1.0f + 3 * 0x1p-11f), 0x3c02);  // tie, rounds up to even
}

TEST(HalfFloat, ClampedNeverStoresInfinity) {
    const float inf = std::numeric_limits<float>::infinity();
    EXPECT_EQ(floatToHalfClamped(65520.0f), 0x7bff);
    EXPECT_EQ(floatToHalfClamped(1e30f), 0x7bff);
    EXPECT_EQ(floatToHalfClamped(-1e30f), 0xfbff);
    EXPECT_EQ(floatToHalfClamped(inf), 0x7bff);
    EXPECT_EQ(floatToHalfClamped(-inf), 0xfbff);
    EXPECT_TRUE(isHalfNan(floatToHalfClamped(std::numeric_limits<float>::quiet_NaN())));
    // Everything that fits is converted exactly like floatToHalf.
    for (uint32_t pattern = 0; pattern <= 0xffff; ++pattern) {
        const auto bits = uint16_t(pattern);
        if ((bits & 0x7c00) == 0x7c00) continue;
        ASSERT_EQ(floatToHalfClamped(halfToFloat(bits)), bits);
    }
}

/// Deterministic, well spread unit vectors (Fibonacci sphere).
std::vector<glm::vec3> fibonacciDirections(int count) {
    std::vector<glm::vec3> directions;
    const double goldenAngle = std::numbers::pi * (3.0 - std::sqrt(5.0));
    for (int i = 0; i < count; ++i) {
        const double z = 1.0 - (2.0 * i + 1.0) / count;
        const double r = std::sqrt(1.0 - z * z);
        directions.emplace_back(float(r * std::cos(goldenAngle * i)),
                                float(r * std::sin(goldenAngle * i)), float(z));
    }
    return directions;
}

/// Angle in radians between two unit vectors, accurate for tiny angles.
double angleBetween(const glm::vec3& a, const glm::vec3& b) {
    const glm::dvec3 da(a), db(b);
    return std::atan2(glm::length(glm::cross(da, db)), glm::dot(da, db));
}

TEST(Octahedral, MaxAngularErrorIsSmall) {
    std::vector<glm::vec3> directions = fibonacciDirections(1 << 20);
    // Axes, diagonals and the folds of the octahedron, where the mapping is least smooth.
    for (int sx = -1; sx <= 1; ++sx)
        for (int sy = -1; sy <= 1; ++sy)
            for (int sz = -1; sz <= 1; ++sz)
                if (sx || sy || sz) directions.push_back(glm::normalize(glm::vec3(sx, sy, sz)));
    directions.push_back(glm::normalize(glm::vec3(1e-4f, -1.0f, -1e-4f)));
    double maxError = 0.0;
    for (const glm::vec3& d : directions) {
        const glm::vec3 decoded = decodeOctahedral(encodeOctahedral(d));
        ASSERT_NEAR(glm::length(decoded), 1.0f, 1e-6f);
        maxError = std::max(maxError, angleBetween(d, decoded));
    }
    EXPECT_LT(maxError, 1e-4);
    EXPECT_GT(maxError, 1e-6);  // 16-bit quantisation is visible: the test measures something
}

TEST(Octahedral, LayoutAndDegenerateInputs) {
    // x lives in the low 16 bits as snorm16.
    EXPECT_EQ(encodeOctahedral({1, 0, 0}), 0x00007fffu);
    EXPECT_EQ(encodeOctahedral({0, 1, 0}), 0x7fff0000u);
    EXPECT_EQ(encodeOctahedral({0, 0, 1}), 0u);
    EXPECT_EQ(decodeOctahedral(0x00007fffu), glm::vec3(1, 0, 0));
    EXPECT_EQ(decodeOctahedral(encodeOctahedral({0, 0, -1})), glm::vec3(0, 0, -1));
    // Scale does not matter; zero and non-finite vectors become +z instead of NaN.
    EXPECT_EQ(encodeOctahedral({3, -4, 12}), encodeOctahedral(glm::vec3(3, -4, 12) / 13.0f));
    EXPECT_EQ(encodeOctahedral({0, 0, 0}), encodeOctahedral({0, 0, 1}));
    EXPECT_EQ(encodeOctahedral({std::nanf(""), 0, 0}), encodeOctahedral({0, 0, 1}));
    EXPECT_EQ(encodeOctahedral({std::numeric_limits<float>::infinity(), 0, 0}),
              encodeOctahedral({0, 0, 1}));
    // Every code decodes to a unit vector, including -32768 which snorm clamps to -1.
    for (const uint32_t code : {0x80008000u, 0x7fff8000u, 0xffffffffu, 0x12345678u})
        EXPECT_NEAR(glm::length(decodeOctahedral(code)), 1.0f, 1e-6f);
}

TEST(LinkTint, ScaleTimesCodeIsTheTintWithinHalfAStep) {
    Lcg rng;
    for (int i = 0; i < 10000; ++i) {
        // Tints over four decades, channels independent (a black or saturated surface gives 0).
        const float magnitude = std::exp2(-6.0f + 13.0f * rng.next());
        glm::vec3 tint = magnitude * glm::vec3(rng.next(), rng.next(), rng.next());
        if (i % 7 == 0) tint[i % 3] = 0.0f;
        const EncodedLinkTint e = encodeLinkTint(tint);
        const glm::vec3 back = e.scale * decodeLinkTint(e.code);
        const float largest = std::max({tint.r, tint.g, tint.b});
        EXPECT_EQ(e.scale, largest);
        EXPECT_EQ(e.code >> 30, 0u);
        for (int c = 0; c < 3; ++c)
            ASSERT_LE(std::abs(back[c] - tint[c]), largest * (1.0001f / 2046.0f)) << i << " " << c;
    }
}

TEST(LinkTint, LayoutNeutralAndDegenerateInputs) {
    // R in bits 0-9, G 10-19, B 20-29.
    EXPECT_EQ(encodeLinkTint({1.0f, 0.0f, 0.0f}).code, 0x3FFu);
    EXPECT_EQ(encodeLinkTint({0.0f, 2.0f, 0.0f}).code, 0x3FFu << 10);
    EXPECT_EQ(encodeLinkTint({0.0f, 0.0f, 0.5f}).code, 0x3FFu << 20);
    const EncodedLinkTint grey = encodeLinkTint(glm::vec3(3.5f));
    EXPECT_EQ(grey.code, kNeutralLinkTint);
    EXPECT_EQ(grey.scale, 3.5f);
    EXPECT_EQ(decodeLinkTint(kNeutralLinkTint), glm::vec3(1.0f));
    // Nothing to carry: code 0, scale 0; negative and non-finite channels count as 0.
    for (const glm::vec3 t : {glm::vec3(0.0f), glm::vec3(-1.0f), glm::vec3(NAN, 0.0f, -INFINITY)}) {
        const EncodedLinkTint e = encodeLinkTint(t);
        EXPECT_EQ(e.code, 0u);
        EXPECT_EQ(e.scale, 0.0f);
    }
    const EncodedLinkTint partly = encodeLinkTint({NAN, 2.0f, -1.0f});
    EXPECT_EQ(partly.code, 0x3FFu << 10);
    EXPECT_EQ(partly.scale, 2.0f);
}

TEST(Rgbe8, ErrorIsBoundedOverAFloatsRange) {
    Lcg rng;
    double maxRelative = 0.0;
    for (int i = 0; i < 100000; ++i) {
        // Log-uniform magnitudes from 2^-99 to 2^126, then independent channel ratios.
        const float magnitude = std::exp2(-99.0f + 225.0f * rng.next());
        const glm::vec3 rgb = magnitude * glm::vec3(rng.next(), rng.next(), rng.next());
        const glm::vec3 back = unpackRgbe8(packRgbe8(rgb));
        const float maxChannel = std::max({rgb.r, rgb.g, rgb.b});
        if (maxChannel < 0x1p-100f) continue;  // stored as 0
        const double relative =
            std::abs(std::max({back.r, back.g, back.b}) - maxChannel) / maxChannel;
        maxRelative = std::max(maxRelative, relative);
        // The largest channel's mantissa is at least 128, so a step is at most 2^-7 of it and
        // every channel, rounded to the nearest step, is within 2^-8 of it.
        for (int c = 0; c < 3; ++c)
            ASSERT_LE(std::abs(back[c] - rgb[c]), maxChannel * 0x1p-8f) << i << " " << c;
    }
    EXPECT_LE(maxRelative, 0x1p-8 * 1.0001);
    EXPECT_GT(maxRelative, 0x1p-10);
}

TEST(Rgbe8, LayoutExactValuesAndClamping) {
    // 1.0 = 128 · 2^-7: exponent byte 1 + 128 = 129, mantissa 128.
    EXPECT_EQ(packRgbe8({1, 0, 0}), (129u << 24) | 128u);
    EXPECT_EQ(packRgbe8({0, 0.5f, 0}), (128u << 24) | (128u << 8));
    EXPECT_EQ(packRgbe8({0, 0, 0}), 0u);
    EXPECT_EQ(unpackRgbe8(0u), glm::vec3(0));
    for (const glm::vec3 exact : {glm::vec3(1, 0.5f, 0.25f), glm::vec3(3, 96, 1),
                                  glm::vec3(kRgbe8Max, 0, 0x1p119f), glm::vec3(0x1p-100f, 0, 0)})
        EXPECT_EQ(unpackRgbe8(packRgbe8(exact)), exact);
    // Rounding 255.9 up needs the next exponent.
    EXPECT_EQ(unpackRgbe8(packRgbe8({255.9f, 0, 0})), glm::vec3(256, 0, 0));
    const float inf = std::numeric_limits<float>::infinity();
    EXPECT_EQ(unpackRgbe8(packRgbe8({-1.0f, std::nanf(""), 2.0f})), glm::vec3(0, 0, 2));
    EXPECT_EQ(unpackRgbe8(packRgbe8({0, inf, -inf})), glm::vec3(0, kRgbe8Max, 0));
    EXPECT_EQ(packRgbe8({1e-31f, 5e-32f, 0}), 0u);
    EXPECT_EQ(unpackRgbe8(0xffffffffu), glm::vec3(kRgbe8Max));
    // Radiance far past a half float's range (a 50,000 cd lamp 0.4 m from a wall) keeps its
    // value instead of clamping.
    const glm::vec3 bright(2e5f, 1e5f, 5e4f);
    const glm::vec3 back = unpackRgbe8(packRgbe8(bright));
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(back[c], bright[c], 2e5f * 0x1p-8f);
}

TEST(Luminance, Rec709Weights) {
    EXPECT_NEAR(luminance({1, 1, 1}), 1.0f, 1e-6f);
    EXPECT_FLOAT_EQ(luminance({1, 0, 0}), 0.2126f);
    EXPECT_FLOAT_EQ(luminance({0, 1, 0}), 0.7152f);
    EXPECT_FLOAT_EQ(luminance({0, 0, 1}), 0.0722f);
    EXPECT_FLOAT_EQ(luminance({2, 4, 8}), 2 * 0.2126f + 4 * 0.7152f + 8 * 0.0722f);
}

}  // namespace
}  // namespace pic
