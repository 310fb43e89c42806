#include "core/sh.h"

#include <algorithm>
#include <array>
#include <numbers>

#include "core/error.h"

namespace pic {
namespace {

constexpr double kPi = std::numbers::pi;

/// Square root usable in constant expressions (Newton's iteration from above; x >= 0).
constexpr double constexprSqrt(double x) {
    if (x <= 0.0) return 0.0;
    double root = x > 1.0 ? x : 1.0;
    for (;;) {
        const double next = 0.5 * (root + x / root);
        if (next >= root) return root;
        root = next;
    }
}

/// Constants of the normalised associated-Legendre recurrence. With
/// Q_l^m = c_m N_l^m P_l^m(z) / sin^m θ (c_0 = 1, c_m = √2), the basis is
/// y_l^m = Q_l^m Re((x + iy)^m) and y_l^-m = Q_l^m Im((x + iy)^m), and
///   Q_m^m = c_m sqrt((2m+1)/(4π) · (2m-1)!!/(2m)!!),
///   Q_l^m = a_l^m z Q_{l-1}^m - b_l^m Q_{l-2}^m   (l > m, Q_{m-1}^m = 0).
struct LegendreTables {
    std::array<float, kMaxShBands> diagonal{};
    std::array<std::array<float, kMaxShBands>, kMaxShBands> a{};  // [l][m]
    std::array<std::array<float, kMaxShBands>, kMaxShBands> b{};  // [l][m]
};

constexpr LegendreTables makeLegendreTables() {
    LegendreTables tables;
    double doubleFactorialRatio = 1.0;  // (2m-1)!! / (2m)!!
    for (int m = 0; m < kMaxShBands; ++m) {
        if (m > 0) doubleFactorialRatio *= double(2 * m - 1) / double(2 * m);
        const double c2 = m == 0 ? 1.0 : 2.0;
        tables.diagonal[m] =
            float(constexprSqrt(c2 * (2 * m + 1) / (4.0 * kPi) * doubleFactorialRatio));
        for (int l = m + 1; l < kMaxShBands; ++l) {
            const double l2m2 = double(l * l - m * m);
            tables.a[l][m] = float(constexprSqrt((4.0 * l * l - 1.0) / l2m2));
            tables.b[l][m] = float(constexprSqrt(double(2 * l + 1) * ((l - 1) * (l - 1) - m * m) /
                                                 (double(2 * l - 3) * l2m2)));
        }
    }
    return tables;
}

constexpr LegendreTables kLegendre = makeLegendreTables();

/// Writes Q_L^M times the azimuthal factors: y_L^M, and y_L^-M for M > 0.
template <int L, int M>
inline void storeBasis(float q, float cosTerm, float sinTerm, float* out) {
    if constexpr (M == 0) {
        out[shIndex(L, 0)] = q;
    } else {
        out[shIndex(L, M)] = q * cosTerm;
        out[shIndex(L, -M)] = q * sinTerm;
    }
}

/// Order M, bands L .. Bands-1, by the upward recurrence from current = Q_{L-1}^M and
/// previous = Q_{L-2}^M. Compile-time indices turn every table entry into an immediate.
template <int Bands, int M, int L>
inline void evaluateColumn(float z, float current, float previous, float cosTerm, float sinTerm,
                           float* out) {
    if constexpr (L < Bands) {
        constexpr float a = kLegendre.a[L][M];
        constexpr float b = kLegendre.b[L][M];
        const float next = a * z * current - b * previous;
        storeBasis<L, M>(next, cosTerm, sinTerm, out);
        evaluateColumn<Bands, M, L + 1>(z, next, current, cosTerm, sinTerm, out);
    }
}

/// Orders M .. Bands-1; (cosTerm, sinTerm) = Re, Im of (x + iy)^M = sin^M θ (cos Mφ, sin Mφ),
/// advanced by one complex product per order.
template <int Bands, int M>
inline void evaluateOrders(const glm::vec3& d, float cosTerm, float sinTerm, float* out) {
    if constexpr (M < Bands) {
        constexpr float diagonal = kLegendre.diagonal[M];
        storeBasis<M, M>(diagonal, cosTerm, sinTerm, out);
        evaluateColumn<Bands, M, M + 1>(d.z, diagonal, 0.0f, cosTerm, sinTerm, out);
        evaluateOrders<Bands, M + 1>(d, cosTerm * d.x - sinTerm * d.y,
                                     cosTerm * d.y + sinTerm * d.x, out);
    }
}

/// shEvaluate for a compile-time band count: straight-line code without loops or branches.
template <int Bands>
void evaluateBands(const glm::vec3& direction, float* out) {
    evaluateOrders<Bands, 0>(direction, 1.0f, 0.0f, out);
}

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
        return evaluateBands<1>(direction, out);
    case 2:
        return evaluateBands<2>(direction, out);
    case 3:
        return evaluateBands<3>(direction, out);
    case 4:
        return evaluateBands<4>(direction, out);
    case 5:
        return evaluateBands<5>(direction, out);
    case 6:
        return evaluateBands<6>(direction, out);
    case 7:
        return evaluateBands<7>(direction, out);
    case 8:
        return evaluateBands<8>(direction, out);
    default:
        PIC_CHECK(bands >= 0 && bands <= kMaxShBands);
    }
}

ShRecurrence shRecurrence() {
    ShRecurrence out{};
    for (int m = 0; m < kMaxShBands; ++m) {
        out.diagonal[m] = kLegendre.diagonal[m];
        for (int l = 0; l < kMaxShBands; ++l) {
            out.a[l][m] = kLegendre.a[l][m];
            out.b[l][m] = kLegendre.b[l][m];
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
