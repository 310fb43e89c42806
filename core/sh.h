#pragma once
/// Real spherical harmonics up to 8 bands and the zonal kernels of paper 000 (§3.2, §4.6,
/// appendices B and C): clamped cosine, normalised cosine lobe and solid cone.
///
/// Convention. Polar axis z; a unit direction is (x, y, z) = (sinθ cosφ, sinθ sinφ, cosθ).
/// The basis y_l^m is real and orthonormal on the sphere, stored at index i = l(l+1) + m:
///   y_l^0  = N_l^0 P_l^0(cosθ)
///   y_l^m  = √2 N_l^m P_l^m(cosθ) cos(mφ)    for m > 0
///   y_l^-m = √2 N_l^m P_l^m(cosθ) sin(mφ)    for m > 0
/// with N_l^m = sqrt((2l+1)/(4π) · (l-m)!/(l+m)!) and P_l^m the associated Legendre functions
/// WITHOUT the Condon-Shortley phase (-1)^m. Every y_l^±l is positive-weighted in x and y, so
/// band 1 is (y_1^-1, y_1^0, y_1^1) = sqrt(3/(4π)) · (y, z, x), and e.g.
/// y_2^-2 = sqrt(15/(4π)) x y, y_2^2 = sqrt(15/(16π)) (x² - y²).
///
/// "bands" is l_max + 1: 3 bands hold 9 coefficients.
///
/// Zonal functions. A function g(d·ω) that depends only on the angle to an axis d projects to
/// c_l^m = K_l · y_l^m(d) with K_l = 2π ∫_{-1}^{1} g(t) P_l(t) dt (Funk-Hecke; paper eq. 5
/// written with K_l = sqrt(4π/(2l+1)) c_l^0 of the lobe around z). Every kernel below is such
/// a per-band factor K_l.

#include <array>
#include <numbers>

#include <glm/vec3.hpp>

