// Shared-exponent RGBE8 on the GPU: the bit-exact twin of core/color.h packRgbe8 and
// unpackRgbe8 (8-bit mantissas R, G, B in bits 0-7, 8-15, 16-23, an exponent byte x in bits
// 24-31, each channel mantissa · 2^(x − 136)). Powers of two built from their bits, products
// by them and floor are exact here, as on the CPU.

const float kRgbe8Max = 255.0 * 6.64613997892457936451903530140172288e35;  // 255 · 2^119

/// core/color.h packRgbe8: a largest channel below 2^-100 stores 0, channels above kRgbe8Max
/// clamp, negative and NaN channels store 0.
uint packRgbe8(vec3 rgb) {
    // `c > 0` is false for NaN.
    const vec3 c = vec3(rgb.r > 0.0 ? min(rgb.r, kRgbe8Max) : 0.0,
                        rgb.g > 0.0 ? min(rgb.g, kRgbe8Max) : 0.0,
                        rgb.b > 0.0 ? min(rgb.b, kRgbe8Max) : 0.0);
    const float maxChannel = max(c.r, max(c.g, c.b));
    if (maxChannel < 7.88860905221011805411728565283e-31) return 0u;  // 2^-100
    // e with max / 2^e in [1/2, 1): floor(log2(max)) + 1 from the float's exponent bits.
    int exponent = int(floatBitsToUint(maxChannel) >> 23) - 126;
    // 1 / mantissa step, 2^(8 − e), from its float bits (lavapipe's ldexp costs more).
    float scale = uintBitsToFloat(uint(8 - exponent + 127) << 23u);
    // Rounding the largest channel up to 2^8 needs the next exponent.
    if (floor(maxChannel * scale + 0.5) >= 256.0) {
        ++exponent;
        scale *= 0.5;
    }
    const uvec3 mantissa = uvec3(floor(c * scale + 0.5));
    return mantissa.r | (mantissa.g << 8u) | (mantissa.b << 16u) | (uint(exponent + 128) << 24u);
}

/// core/color.h unpackRgbe8. The step 2^(x − 136) is built from its float bits (biased
/// exponent x − 9); the bytes below 10, which packRgbe8 never writes but 0, give a step of 0.
vec3 unpackRgbe8(uint packed) {
    const float step = uintBitsToFloat(uint(max(int(packed >> 24u) - 9, 0)) << 23u);
    return vec3(uvec3(packed, packed >> 8u, packed >> 16u) & 255u) * step;
}
