#include "core/sh.h"

#include <algorithm>
#include <array>
#include <numbers>

#include "core/error.h"

namespace pic {
namespace {

constexpr double kPi = std::numbers::pi;

/// Paper 000 appendix B recurrence for s_l(n) = (n+1) ∫_0^1 t^n P_l(t) dt.
constexpr double lobeFactor(int l, double n) {
    double even = 1.0;                   // s_0
    double odd = (n + 1.0) / (n + 2.0);  // s_1
    for (int k = 2; k <= l; ++k) {
        double& s = (k % 2 == 0) ? even : odd;
        s *= (n + 2.0 - k) / (n + 1.0 + k);
    }
    return l % 2 == 0 ? even : odd;
}

/// K_l of the clamped cosine for the bands shIrradiance uses: π s_l(1).
constexpr std::array<float, kMaxShBands> kClampedCosine = [] {
    std::array<float, kMaxShBands> k{};
    for (int l = 0; l < kMaxShBands; ++l) k[l] = float(kPi * lobeFactor(l, 1.0));
    return k;
}();

/// K_l(α) of the cone indicator for l = 0, 1, 2, ... in turn. For l > 0,
/// ∫_x^1 P_l(t) dt = (1 - x²) P_l'(x) / (l(l+1)) with x = cos α, and 1 - x² = u (2 - u) is
/// formed from u = 1 - cos α itself: no difference of nearly equal terms, so tiny cones keep
/// full precision (P_l'(1) = l(l+1)/2 gives K_l -> 2π u) and the full sphere u = 2 gives 0.
class ConeZonalSequence {
public:
    explicit ConeZonalSequence(double oneMinusCosAlpha)
        : mU(std::clamp(oneMinusCosAlpha, 0.0, 2.0)), mX(1.0 - mU), mSinSquared(mU * (2.0 - mU)) {
        PIC_DCHECK(oneMinusCosAlpha >= 0.0 && oneMinusCosAlpha <= 2.0);
    }

    /// K_l for the current band l.
    double value() const {
        if (mL == 0) return 2.0 * kPi * mU;
        return 2.0 * kPi * mSinSquared * mDerivative / double(mL * (mL + 1));
    }

