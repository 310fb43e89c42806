#include "core/color.h"

#include <algorithm>
#include <bit>
#include <cmath>

#include <glm/geometric.hpp>

namespace pic {
namespace {

constexpr int kRgbe8MantissaBits = 8;
constexpr int kRgbe8Bias = 128;
/// Largest channels below this store 0 (it keeps every scale below a normal float).
constexpr float kRgbe8Min = 0x1p-100f;

/// 2^exponent as a float, built from its bits; exponent in [-126, 127].
float exp2i(int exponent) {
    return std::bit_cast<float>(uint32_t(exponent + 127) << 23);
}

/// Half-float bits of a finite or infinite magnitude |value| (sign bit clear).
uint16_t magnitudeToHalf(uint32_t absBits) {
    const uint32_t exponent = absBits >> 23;  // biased float exponent
    const uint32_t mantissa = absBits & 0x7fffffu;
    // 2^16 and above (and inf) are beyond the largest half; 65520 .. 65535 round up to inf
    // through the carry of the normal path below.
    if (exponent >= 127 + 16) return 0x7c00;
    uint32_t half;
    uint32_t remainder;
    uint32_t halfway;
    if (exponent >= 127 - 14) {
        // Normal half: rebias the exponent (127 -> 15) and keep the top 10 mantissa bits.
        half = ((exponent - 112) << 10) | (mantissa >> 13);
        remainder = mantissa & 0x1fffu;
        halfway = 0x1000u;
    } else {
        // Subnormal half: the value in units of 2^-24 is (1.mantissa) · 2^(exponent - 126).
        // Below 2^-25 (shift > 24) everything rounds to zero, including float subnormals.
        const uint32_t shift = 126 - exponent;
        if (shift > 24) return 0;
        const uint32_t significand = mantissa | 0x800000u;
        half = significand >> shift;
        remainder = significand & ((1u << shift) - 1u);
        halfway = 1u << (shift - 1u);
    }
    // Round to nearest, ties to even; a carry out of the mantissa correctly bumps the
    // exponent (largest subnormal -> smallest normal, 65504 -> inf).
    if (remainder > halfway || (remainder == halfway && (half & 1u))) ++half;
    return uint16_t(half);
}

}  // namespace

uint16_t floatToHalf(float value) {
    const uint32_t bits = std::bit_cast<uint32_t>(value);
    const auto sign = uint16_t((bits >> 16) & 0x8000u);
    const uint32_t absBits = bits & 0x7fffffffu;
    if (absBits > 0x7f800000u) {
        // NaN: keep the top payload bits and set the quiet bit so the result cannot be inf.
        return uint16_t(sign | 0x7e00u | ((absBits >> 13) & 0x3ffu));
    }
    return uint16_t(sign | magnitudeToHalf(absBits));
}

uint16_t floatToHalfClamped(float value) {
    const uint16_t half = floatToHalf(value);
    // Infinity (from overflow or an infinite input) becomes the largest finite half.
    if ((half & 0x7fffu) == 0x7c00u) return uint16_t((half & 0x8000u) | 0x7bffu);
    return half;
}

uint32_t encodeOctahedral(const glm::vec3& unitDir) {
    const float l1 = std::abs(unitDir.x) + std::abs(unitDir.y) + std::abs(unitDir.z);
    if (!(l1 > 0.0f) || !std::isfinite(l1)) return encodeOctahedral({0.0f, 0.0f, 1.0f});
    // Project onto the octahedron |x| + |y| + |z| = 1, then unfold the lower half outwards.
    float u = unitDir.x / l1;
    float v = unitDir.y / l1;
    if (unitDir.z < 0.0f) {
        const float foldedU = (1.0f - std::abs(v)) * (u >= 0.0f ? 1.0f : -1.0f);
        const float foldedV = (1.0f - std::abs(u)) * (v >= 0.0f ? 1.0f : -1.0f);
        u = foldedU;
        v = foldedV;
    }
    const auto toSnorm16 = [](float c) {
        return uint32_t(uint16_t(int16_t(std::lround(std::clamp(c, -1.0f, 1.0f) * 32767.0f))));
    };
    return toSnorm16(u) | (toSnorm16(v) << 16);
}

EncodedLinkTint encodeLinkTint(const glm::vec3& tint) {
    glm::vec3 t;
    for (int c = 0; c < 3; ++c) t[c] = std::isfinite(tint[c]) ? std::max(tint[c], 0.0f) : 0.0f;
    const float largest = std::max({t.r, t.g, t.b});
    if (!(largest > 0.0f)) return {0u, 0.0f};
    uint32_t code = 0;
    for (int c = 0; c < 3; ++c)
        code |= uint32_t(std::lround(std::min(t[c] / largest, 1.0f) * 1023.0f)) << (10 * c);
    return {code, largest};
}

glm::vec3 decodeOctahedral(uint32_t code) {
    const auto fromSnorm16 = [](uint32_t bits) {
        return std::max(float(int16_t(uint16_t(bits))) / 32767.0f, -1.0f);
    };
    const float u = fromSnorm16(code & 0xffffu);
    const float v = fromSnorm16(code >> 16);
    glm::vec3 dir(u, v, 1.0f - std::abs(u) - std::abs(v));
    if (dir.z < 0.0f) {
        dir.x = (1.0f - std::abs(v)) * (u >= 0.0f ? 1.0f : -1.0f);
        dir.y = (1.0f - std::abs(u)) * (v >= 0.0f ? 1.0f : -1.0f);
    }
    return glm::normalize(dir);
}

uint32_t packRgbe8(const glm::vec3& rgb) {
    // Negative and NaN channels fail `c > 0` and store 0.
    const auto clampChannel = [](float c) { return c > 0.0f ? std::min(c, kRgbe8Max) : 0.0f; };
    const float r = clampChannel(rgb.r);
    const float g = clampChannel(rgb.g);
    const float b = clampChannel(rgb.b);
    const float maxChannel = std::max({r, g, b});
    if (maxChannel < kRgbe8Min) return 0;
    // The exponent e with max / 2^e in [1/2, 1): floor(log2(max)) + 1 from the float's exponent
    // bits, in [-99, 127].
    int exponent = int(std::bit_cast<uint32_t>(maxChannel) >> 23) - 127 + 1;
    float scale = exp2i(kRgbe8MantissaBits - exponent);  // 1 / mantissa step
    // Rounding the largest channel up to 2^8 needs the next exponent (never past 127: the
    // clamp keeps max · 2^-119 <= 255).
    if (std::floor(maxChannel * scale + 0.5f) >= float(1 << kRgbe8MantissaBits)) {
        ++exponent;
        scale *= 0.5f;
    }
    const auto mantissa = [scale](float c) { return uint32_t(std::floor(c * scale + 0.5f)); };
    return mantissa(r) | (mantissa(g) << 8) | (mantissa(b) << 16) |
           (uint32_t(exponent + kRgbe8Bias) << 24);
}

glm::vec3 unpackRgbe8(uint32_t packed) {
    // ldexp: exact, and defined for the exponent bytes packRgbe8 never writes (below 29).
    const float step = std::ldexp(1.0f, int(packed >> 24) - kRgbe8Bias - kRgbe8MantissaBits);
    return {float(packed & 0xffu) * step, float((packed >> 8) & 0xffu) * step,
            float((packed >> 16) & 0xffu) * step};
}

float luminance(const glm::vec3& linearRgb) {
    return 0.2126f * linearRgb.r + 0.7152f * linearRgb.g + 0.0722f * linearRgb.b;
}

}  // namespace pic
