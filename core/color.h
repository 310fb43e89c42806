#pragma once
/// Colour and storage encodings: YCoCg (paper 000 eq. 7), IEEE half floats, octahedral unit
/// vectors in 32 bits and the shared-exponent RGBE8 HDR format (paper 000 §4.7 uses a shared
/// exponent too).

#include <bit>
#include <cstdint>

#include <glm/common.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

namespace pic {

/// Linear RGB to YCoCg: Y = R/4 + G/2 + B/4, Co = (R - B)/2, Cg = (-R + 2G - B)/4. Inline,
/// as is its inverse: the CPU twin's cache lighting converts per tinted link.
inline glm::vec3 rgbToYCoCg(const glm::vec3& rgb) {
    // Lifting steps of paper 000 eq. 7; t = (R + B)/2.
    const float co = 0.5f * (rgb.r - rgb.b);
    const float t = rgb.b + co;
    const float cg = 0.5f * (rgb.g - t);
    return {t + cg, co, cg};
}

/// Exact inverse of rgbToYCoCg: t = Y - Cg, R = t + Co, G = Y + Cg, B = t - Co.
inline glm::vec3 yCoCgToRgb(const glm::vec3& yCoCg) {
    // The lifting steps of rgbToYCoCg undone in reverse order.
    const float t = yCoCg.x - yCoCg.z;
    return {t + yCoCg.y, yCoCg.x + yCoCg.z, t - yCoCg.y};
}

/// IEEE binary16 bits of value, rounded to nearest even; subnormals are exact, magnitudes
/// from 65520 up become ±inf, NaN stays NaN (quiet, sign and top payload bits kept).
uint16_t floatToHalf(float value);

/// Like floatToHalf but finite values and ±inf saturate to ±65504, so no inf is ever
/// stored; NaN still maps to NaN so that upstream bugs stay visible.
uint16_t floatToHalfClamped(float value);

/// The float that binary16 bits represent (exact for every pattern, NaN payload kept).
/// Branch-free and inline, so that loops over many halves vectorise: the runtime converts
/// every cache coefficient it reads back, 137k per update at the moderate setting, in 0.05 ms
/// (0.22 ms through a call per value with branches).
inline float halfToFloat(uint16_t bits) {
    // Exponent and mantissa move to their float places and the exponent is rebiased by
    // 127 − 15; infinities and NaNs (exponent 31) once more, to 255. A subnormal or zero
    // (exponent 0) is m·2^−24, exact in float. Masks rather than branches select the case.
    const uint32_t magnitude = uint32_t(bits & 0x7fffu) << 13;
    const uint32_t exponent = magnitude & 0x0f800000u;
    const uint32_t infOrNan = 0u - uint32_t(exponent == 0x0f800000u);
    const uint32_t subnormal = 0u - uint32_t(exponent == 0u);
    const uint32_t normal = magnitude + (112u << 23) + (infOrNan & (112u << 23));
    const uint32_t small = std::bit_cast<uint32_t>(float(bits & 0x3ffu) * 0x1p-24f);
    const uint32_t sign = uint32_t(bits & 0x8000u) << 16;
    return std::bit_cast<float>(sign | (small & subnormal) | (normal & ~subnormal));
}

/// Octahedral encoding of a direction into two snorm16 values, x in the low 16 bits. The
/// input need not be normalised; a zero or non-finite vector encodes +z.
uint32_t encodeOctahedral(const glm::vec3& unitDir);

/// Unit direction of an octahedral code from encodeOctahedral.
glm::vec3 decodeOctahedral(uint32_t code);

/// The chroma per luma (Co/Y, Cg/Y) of a YCoCg colour, clamped to what non-negative RGB
/// allows (|Co| ≤ 2Y, |Cg| ≤ Y); (0, 0) where Y ≤ 0. The SH caches predict the chroma of
/// their bands above lC from their luma with the ratio of band 0 (core/cache_values.h).
inline glm::vec2 chromaPerLuma(const glm::vec3& yCoCg) {
    if (!(yCoCg.x > 0.0f)) return glm::vec2(0.0f);
    return glm::clamp(glm::vec2(yCoCg.y, yCoCg.z) / yCoCg.x, glm::vec2(-2.0f, -1.0f),
                      glm::vec2(2.0f, 1.0f));
}

/// A link's tint (bake/link_generation.h): per-channel multipliers of its factor, stored as
/// three unorm10 fractions of the largest, R in bits 0-9, G 10-19, B 20-29, bits 30-31 zero.
/// kNeutralLinkTint is (1, 1, 1). Every channel keeps an error ≤ 1/2046 of the largest.
inline constexpr uint32_t kNeutralLinkTint = 0x3FFFFFFFu;

/// A tint's code and the scale the link's factor takes so that scale·decodeLinkTint(code)
/// is the tint.
struct EncodedLinkTint {
    uint32_t code = kNeutralLinkTint;
    float scale = 1.0f;
};

/// Encodes a tint; negative and non-finite channels count as 0, and an all-zero tint encodes
/// code 0 with scale 0.
EncodedLinkTint encodeLinkTint(const glm::vec3& tint);

/// The multipliers of a tint code, each in [0, 1] (shaders/cache_lighting.comp decodes the
/// same way).
inline glm::vec3 decodeLinkTint(uint32_t code) {
    return glm::vec3(float(code & 0x3FFu), float((code >> 10) & 0x3FFu),
                     float((code >> 20) & 0x3FFu)) *
           (1.0f / 1023.0f);
}

/// Shared-exponent RGBE8 (Ward's RGBE, as in the Radiance format): 8-bit mantissas R, G, B in
/// bits 0-7, 8-15, 16-23 and an 8-bit exponent byte x in bits 24-31, each channel being
/// mantissa · 2^(x − 136). Every channel keeps an error <= 2^-8 of the largest one. The range is
/// a float's: a largest channel below 2^-100 stores 0, channels above kRgbe8Max clamp to it,
/// negative and NaN channels store 0.
uint32_t packRgbe8(const glm::vec3& rgb);

/// Linear RGB of an RGBE8 code.
glm::vec3 unpackRgbe8(uint32_t packed);

/// Largest value an RGBE8 channel holds: 255/256 · 2^127.
constexpr float kRgbe8Max = 255.0f * 0x1p119f;

/// Relative luminance of linear Rec. 709 RGB: 0.2126 R + 0.7152 G + 0.0722 B.
float luminance(const glm::vec3& linearRgb);

}  // namespace pic