    /// Moves to band l + 1 with P_{l+1} = ((2l+1) x P_l - l P_{l-1}) / (l+1) and
    /// P_{l+1}' = P_{l-1}' + (2l+1) P_l.
    void advance() {
        const double nextLegendre =
            ((2 * mL + 1) * mX * mLegendre - mL * mLegendrePrevious) / (mL + 1);
        const double nextDerivative = mDerivativePrevious + (2 * mL + 1) * mLegendre;
        mLegendrePrevious = mLegendre;
        mLegendre = nextLegendre;
        mDerivativePrevious = mDerivative;
        mDerivative = nextDerivative;
        ++mL;
    }

private:
    double mU;
    double mX;
    double mSinSquared;
    int mL = 0;
    double mLegendre = 1.0;            // P_l(x)
    double mLegendrePrevious = 0.0;    // P_{l-1}(x), P_{-1} = 0
    double mDerivative = 0.0;          // P_l'(x)
    double mDerivativePrevious = 0.0;  // P_{l-1}'(x)
};

/// Σ_l factor_l Σ_m coeffs_l^m basis_l^m.
float bandWeightedDot(int bands, const float* coeffs, const float* basis, const float* factor) {
    float sum = 0.0f;
    for (int l = 0; l < bands; ++l) {
        float band = 0.0f;
        for (int i = l * l; i < (l + 1) * (l + 1); ++i) band += coeffs[i] * basis[i];
        sum += factor[l] * band;
    }
    return sum;
}

}  // namespace

void shEvaluate(int bands, const glm::vec3& direction, float* out) {
    switch (bands) {
    case 0:
        return;
    case 1:
        return shEvaluateFixed<1>(direction, out);
    case 2:
        return shEvaluateFixed<2>(direction, out);
    case 3:
        return shEvaluateFixed<3>(direction, out);
    case 4:
        return shEvaluateFixed<4>(direction, out);
    case 5:
        return shEvaluateFixed<5>(direction, out);
    case 6:
        return shEvaluateFixed<6>(direction, out);
    case 7:
        return shEvaluateFixed<7>(direction, out);
    case 8:
        return shEvaluateFixed<8>(direction, out);
    default:
        PIC_CHECK(bands >= 0 && bands <= kMaxShBands);
    }
}

ShRecurrence shRecurrence() {
    ShRecurrence out{};
    for (int m = 0; m < kMaxShBands; ++m) {
        out.diagonal[m] = detail::kLegendre.diagonal[m];
        for (int l = 0; l < kMaxShBands; ++l) {
            out.a[l][m] = detail::kLegendre.a[l][m];
            out.b[l][m] = detail::kLegendre.b[l][m];
        }
    }
    return out;
}

float clampedCosineZonal(int l) {
    PIC_DCHECK(l >= 0);
    return float(kPi * lobeFactor(l, 1.0));
}

float cosineLobeFactor(int l, float n) {
    PIC_DCHECK(l >= 0 && n > -1.0f);
    return float(lobeFactor(l, double(n)));
}

void coneZonalBands(int bands, double oneMinusCosAlpha, double* out) {
    PIC_DCHECK(bands >= 0);
    ConeZonalSequence sequence(oneMinusCosAlpha);
    for (int l = 0; l < bands; ++l, sequence.advance()) out[l] = sequence.value();
}

double coneZonal(int l, double oneMinusCosAlpha) {
    PIC_DCHECK(l >= 0);
    ConeZonalSequence sequence(oneMinusCosAlpha);
    for (int k = 0; k < l; ++k) sequence.advance();
    return sequence.value();
}

void shAddCone(int bands, const glm::vec3& direction, float oneMinusCosAlpha, float scale,
               float* inOut) {
    std::array<float, shCount(kMaxShBands)> basis;
    std::array<double, kMaxShBands> cone;
    shEvaluate(bands, direction, basis.data());
    coneZonalBands(bands, double(oneMinusCosAlpha), cone.data());
    for (int l = 0; l < bands; ++l) {
        const float weight = scale * float(cone[l]);
        for (int i = l * l; i < (l + 1) * (l + 1); ++i) inOut[i] += weight * basis[i];
    }
}

void shAddClampedCosine(int bands, const glm::vec3& direction, float scale, float* inOut) {
    std::array<float, shCount(kMaxShBands)> basis;
    shEvaluate(bands, direction, basis.data());
    for (int l = 0; l < bands; ++l) {
        const float weight = scale * kClampedCosine[l];
        for (int i = l * l; i < (l + 1) * (l + 1); ++i) inOut[i] += weight * basis[i];
    }
}

float shIrradiance(int bands, const float* radianceSh, const glm::vec3& normal) {
    std::array<float, shCount(kMaxShBands)> basis;
    shEvaluate(bands, normal, basis.data());
    return bandWeightedDot(bands, radianceSh, basis.data(), kClampedCosine.data());
}

float shGlossy(int bands, const float* radianceSh, const glm::vec3& reflectDir, float exponent) {
    PIC_DCHECK(exponent > -1.0f);
    std::array<float, shCount(kMaxShBands)> basis;
    std::array<float, kMaxShBands> lobe;
    shEvaluate(bands, reflectDir, basis.data());
    for (int l = 0; l < bands; ++l) lobe[l] = float(lobeFactor(l, double(exponent)));
    return bandWeightedDot(bands, radianceSh, basis.data(), lobe.data());
}

float shDot(int bands, const float* a, const float* b) {
    float sum = 0.0f;
    for (int i = 0; i < shCount(bands); ++i) sum += a[i] * b[i];
    return sum;
}

}  // namespace pic
