#include "core/sh.h"

#include <array>
#include <cmath>
#include <functional>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

namespace pic {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr int kMaxCount = shCount(kMaxShBands);

using ShVector = std::array<double, kMaxCount>;

/// Gauss-Legendre nodes and weights on [a, b] (Newton on P_n); exact for degree <= 2n - 1.
struct GaussRule {
    std::vector<double> nodes;
    std::vector<double> weights;
};

GaussRule gaussLegendre(int n, double a, double b) {
    GaussRule rule;
    for (int i = 0; i < n; ++i) {
        double x = std::cos(kPi * (i + 0.75) / (n + 0.5));
        double derivative = 1.0;
        for (int iteration = 0; iteration < 100; ++iteration) {
            double p = 1.0, previous = 0.0;
            for (int k = 1; k <= n; ++k) {
                const double next = ((2 * k - 1) * x * p - (k - 1) * previous) / k;
                previous = p;
                p = next;
            }
            derivative = n * (x * p - previous) / (x * x - 1.0);
            const double step = p / derivative;
            x -= step;
            if (std::abs(step) < 1e-16) break;
        }
        const double w = 2.0 / ((1.0 - x * x) * derivative * derivative);
        rule.nodes.push_back(0.5 * (a + b) + 0.5 * (b - a) * x);
        rule.weights.push_back(0.5 * (b - a) * w);
    }
    return rule;
}

/// A unit vector and its quadrature weight (steradians).
struct SpherePoint {
    glm::dvec3 direction;
    double weight;
};

/// Product quadrature over the zone t = axis·ω in [t0, t1]: Gauss-Legendre in t times a
/// uniform rule in the azimuth about axis. Exact for polynomials in ω of degree
/// < min(2 nT, nPhi) restricted to the zone.
std::vector<SpherePoint> zoneQuadrature(const glm::dvec3& axis, double t0, double t1, int nT,
                                        int nPhi) {
    const glm::dvec3 helper = std::abs(axis.z) < 0.9 ? glm::dvec3(0, 0, 1) : glm::dvec3(1, 0, 0);
    const glm::dvec3 e1 = glm::normalize(glm::cross(helper, axis));
    const glm::dvec3 e2 = glm::cross(axis, e1);
    const GaussRule rule = gaussLegendre(nT, t0, t1);
    std::vector<SpherePoint> points;
    for (int i = 0; i < nT; ++i) {
        const double t = rule.nodes[i];
        const double s = std::sqrt(std::max(0.0, 1.0 - t * t));
        for (int j = 0; j < nPhi; ++j) {
            // Offset azimuth so that no sample sits on a coordinate plane by construction.
            const double phi = 2.0 * kPi * (j + 0.37) / nPhi;
            points.push_back({t * axis + s * (std::cos(phi) * e1 + std::sin(phi) * e2),
                              rule.weights[i] * 2.0 * kPi / nPhi});
        }
    }
    return points;
}

/// Whole-sphere quadrature exact for polynomials of degree <= 31 (far above 2 l_max = 14).
std::vector<SpherePoint> sphereQuadrature() {
    return zoneQuadrature({0, 0, 1}, -1.0, 1.0, 16, 32);
}

/// ∫ f(ω) y_i(ω) dω for i < shCount(bands), evaluated with the given quadrature.
ShVector project(const std::vector<SpherePoint>& points,
                 const std::function<double(const glm::dvec3&)>& f, int bands = kMaxShBands) {
    ShVector coeffs{};
    std::array<float, kMaxCount> basis;
    for (const SpherePoint& point : points) {
        shEvaluate(bands, glm::vec3(point.direction), basis.data());
        const double value = f(point.direction) * point.weight;
        for (int i = 0; i < shCount(bands); ++i) coeffs[i] += value * basis[i];
    }
    return coeffs;
}

/// Deterministic, well spread unit vectors (Fibonacci sphere).
std::vector<glm::vec3> fibonacciDirections(int count) {
    std::vector<glm::vec3> directions;
    const double goldenAngle = kPi * (3.0 - std::sqrt(5.0));
    for (int i = 0; i < count; ++i) {
        const double z = 1.0 - (2.0 * i + 1.0) / count;
        const double r = std::sqrt(1.0 - z * z);
        const double phi = goldenAngle * i;
        directions.emplace_back(float(r * std::cos(phi)), float(r * std::sin(phi)), float(z));
    }
    return directions;
}

/// Axes, diagonals and generic directions used as lobe axes.
std::vector<glm::dvec3> testAxes() {
    return {{0, 0, 1},
            {0, 0, -1},
            {1, 0, 0},
            glm::normalize(glm::dvec3(1, -1, 0)),
            glm::normalize(glm::dvec3(0.3, -0.5, 0.81)),
            glm::normalize(glm::dvec3(-0.7, 0.2, -0.4))};
}

/// Reference K_l of a zonal function g: 2π ∫ g(t) P_l(t) dt over [t0, 1] by Gauss-Legendre.
double zonalReference(int l, double t0, const std::function<double(double)>& g, int nodes) {
    const GaussRule rule = gaussLegendre(nodes, t0, 1.0);
    double sum = 0.0;
    for (int i = 0; i < nodes; ++i)
        sum += rule.weights[i] * g(rule.nodes[i]) * std::legendre(l, rule.nodes[i]);
    return 2.0 * kPi * sum;
}

/// The basis straight from its definition (associated Legendre without Condon-Shortley phase,
/// trigonometric azimuth), independent of the recurrences in shEvaluate.
double basisFromDefinition(int l, int m, const glm::dvec3& d) {
    const double phi = std::atan2(d.y, d.x);
    const int am = std::abs(m);
    double factorialRatio = 1.0;  // (l - |m|)! / (l + |m|)!
    for (int k = l - am + 1; k <= l + am; ++k) factorialRatio /= k;
    const double norm = std::sqrt((2 * l + 1) / (4.0 * kPi) * factorialRatio);
    // libstdc++'s std::assoc_legendre omits the (-1)^m phase, as does pic's convention.
    const double legendre = std::assoc_legendre(l, am, d.z);
    if (m == 0) return norm * legendre;
    const double azimuth = m > 0 ? std::cos(am * phi) : std::sin(am * phi);
    return std::sqrt(2.0) * norm * legendre * azimuth;
}

TEST(ShBasis, MatchesAssociatedLegendreDefinition) {
    std::array<float, kMaxCount> basis;
    for (const glm::vec3& d : fibonacciDirections(2000)) {
        shEvaluate(kMaxShBands, d, basis.data());
        for (int l = 0; l < kMaxShBands; ++l)
            for (int m = -l; m <= l; ++m)
                ASSERT_NEAR(basis[shIndex(l, m)], basisFromDefinition(l, m, glm::dvec3(d)), 2e-5)
                    << "l=" << l << " m=" << m;
    }
}

TEST(ShBasis, LowBandsFollowTheStatedSignConvention) {
    const glm::dvec3 d = glm::normalize(glm::dvec3(0.36, -0.48, 0.8));
    std::array<float, kMaxCount> basis;
    shEvaluate(3, glm::vec3(d), basis.data());
    const double c1 = std::sqrt(3.0 / (4.0 * kPi));
    EXPECT_NEAR(basis[0], 0.5 / std::sqrt(kPi), 1e-7);
    EXPECT_NEAR(basis[shIndex(1, -1)], c1 * d.y, 1e-6);
    EXPECT_NEAR(basis[shIndex(1, 0)], c1 * d.z, 1e-6);
    EXPECT_NEAR(basis[shIndex(1, 1)], c1 * d.x, 1e-6);
    EXPECT_NEAR(basis[shIndex(2, -2)], std::sqrt(15.0 / (4.0 * kPi)) * d.x * d.y, 1e-6);
    EXPECT_NEAR(basis[shIndex(2, -1)], std::sqrt(15.0 / (4.0 * kPi)) * d.y * d.z, 1e-6);
    EXPECT_NEAR(basis[shIndex(2, 0)], std::sqrt(5.0 / (16.0 * kPi)) * (3 * d.z * d.z - 1), 1e-6);
    EXPECT_NEAR(basis[shIndex(2, 1)], std::sqrt(15.0 / (4.0 * kPi)) * d.x * d.z, 1e-6);
    EXPECT_NEAR(basis[shIndex(2, 2)], std::sqrt(15.0 / (16.0 * kPi)) * (d.x * d.x - d.y * d.y),
                1e-6);
}

TEST(ShBasis, FewerBandsArePrefixOfMoreBands) {
    const glm::vec3 d = glm::normalize(glm::vec3(-0.2f, 0.9f, 0.3f));
    std::array<float, kMaxCount> full;
    shEvaluate(kMaxShBands, d, full.data());
    for (int bands = 1; bands < kMaxShBands; ++bands) {
        std::array<float, kMaxCount> partial;
        partial.fill(-7.0f);
        shEvaluate(bands, d, partial.data());
        for (int i = 0; i < shCount(bands); ++i)
            EXPECT_EQ(partial[i], full[i]) << bands << " " << i;
        // Nothing beyond shCount(bands) is written.
        for (int i = shCount(bands); i < kMaxCount; ++i) EXPECT_EQ(partial[i], -7.0f);
    }
}

TEST(ShBasis, LanesEvaluateEachDirectionAsTheScalarBasis) {
    // Four directions in the lanes of one vector (as the CPU twin's cache lighting evaluates
    // them): every lane holds its own direction's basis, as shEvaluate gives it.
    using Lanes = float __attribute__((vector_size(4 * sizeof(float))));
    const std::array<glm::vec3, 4> d = {
        glm::normalize(glm::vec3(-0.2f, 0.9f, 0.3f)), glm::vec3(0.0f, 0.0f, -1.0f),
        glm::normalize(glm::vec3(0.7f, -0.1f, 0.7f)), glm::normalize(glm::vec3(-1.0f, -2.0f, 0.5f))};
    Lanes x, y, z;
    for (int k = 0; k < 4; ++k) x[k] = d[k].x, y[k] = d[k].y, z[k] = d[k].z;
    std::array<Lanes, kMaxCount> lanes;
    shEvaluateLanes<kMaxShBands>(x, y, z, lanes.data());
    for (int k = 0; k < 4; ++k) {
        std::array<float, kMaxCount> scalar;
        shEvaluate(kMaxShBands, d[k], scalar.data());
        for (int i = 0; i < kMaxCount; ++i)
            EXPECT_NEAR(lanes[i][k], scalar[i], 1e-6f * (1.0f + std::abs(scalar[i])))
                << "lane " << k << " basis " << i;
    }
}

TEST(ShBasis, OrthonormalUpToEightBands) {
    // Gram matrix with an exact product rule: the identity up to float evaluation error.
    const std::vector<SpherePoint> points = sphereQuadrature();
    std::vector<double> gram(kMaxCount * kMaxCount, 0.0);
    std::array<float, kMaxCount> basis;
    for (const SpherePoint& point : points) {
        shEvaluate(kMaxShBands, glm::vec3(point.direction), basis.data());
        for (int i = 0; i < kMaxCount; ++i)
            for (int j = 0; j < kMaxCount; ++j)
                gram[i * kMaxCount + j] += point.weight * basis[i] * basis[j];
    }
    for (int i = 0; i < kMaxCount; ++i)
        for (int j = 0; j < kMaxCount; ++j)
            ASSERT_NEAR(gram[i * kMaxCount + j], i == j ? 1.0 : 0.0, 1e-5) << i << "," << j;
}

TEST(ShBasis, OrthonormalOnFibonacciSphere) {
    // The same with an unstructured equal-weight point set, independent of the z axis.
    const std::vector<glm::vec3> directions = fibonacciDirections(40000);
    const double weight = 4.0 * kPi / directions.size();
    std::vector<double> gram(kMaxCount * kMaxCount, 0.0);
    std::array<float, kMaxCount> basis;
    for (const glm::vec3& d : directions) {
        shEvaluate(kMaxShBands, d, basis.data());
        for (int i = 0; i < kMaxCount; ++i)
            for (int j = 0; j < kMaxCount; ++j)
                gram[i * kMaxCount + j] += weight * basis[i] * basis[j];
    }
    for (int i = 0; i < kMaxCount; ++i)
        for (int j = 0; j < kMaxCount; ++j)
            ASSERT_NEAR(gram[i * kMaxCount + j], i == j ? 1.0 : 0.0, 2e-3) << i << "," << j;
}

TEST(ShProjection, ConstantIsExact) {
    const double c = 2.5;
    const ShVector coeffs = project(sphereQuadrature(), [c](const glm::dvec3&) { return c; });
    EXPECT_NEAR(coeffs[0], c * std::sqrt(4.0 * kPi), 1e-6);
    for (int i = 1; i < kMaxCount; ++i) EXPECT_NEAR(coeffs[i], 0.0, 1e-6) << i;
}

TEST(ShProjection, PolynomialOfDegreeSevenIsReproduced) {
    // A polynomial of degree <= 7 lies in the span of 8 bands, so projecting and evaluating
    // gives it back exactly; with 3 bands only its degree <= 2 part survives.
    const auto f = [](const glm::dvec3& d) {
        return 0.3 + d.x - 2.0 * d.y * d.z + 0.5 * d.x * d.x * d.x * d.z - std::pow(d.z, 7) +
               0.25 * d.x * d.y * std::pow(d.y, 4);
    };
    const ShVector coeffs = project(sphereQuadrature(), f);
    std::array<float, kMaxCount> coeffsF;
    for (int i = 0; i < kMaxCount; ++i) coeffsF[i] = float(coeffs[i]);
    std::array<float, kMaxCount> basis;
    double maxError = 0.0;
    for (const glm::vec3& d : fibonacciDirections(500)) {
        shEvaluate(kMaxShBands, d, basis.data());
        maxError = std::max(maxError, std::abs(shDot(kMaxShBands, coeffsF.data(), basis.data()) -
                                               f(glm::dvec3(d))));
    }
    EXPECT_LT(maxError, 2e-5);
    // Bands 3..7 carry the cubic and higher terms: a 3-band truncation must visibly differ.
    double truncationError = 0.0;
    for (const glm::vec3& d : fibonacciDirections(500)) {
        shEvaluate(3, d, basis.data());
        truncationError = std::max(
            truncationError, std::abs(shDot(3, coeffsF.data(), basis.data()) - f(glm::dvec3(d))));
    }
    EXPECT_GT(truncationError, 0.1);
}

TEST(ShProjection, DotIsTheIntegralOfTheProduct) {
    const auto f = [](const glm::dvec3& d) { return 1.0 + d.x * d.y - d.z * d.z * d.z; };
    const auto g = [](const glm::dvec3& d) { return d.y + 0.5 * d.x * d.z * d.z * d.z; };
    const std::vector<SpherePoint> points = sphereQuadrature();
    const ShVector fc = project(points, f);
    const ShVector gc = project(points, g);
    std::array<float, kMaxCount> ff, gf;
    for (int i = 0; i < kMaxCount; ++i) ff[i] = float(fc[i]), gf[i] = float(gc[i]);
    double integral = 0.0;
    for (const SpherePoint& p : points) integral += p.weight * f(p.direction) * g(p.direction);
    EXPECT_NEAR(shDot(kMaxShBands, ff.data(), gf.data()), integral, 1e-5);
    EXPECT_NE(integral, 0.0);
}

TEST(ShZonal, ClampedCosineKnownValues) {
    const std::array<double, 8> expected = {kPi,       2 * kPi / 3, kPi / 4,  0,
                                            -kPi / 24, 0,           kPi / 64, 0};
    for (int l = 0; l < kMaxShBands; ++l) EXPECT_NEAR(clampedCosineZonal(l), expected[l], 1e-6);
}

TEST(ShZonal, ClampedCosineMatchesQuadrature) {
    // Full 2D projection of max(0, z·ω) (zero below the horizon, so only t in [0, 1]).
    const ShVector coeffs = project(zoneQuadrature({0, 0, 1}, 0.0, 1.0, 12, 32),
                                    [](const glm::dvec3& d) { return d.z; });
    std::array<float, kMaxCount> basisZ;
    shEvaluate(kMaxShBands, {0, 0, 1}, basisZ.data());
    for (int l = 0; l < kMaxShBands; ++l)
        for (int m = -l; m <= l; ++m)
            EXPECT_NEAR(coeffs[shIndex(l, m)], clampedCosineZonal(l) * basisZ[shIndex(l, m)], 2e-6)
                << "l=" << l << " m=" << m;
}

TEST(ShZonal, CosineLobeMatchesQuadratureAndRecurrence) {
    for (const double n : {1.0, 4.0, 30.0, 2.5}) {
        for (int l = 0; l < kMaxShBands; ++l) {
            // s_l(n) = (n+1) ∫_0^1 t^n P_l(t) dt; 64 nodes resolve t^30 and t^2.5 to ~1e-10.
            const double reference = (n + 1.0) / (2.0 * kPi) *
                                     zonalReference(
                                         l, 0.0, [n](double t) { return std::pow(t, n); }, 64);
            EXPECT_NEAR(cosineLobeFactor(l, float(n)), reference, 2e-7) << "n=" << n << " l=" << l;
        }
        // Closed forms of the first bands from the paper's recurrence.
        EXPECT_NEAR(cosineLobeFactor(0, float(n)), 1.0, 1e-7);
        EXPECT_NEAR(cosineLobeFactor(1, float(n)), (n + 1) / (n + 2), 1e-7);
        EXPECT_NEAR(cosineLobeFactor(2, float(n)), n / (n + 3), 1e-7);
        EXPECT_NEAR(cosineLobeFactor(3, float(n)), (n + 1) * (n - 1) / ((n + 2) * (n + 4)), 1e-7);
    }
    // The diffuse lobe max(0, cos)/π is the n = 1 lobe.
    for (int l = 0; l < kMaxShBands; ++l)
        EXPECT_NEAR(cosineLobeFactor(l, 1.0f) * kPi, clampedCosineZonal(l), 1e-6);
}

TEST(ShZonal, ConeMatchesQuadratureFromTinyToFullSphere) {
    for (const double u : {1e-8, 1e-6, 1e-4, 0.01, 0.3, 1.0, 1.7, 2.0 - 1e-6, 2.0}) {
        std::array<double, kMaxShBands> bands;
        coneZonalBands(kMaxShBands, u, bands.data());
        for (int l = 0; l < kMaxShBands; ++l) {
            // 2π ∫_0^u P_l(1 - v) dv: 8 nodes integrate the degree-7 polynomial exactly, and
            // sampling P_l near t = 1 has no cancellation.
            const GaussRule rule = gaussLegendre(8, 0.0, u);
            double reference = 0.0;
            for (int i = 0; i < 8; ++i)
                reference += rule.weights[i] * std::legendre(l, 1.0 - rule.nodes[i]);
            reference *= 2.0 * kPi;
            // Relative to the cone's solid angle 2πu, the natural scale of every K_l.
            EXPECT_NEAR(coneZonal(l, u), reference, 1e-9 * 2.0 * kPi * u)
                << "u=" << u << " l=" << l;
            EXPECT_EQ(bands[l], coneZonal(l, u));
        }
    }
}

TEST(ShZonal, ConeMatchesPaperAppendixC) {
    // Appendix C with the minus signs the text extraction lost restored.
    for (const double c : {0.95, 0.5, 0.0, -0.7}) {
        const double c2 = c * c, c3 = c2 * c, c4 = c3 * c, c5 = c4 * c, c6 = c5 * c, c7 = c6 * c,
                     c8 = c7 * c;
        const std::array<double, 8> paper = {
            -2 * kPi * (c - 1),
            -kPi * (c2 - 1),
            -kPi * (c3 - c),
            -kPi / 4 * (5 * c4 - 6 * c2 + 1),
            -kPi / 4 * (7 * c5 - 10 * c3 + 3 * c),
            -kPi / 8 * (21 * c6 - 35 * c4 + 15 * c2 - 1),
            -kPi / 8 * (33 * c7 - 63 * c5 + 35 * c3 - 5 * c),
            -kPi / 64 * (429 * c8 - 924 * c6 + 630 * c4 - 140 * c2 + 5)};
        for (int l = 0; l < kMaxShBands; ++l)
            EXPECT_NEAR(coneZonal(l, 1.0 - c), paper[l], 1e-12) << "cos=" << c << " l=" << l;
    }
}

TEST(ShZonal, TinyConeLimit) {
    // K_l(u) = 2π (u - l(l+1) u²/4 + O(u³)); the closed forms lose every digit here.
    for (const double u : {1e-8, 1e-7, 1e-6}) {
        EXPECT_NEAR(coneZonal(0, u), 2.0 * kPi * u, 1e-15 * u);
        for (int l = 1; l < kMaxShBands; ++l) {
            const double expected = 2.0 * kPi * u * (1.0 - l * (l + 1) * u / 4.0);
            EXPECT_NEAR(coneZonal(l, u) / expected, 1.0, 1e-9) << "u=" << u << " l=" << l;
        }
    }
    EXPECT_EQ(coneZonal(3, 0.0), 0.0);
}

TEST(ShZonal, FullSphereCone) {
    EXPECT_NEAR(coneZonal(0, 2.0), 4.0 * kPi, 1e-14);
    for (int l = 1; l < kMaxShBands; ++l) EXPECT_NEAR(coneZonal(l, 2.0), 0.0, 1e-14) << l;
}

TEST(ShZonal, ConeBeyondEightBands) {
    // coneZonal is not limited to kMaxShBands; 8 Gauss nodes are exact up to degree 15.
    for (const int l : {8, 9, 15})
        EXPECT_NEAR(coneZonal(l, 0.3),
                    zonalReference(
                        l, 0.7, [](double) { return 1.0; }, 8),
                    1e-12)
            << l;
}

/// Projection of a zonal function g(axis·ω) by quadrature over [t0, 1] around the axis.
ShVector projectZonal(const glm::dvec3& axis, double t0, const std::function<double(double)>& g) {
    return project(zoneQuadrature(axis, t0, 1.0, 24, 32),
                   [&](const glm::dvec3& d) { return g(glm::dot(axis, d)); });
}

void expectCoefficientsNear(const ShVector& expected, const float* actual, double tolerance,
                            const char* what) {
    for (int i = 0; i < kMaxCount; ++i)
        ASSERT_NEAR(actual[i], expected[i], tolerance) << what << " coefficient " << i;
}

TEST(ShRotation, ZonalLobesAroundArbitraryAxes) {
    // Paper eq. 5: the projection of a lobe around any axis d is K_l y_l^m(d).
    for (const glm::dvec3& axis : testAxes()) {
        const glm::vec3 d(axis);
        std::array<float, kMaxCount> coeffs{};
        shAddClampedCosine(kMaxShBands, d, 1.5f, coeffs.data());
        expectCoefficientsNear(projectZonal(axis, 0.0, [](double t) { return 1.5 * t; }),
                               coeffs.data(), 5e-6, "clamped cosine");

        for (const double cosAlpha : {0.999, 0.3, -0.8}) {
            coeffs.fill(0.0f);
            shAddCone(kMaxShBands, d, float(1.0 - cosAlpha), 2.0f, coeffs.data());
            expectCoefficientsNear(projectZonal(axis, cosAlpha, [](double) { return 2.0; }),
                                   coeffs.data(), 1e-5, "cone");
        }

        for (const float n : {4.0f, 30.0f}) {
            std::array<float, kMaxCount> basis;
            shEvaluate(kMaxShBands, d, basis.data());
            for (int i = 0; i < kMaxCount; ++i) {
                const int l = int(std::sqrt(float(i)));
                coeffs[i] = cosineLobeFactor(l, n) * basis[i];
            }
            const ShVector expected = projectZonal(
                axis, 0.0, [n](double t) { return (n + 1) / (2 * kPi) * std::pow(t, n); });
            expectCoefficientsNear(expected, coeffs.data(), 5e-6, "cosine lobe");
        }
    }
}

TEST(ShRotation, ClampedCosineOnAnUnalignedPointSet) {
    // The same statement with a quadrature that knows nothing about the lobe axis.
    const glm::dvec3 axis = glm::normalize(glm::dvec3(0.3, -0.5, 0.81));
    const std::vector<glm::vec3> directions = fibonacciDirections(200000);
    ShVector expected{};
    std::array<float, kMaxCount> basis;
    for (const glm::vec3& d : directions) {
        const double value =
            std::max(0.0, glm::dot(axis, glm::dvec3(d))) * 4.0 * kPi / directions.size();
        shEvaluate(kMaxShBands, d, basis.data());
        for (int i = 0; i < kMaxCount; ++i) expected[i] += value * basis[i];
    }
    std::array<float, kMaxCount> coeffs{};
    shAddClampedCosine(kMaxShBands, glm::vec3(axis), 1.0f, coeffs.data());
    expectCoefficientsNear(expected, coeffs.data(), 1e-4, "clamped cosine");
}

TEST(ShRotation, ConeProjectionIntegratesToSolidAngle) {
    // ∫ cone = <projection, 1>, and 1 has the single coefficient sqrt(4π).
    std::array<float, kMaxCount> one{};
    one[0] = float(std::sqrt(4.0 * kPi));
    for (const float u : {1e-6f, 0.05f, 1.2f, 2.0f}) {
        for (int bands = 1; bands <= kMaxShBands; ++bands) {
            std::array<float, kMaxCount> coeffs{};
            shAddCone(bands, glm::normalize(glm::vec3(1, 2, -2)), u, 1.0f, coeffs.data());
            EXPECT_NEAR(shDot(bands, coeffs.data(), one.data()), 2.0 * kPi * u, 1e-6 * u);
        }
    }
}

TEST(ShShading, IrradianceOfConstantRadianceIsPi) {
    const float radiance = 0.8f;
    std::array<float, kMaxCount> coeffs{};
    coeffs[0] = radiance * float(std::sqrt(4.0 * kPi));
    for (int bands = 1; bands <= kMaxShBands; ++bands)
        for (const glm::vec3& n : fibonacciDirections(50)) {
            EXPECT_NEAR(shIrradiance(bands, coeffs.data(), n), kPi * radiance, 1e-5);
            EXPECT_NEAR(shGlossy(bands, coeffs.data(), n, 12.0f), radiance, 1e-6);
        }
}

/// A smooth radiance of degree 7, exactly representable with 8 bands.
double testRadiance(const glm::dvec3& d) {
    return 1.0 + 0.5 * d.x - 0.3 * d.y * d.z + 0.2 * d.z * d.z + 0.4 * std::pow(d.x, 3) * d.y -
           0.3 * std::pow(d.z, 7) + 0.2 * d.x * d.y * std::pow(d.z, 4);
}

TEST(ShShading, IrradianceAndGlossyMatchQuadrature) {
    const ShVector radiance = project(sphereQuadrature(), testRadiance);
    std::array<float, kMaxCount> radianceF;
    for (int i = 0; i < kMaxCount; ++i) radianceF[i] = float(radiance[i]);
    for (const glm::dvec3& n : testAxes()) {
        // ∫ L(ω) max(0, n·ω) dω and the normalised lobe integral, straight by quadrature.
        double irradiance = 0.0, glossy4 = 0.0, glossy30 = 0.0;
        for (const SpherePoint& p : zoneQuadrature(n, 0.0, 1.0, 40, 32)) {
            const double t = glm::dot(n, p.direction);
            const double l = testRadiance(p.direction) * p.weight;
            irradiance += l * t;
            glossy4 += l * 5.0 / (2.0 * kPi) * std::pow(t, 4);
            glossy30 += l * 31.0 / (2.0 * kPi) * std::pow(t, 30);
        }
        // The radiance is band-limited to 8 bands, so these SH results are exact.
        EXPECT_NEAR(shIrradiance(kMaxShBands, radianceF.data(), glm::vec3(n)), irradiance, 2e-5);
        EXPECT_NEAR(shGlossy(kMaxShBands, radianceF.data(), glm::vec3(n), 4.0f), glossy4, 2e-5);
        EXPECT_NEAR(shGlossy(kMaxShBands, radianceF.data(), glm::vec3(n), 30.0f), glossy30, 2e-5);
    }
}

}  // namespace
}  // namespace pic
