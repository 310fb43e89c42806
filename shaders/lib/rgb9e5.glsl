// Shared-exponent RGB9E5 on the GPU: the bit-exact twin of core/color.h packRgb9e5 and
// unpackRgb9e5 (9-bit mantissas R, G, B in bits 0-8, 9-17, 18-26, a 5-bit exponent with bias
// 15 in bits 27-31). ldexp, floor and single float products are exact here, as on the CPU.

const float kRgb9e5Max = 65408.0;  // 511/512 · 2^16

/// core/color.h packRgb9e5: negative and NaN channels store 0, values above kRgb9e5Max clamp.
uint packRgb9e5(vec3 rgb) {
    // `c > 0` is false for NaN.
    const vec3 c = vec3(rgb.r > 0.0 ? min(rgb.r, kRgb9e5Max) : 0.0,
                        rgb.g > 0.0 ? min(rgb.g, kRgb9e5Max) : 0.0,
                        rgb.b > 0.0 ? min(rgb.b, kRgb9e5Max) : 0.0);
    const float maxChannel = max(c.r, max(c.g, c.b));
    // floor(log2(max)) from the float's exponent bits; below 2^-16 the smallest exponent.
    int floorLog2 = -16;
    if (maxChannel >= ldexp(1.0, -16)) floorLog2 = int(floatBitsToUint(maxChannel) >> 23) - 127;
    int exponent = floorLog2 + 16;
    float scale = ldexp(1.0, 24 - exponent);  // 1 / mantissa step
    // Rounding the largest channel up to 2^9 needs the next exponent.
    if (floor(maxChannel * scale + 0.5) >= 512.0) {
        ++exponent;
        scale *= 0.5;
    }
    const uvec3 mantissa = uvec3(floor(c * scale + 0.5));
    return mantissa.r | (mantissa.g << 9u) | (mantissa.b << 18u) | (uint(exponent) << 27u);
}

/// core/color.h unpackRgb9e5.
vec3 unpackRgb9e5(uint packed) {
    return vec3(uvec3(packed, packed >> 9u, packed >> 18u) & 511u) *
           ldexp(1.0, int(packed >> 27u) - 24);
}
