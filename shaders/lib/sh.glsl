// Real SH of core/sh.h on the GPU. The includer declares the specialization constant
// kBandsY, const uint kCountY = kBandsY·kBandsY, and a uniform block member `ShTables sh`.

#define PIC_SH_TABLE(array, k) (array[(k) >> 2u][(k) & 3u])

const float kPi = 3.14159265358979;

#include "sh_basis.glsl"  // generated: shEvaluate

/// K_l(α), l < kBandsY, of the indicator of a cone with u = 1 − cos α (core/sh.h
/// coneZonalBands): K_0 = 2πu, K_l = 2π·(1 − x²)·P_l'(x)/(l(l + 1)) with x = cos α. The
/// divisors are constants once the loop is unrolled, so this multiplies by their reciprocals:
/// llvmpipe keeps a division by a constant a division (cache lighting with RTP links: 0.98 of
/// the time at the moderate setting, 0.96 at the high one, 61 passes of each in turns).
void coneZonal(float oneMinusCosAlpha, out float k[kBandsY]) {
    const float u = clamp(oneMinusCosAlpha, 0.0, 2.0);
    const float x = 1.0 - u;
    const float sinSquared = u * (2.0 - u);
    float legendre = 1.0, legendrePrevious = 0.0;      // P_l, P_{l−1}
    float derivative = 0.0, derivativePrevious = 0.0;  // P_l', P_{l−1}'
    k[0] = 2.0 * kPi * u;
    [[unroll]] for (uint l = 1u; l < kBandsY; ++l) {
        const float lm = float(l - 1u);
        const float nextLegendre =
            ((2.0 * lm + 1.0) * x * legendre - lm * legendrePrevious) * (1.0 / (lm + 1.0));
        const float nextDerivative = derivativePrevious + (2.0 * lm + 1.0) * legendre;
        legendrePrevious = legendre;
        legendre = nextLegendre;
        derivativePrevious = derivative;
        derivative = nextDerivative;
        k[l] = (2.0 * kPi / float(l * (l + 1u))) * sinSquared * derivative;
    }
}

/// Paper 000 eq. 7 lifting steps (core/color.h rgbToYCoCg).
vec3 rgbToYCoCg(vec3 rgb) {
    const float co = 0.5 * (rgb.r - rgb.b);
    const float t = rgb.b + co;
    const float cg = 0.5 * (rgb.g - t);
    return vec3(t + cg, co, cg);
}

/// core/color.h yCoCgToRgb.
vec3 yCoCgToRgb(vec3 ycocg) {
    const float t = ycocg.x - ycocg.z;
    return vec3(t + ycocg.y, ycocg.x + ycocg.z, t - ycocg.y);
}

/// core/color.h chromaPerLuma: (Co/Y, Cg/Y) within |Co| ≤ 2Y, |Cg| ≤ Y; 0 where Y ≤ 0. The
/// chroma of SH bands above lC is their luma times band 0's ratio (core/cache_values.h).
vec2 chromaPerLuma(vec3 ycocg) {
    if (!(ycocg.x > 0.0)) return vec2(0.0);
    return clamp(ycocg.yz / ycocg.x, vec2(-2.0, -1.0), vec2(2.0, 1.0));
}

/// core/color.h decodeOctahedral for the GPU links' 2 × snorm9 form (shared/cache_lighting.h
/// GpuRtpLink): x in bits 0-8, y in bits 9-17.
vec3 decodeOctahedral9(uint code) {
    const float u = max(float(int(code << 23u) >> 23) * (1.0 / 255.0), -1.0);
    const float v = max(float(int(code << 14u) >> 23) * (1.0 / 255.0), -1.0);
    vec3 dir = vec3(u, v, 1.0 - abs(u) - abs(v));
    if (dir.z < 0.0) {
        dir.x = (1.0 - abs(v)) * (u >= 0.0 ? 1.0 : -1.0);
        dir.y = (1.0 - abs(u)) * (v >= 0.0 ? 1.0 : -1.0);
    }
    return normalize(dir);
}