namespace pic {

/// Largest supported band count (l_max = 7, 64 coefficients).
constexpr int kMaxShBands = 8;

/// Number of coefficients of an SH expansion with `bands` bands.
constexpr int shCount(int bands) {
    return bands * bands;
}

/// Index of coefficient (l, m), -l <= m <= l, in a coefficient array.
constexpr int shIndex(int l, int m) {
    return l * (l + 1) + m;
}

/// Writes the shCount(bands) basis values y_l^m(direction) to out; bands in [0, kMaxShBands],
/// direction unit length. Polynomial recurrences in x, y, z only: no trig, no allocation.
void shEvaluate(int bands, const glm::vec3& direction, float* out);

namespace detail {

/// Square root usable in constant expressions (Newton's iteration from above; x >= 0).
inline constexpr double constexprSqrt(double x) {
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

inline constexpr LegendreTables makeLegendreTables() {
    LegendreTables tables;
    double doubleFactorialRatio = 1.0;  // (2m-1)!! / (2m)!!
    for (int m = 0; m < kMaxShBands; ++m) {
        if (m > 0) doubleFactorialRatio *= double(2 * m - 1) / double(2 * m);
        const double c2 = m == 0 ? 1.0 : 2.0;
        tables.diagonal[m] = float(
            constexprSqrt(c2 * (2 * m + 1) / (4.0 * std::numbers::pi) * doubleFactorialRatio));
        for (int l = m + 1; l < kMaxShBands; ++l) {
            const double l2m2 = double(l * l - m * m);
            tables.a[l][m] = float(constexprSqrt((4.0 * l * l - 1.0) / l2m2));
            tables.b[l][m] = float(constexprSqrt(double(2 * l + 1) * ((l - 1) * (l - 1) - m * m) /
                                                 (double(2 * l - 3) * l2m2)));
        }
    }
    return tables;
}

inline constexpr LegendreTables kLegendre = makeLegendreTables();

/// Writes Q_L^M times the azimuthal factors: y_L^M, and y_L^-M for M > 0. T is float, or a
/// vector of floats (GCC vector extensions) for kernels that evaluate several directions at once.
template <int L, int M, class T>
inline void storeBasis(T q, T cosTerm, T sinTerm, T* out) {
    if constexpr (M == 0) {
        out[shIndex(L, 0)] = q;
    } else {
        out[shIndex(L, M)] = q * cosTerm;
        out[shIndex(L, -M)] = q * sinTerm;
    }
}

/// Order M, bands L .. Bands-1, by the upward recurrence from current = Q_{L-1}^M and
/// previous = Q_{L-2}^M. Compile-time indices turn every table entry into an immediate.
template <int Bands, int M, int L, class T>
inline void evaluateColumn(T z, T current, T previous, T cosTerm, T sinTerm, T* out) {
    if constexpr (L < Bands) {
        constexpr float a = kLegendre.a[L][M];
        constexpr float b = kLegendre.b[L][M];
        const T next = a * z * current - b * previous;
        storeBasis<L, M>(next, cosTerm, sinTerm, out);
        evaluateColumn<Bands, M, L + 1>(z, next, current, cosTerm, sinTerm, out);
    }
}

/// Orders M .. Bands-1; (cosTerm, sinTerm) = Re, Im of (x + iy)^M = sin^M θ (cos Mφ, sin Mφ),
/// advanced by one complex product per order.
template <int Bands, int M, class T>
inline void evaluateOrders(T x, T y, T z, T cosTerm, T sinTerm, T* out) {
    if constexpr (M < Bands) {
        const T diagonal = T{} + kLegendre.diagonal[M];
        storeBasis<M, M>(diagonal, cosTerm, sinTerm, out);
        evaluateColumn<Bands, M, M + 1>(z, diagonal, T{}, cosTerm, sinTerm, out);
        evaluateOrders<Bands, M + 1>(x, y, z, cosTerm * x - sinTerm * y, cosTerm * y + sinTerm * x,
                                     out);
    }
}

}  // namespace detail

/// shEvaluate for a compile-time band count, inline: straight-line code without loops or
/// branches, for kernels that evaluate a basis per link.
template <int Bands>
inline void shEvaluateFixed(const glm::vec3& direction, float* out) {
    static_assert(Bands >= 0 && Bands <= kMaxShBands);
    detail::evaluateOrders<Bands, 0>(direction.x, direction.y, direction.z, 1.0f, 0.0f, out);
}

/// shEvaluateFixed of several directions at once, T a vector of floats (GCC vector extensions)
/// holding one direction per lane in (x, y, z): out[i] holds basis value i of every lane.
template <int Bands, class T>
inline void shEvaluateLanes(T x, T y, T z, T* out) {
    static_assert(Bands >= 0 && Bands <= kMaxShBands);
    detail::evaluateOrders<Bands, 0>(x, y, z, T{} + 1.0f, T{}, out);
}

/// The constants of shEvaluate's recurrence, for GPU shaders that evaluate the same basis:
/// Q_m^m = diagonal[m], Q_l^m = a[l][m]·z·Q_{l−1}^m − b[l][m]·Q_{l−2}^m (l > m), with
/// y_l^m = Q_l^m·Re((x + iy)^m) and y_l^−m = Q_l^m·Im((x + iy)^m).
struct ShRecurrence {
    float diagonal[kMaxShBands];
    float a[kMaxShBands][kMaxShBands];
    float b[kMaxShBands][kMaxShBands];
};
ShRecurrence shRecurrence();

/// K_l of the clamped cosine max(0, d·ω): its projection is K_l y_l^m(d), so the irradiance
/// of radiance L is E(n) = Σ K_l L_l^m y_l^m(n). K_0 = π, K_1 = 2π/3, K_2 = π/4, K_3 = 0,
/// and zero for every odd l >= 3. l >= 0.
float clampedCosineZonal(int l);

/// s_l(n) of paper 000 appendix B for the normalised lobe (n+1)/(2π) max(0, d·ω)^n, which
/// integrates to 1 over the sphere: the lobe's projection is c_l^m = s_l(n) y_l^m(d), i.e.
/// s_l(n) = sqrt(4π/(2l+1)) c_l^0 = (n+1) ∫_0^1 t^n P_l(t) dt. Computed by the paper's
/// recurrence s_0 = 1, s_1 = (n+1)/(n+2), s_l = s_{l-2} (n+2-l)/(n+1+l). For n = 1 this is
/// clampedCosineZonal(l) / π. l >= 0, n > -1.
float cosineLobeFactor(int l, float n);

/// K_l(α) of the indicator of the cone of half-angle α around d: its projection is
/// K_l(α) y_l^m(d), K_l(α) = 2π ∫_{cos α}^{1} P_l(t) dt (paper 000 eq. 6 and appendix C).
/// Takes u = 1 - cos α in [0, 2] and stays accurate to double rounding for tiny cones
/// (K_l ≈ 2π u as u → 0); the full sphere u = 2 gives K_0 = 4π and K_l = 0 for l > 0. l >= 0.
double coneZonal(int l, double oneMinusCosAlpha);

/// Writes coneZonal(l, oneMinusCosAlpha) for l = 0 .. bands-1 to out (one shared recurrence).
void coneZonalBands(int bands, double oneMinusCosAlpha, double* out);

/// Adds scale · K_l(α) · y_l^m(direction) to inOut: the runtime-projected link of paper 000
/// §4.6, i.e. the projection of `scale` times the indicator of the cone around direction.
void shAddCone(int bands, const glm::vec3& direction, float oneMinusCosAlpha, float scale,
               float* inOut);

/// Adds the projection of scale · max(0, direction·ω) to inOut.
void shAddClampedCosine(int bands, const glm::vec3& direction, float scale, float* inOut);

/// Irradiance E(n) = ∫ L(ω) max(0, n·ω) dω = Σ K_l L_l^m y_l^m(n) of SH radiance L; a
/// constant radiance L gives π L.
float shIrradiance(int bands, const float* radianceSh, const glm::vec3& normal);

/// Glossy lookup ∫ L(ω) (n+1)/(2π) max(0, r·ω)^n dω = Σ s_l(n) L_l^m y_l^m(r): the radiance
/// averaged over the normalised cosine lobe of exponent n around reflectDir.
float shGlossy(int bands, const float* radianceSh, const glm::vec3& reflectDir, float exponent);

/// Inner product Σ a_i b_i of two expansions, equal to ∫ a(ω) b(ω) dω.
float shDot(int bands, const float* a, const float* b);

}  // namespace pic
