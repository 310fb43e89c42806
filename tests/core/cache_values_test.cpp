#include "core/cache_values.h"

#include <cmath>
#include <functional>
#include <numbers>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "core/color.h"
#include "core/sh.h"

namespace pic {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;
constexpr uint32_t kBandsY = 3;
constexpr uint32_t kBandsC = 2;
constexpr uint32_t kGridCaches = 8;      // caches 0..7: the 2×2×2 grid
constexpr uint32_t kLightmapCaches = 4;  // caches 8..11: the 2×2 light map
const glm::vec3 kOrigin(1.0f, 2.0f, 3.0f);
constexpr float kCell = 0.5f;

/// A bake with a 2×2×2 grid (vertex (i,j,k) holds cache i + 2j + 4k) and a 2×2 light map
/// (texel (x,y) holds cache 8 + x + 2y). Triangle 0 maps barycentrics (b1, b2) to light-map UV
/// (b1, b2); triangle 1 is not light-mapped.
BakeData makeBake() {
    BakeData bake;
    bake.params.bandsY = kBandsY;
    bake.params.bandsC = kBandsC;
    bake.grid.origin = kOrigin;
    bake.grid.cellSize = kCell;
    bake.grid.dims = glm::uvec3(2);
    for (uint32_t i = 0; i < kGridCaches; ++i) bake.grid.cacheIndex.push_back(i);
    bake.lightmap.width = 2;
    bake.lightmap.height = 2;
    for (uint32_t i = 0; i < kLightmapCaches; ++i)
        bake.lightmap.cacheIndex.push_back(kGridCaches + i);
    bake.lightmap.triangleUvs = {{0, 0},
                                 {1, 0},
                                 {0, 1},
                                 glm::vec2(kNotLightmapped),
                                 glm::vec2(kNotLightmapped),
                                 glm::vec2(kNotLightmapped)};
    return bake;
}

glm::vec3 gridVertex(uint32_t cache) {
    return kOrigin +
           kCell * glm::vec3(float(cache & 1u), float((cache >> 1) & 1u), float(cache >> 2));
}

/// Texel-centre UV of light-map cache 8 + x + 2y.
glm::vec2 texelCentre(uint32_t cache) {
    const uint32_t t = cache - kGridCaches;
    return (glm::vec2(float(t % 2), float(t / 2)) + 0.5f) / 2.0f;
}

/// Coefficient i of a cache's Y, Co, Cg: an affine function of the cache's position (grid
/// vertex, or texel centre in UV for light-map caches), distinct per coefficient, so that
/// multilinear interpolation must reproduce it exactly everywhere.
glm::vec3 affineValue(uint32_t cache, int i) {
    const glm::vec3 p =
        cache < kGridCaches ? gridVertex(cache) - kOrigin : glm::vec3(texelCentre(cache), 0.0f);
    const float fi = float(i);
    return {1.0f + fi + 0.7f * p.x - 0.3f * p.y + 0.2f * (fi + 1.0f) * p.z,
            0.1f * fi - 0.4f * p.x + 0.25f * p.y + 0.5f * p.z,
            -0.2f + 0.05f * fi + 0.3f * p.x + 0.6f * p.y - 0.1f * p.z};
}

CacheValues makeValues() {
    CacheValues values = CacheValues::zeros(kGridCaches + kLightmapCaches, kBandsY, kBandsC);
    for (uint32_t c = 0; c < kGridCaches + kLightmapCaches; ++c) {
        for (int i = 0; i < shCount(kBandsY); ++i)
            values.y[c * shCount(kBandsY) + i] = affineValue(c, i).x;
        for (int i = 0; i < shCount(kBandsC); ++i) {
            values.co[c * shCount(kBandsC) + i] = affineValue(c, i).y;
            values.cg[c * shCount(kBandsC) + i] = affineValue(c, i).z;
        }
    }
    return values;
}

/// Expected RGB of coefficient i from YCoCg, above lC² with the chroma per luma of band 0.
glm::vec3 toRgb(const glm::vec3& yCoCg, const glm::vec3& band0, int i) {
    if (i < shCount(kBandsC)) return yCoCgToRgb(yCoCg);
    const glm::vec2 ratio = chromaPerLuma(band0);
    return yCoCgToRgb({yCoCg.x, ratio.x * yCoCg.x, ratio.y * yCoCg.x});
}

void expectRadiance(const RadianceSh& radiance, const std::function<glm::vec3(int)>& expectedYCoCg,
                    float tolerance = 1e-5f) {
    ASSERT_EQ(radiance.bands, kBandsY);
    for (int i = 0; i < shCount(kBandsY); ++i) {
        const glm::vec3 expected = toRgb(expectedYCoCg(i), expectedYCoCg(0), i);
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(radiance.rgb[c][i], expected[c], tolerance)
                << "coefficient " << i << " channel " << c;
    }
}

TEST(GridLookup, VerticesAreExact) {
    const BakeData bake = makeBake();
    const CacheValues values = makeValues();
    for (uint32_t v = 0; v < kGridCaches; ++v)
        expectRadiance(lookupGridRadiance(bake, values, gridVertex(v)),
                       [&](int i) { return affineValue(v, i); });
}

TEST(GridLookup, CentreIsTheMeanOfTheEightVertices) {
    const BakeData bake = makeBake();
    const CacheValues values = makeValues();
    expectRadiance(lookupGridRadiance(bake, values, kOrigin + glm::vec3(0.5f * kCell)), [&](int i) {
        glm::vec3 sum(0.0f);
        for (uint32_t v = 0; v < kGridCaches; ++v) sum += affineValue(v, i);
        return sum / 8.0f;
    });
}

TEST(GridLookup, TrilinearReproducesAffineValues) {
    const BakeData bake = makeBake();
    const CacheValues values = makeValues();
    // An affine function of position is reproduced exactly by trilinear interpolation.
    const glm::vec3 offset(0.13f, 0.41f, 0.27f);
    const RadianceSh radiance = lookupGridRadiance(bake, values, kOrigin + offset);
    expectRadiance(radiance, [&](int i) {
        const float fi = float(i);
        const glm::vec3& p = offset;
        return glm::vec3(1.0f + fi + 0.7f * p.x - 0.3f * p.y + 0.2f * (fi + 1.0f) * p.z,
                         0.1f * fi - 0.4f * p.x + 0.25f * p.y + 0.5f * p.z,
                         -0.2f + 0.05f * fi + 0.3f * p.x + 0.6f * p.y - 0.1f * p.z);
    });
}

TEST(GridLookup, MissingVertexIsRenormalisedAway) {
    BakeData bake = makeBake();
    bake.grid.cacheIndex[7] = kNoCache;
    const CacheValues values = makeValues();
    expectRadiance(lookupGridRadiance(bake, values, kOrigin + glm::vec3(0.5f * kCell)), [&](int i) {
        glm::vec3 sum(0.0f);
        for (uint32_t v = 0; v < 7; ++v) sum += affineValue(v, i);
        return sum / 7.0f;
    });
    // Exactly on the missing vertex every remaining weight is zero: its 7 neighbours are
    // averaged rather than returning black.
    expectRadiance(lookupGridRadiance(bake, values, gridVertex(7)), [&](int i) {
        glm::vec3 sum(0.0f);
        for (uint32_t v = 0; v < 7; ++v) sum += affineValue(v, i);
        return sum / 7.0f;
    });
}

TEST(GridLookup, OutsidePointsTakeTheNearestBoundaryValue) {
    const BakeData bake = makeBake();
    const CacheValues values = makeValues();
    // Beyond vertex 0 diagonally: its value.
    expectRadiance(lookupGridRadiance(bake, values, kOrigin - glm::vec3(3.0f)),
                   [&](int i) { return affineValue(0, i); });
    // Beyond the face x = max at the middle of the face: the mean of vertices 1, 3, 5, 7.
    expectRadiance(
        lookupGridRadiance(bake, values, kOrigin + glm::vec3(9.0f, 0.25f, 0.25f)), [&](int i) {
            return 0.25f *
                   (affineValue(1, i) + affineValue(3, i) + affineValue(5, i) + affineValue(7, i));
        });
}

TEST(GridLookup, NoCacheAroundGivesZero) {
    BakeData bake = makeBake();
    bake.grid.cacheIndex.assign(8, kNoCache);
    const CacheValues values = makeValues();
    expectRadiance(lookupGridRadiance(bake, values, kOrigin + glm::vec3(0.1f)),
                   [](int) { return glm::vec3(0.0f); });
}

TEST(GridLookup, SingleVertexGridIsConstant) {
    BakeData bake = makeBake();
    bake.grid.dims = glm::uvec3(1);
    bake.grid.cacheIndex = {5};
    const CacheValues values = makeValues();
    for (const glm::vec3 p : {kOrigin, kOrigin + glm::vec3(0.3f, -2.0f, 7.0f)})
        expectRadiance(lookupGridRadiance(bake, values, p),
                       [&](int i) { return affineValue(5, i); });
}

TEST(LightmapLookup, TexelCentresAreExact) {
    const BakeData bake = makeBake();
    const CacheValues values = makeValues();
    for (uint32_t c = kGridCaches; c < kGridCaches + kLightmapCaches; ++c) {
        const glm::vec2 uv = texelCentre(c);
        expectRadiance(lookupSurfaceRadiance(bake, values, 0, uv.x, uv.y, glm::vec3(100.0f)),
                       [&](int i) { return affineValue(c, i); });
    }
}

TEST(LightmapLookup, BilinearReproducesAffineValues) {
    const BakeData bake = makeBake();
    const CacheValues values = makeValues();
    // The atlas centre is the mean of the 4 texels; any interior point is affine in UV.
    for (const glm::vec2 uv : {glm::vec2(0.5f, 0.5f), glm::vec2(0.31f, 0.62f)}) {
        expectRadiance(lookupSurfaceRadiance(bake, values, 0, uv.x, uv.y, glm::vec3(0.0f)),
                       [&](int i) {
                           const float fi = float(i);
                           return glm::vec3(1.0f + fi + 0.7f * uv.x - 0.3f * uv.y,
                                            0.1f * fi - 0.4f * uv.x + 0.25f * uv.y,
                                            -0.2f + 0.05f * fi + 0.3f * uv.x + 0.6f * uv.y);
                       });
    }
}

TEST(LightmapLookup, TexelsOutsideTheAtlasTakeNoWeight) {
    const BakeData bake = makeBake();
    const CacheValues values = makeValues();
    // UV (0.1, 0.25): texel space (-0.3, 0): half of the stencil lies left of the atlas, so
    // the value is texel (0, 0)'s alone.
    expectRadiance(lookupSurfaceRadiance(bake, values, 0, 0.1f, 0.25f, glm::vec3(0.0f)),
                   [&](int i) { return affineValue(kGridCaches, i); });
}

TEST(LightmapLookup, MissingTexelIsRenormalisedAway) {
    BakeData bake = makeBake();
    bake.lightmap.cacheIndex[3] = kNoCache;
    const CacheValues values = makeValues();
    expectRadiance(lookupSurfaceRadiance(bake, values, 0, 0.5f, 0.5f, glm::vec3(0.0f)), [&](int i) {
        return (affineValue(8, i) + affineValue(9, i) + affineValue(10, i)) / 3.0f;
    });
}

TEST(LightmapLookup, UnmappedTrianglesUseTheGrid) {
    const BakeData bake = makeBake();
    const CacheValues values = makeValues();
    const glm::vec3 p = kOrigin + glm::vec3(0.1f, 0.2f, 0.3f);
    const RadianceSh fromSurface = lookupSurfaceRadiance(bake, values, 1, 0.2f, 0.3f, p);
    const RadianceSh fromGrid = lookupGridRadiance(bake, values, p);
    for (int c = 0; c < 3; ++c)
        for (int i = 0; i < shCount(kBandsY); ++i)
            EXPECT_EQ(fromSurface.rgb[c][i], fromGrid.rgb[c][i]);
}

/// One cache of RGB SH `rgb` (bandsC = bandsY), the only vertex of a one-vertex grid.
struct SingleCache {
    BakeData bake;
    CacheValues values;

    SingleCache(uint32_t bands, const std::function<glm::vec3(int)>& rgb) {
        bake.grid.cellSize = 1.0f;
        bake.grid.dims = glm::uvec3(1);
        bake.grid.cacheIndex = {0};
        values = CacheValues::zeros(1, bands, bands);
        for (int i = 0; i < shCount(int(bands)); ++i) {
            const glm::vec3 yCoCg = rgbToYCoCg(rgb(i));
            values.y[i] = yCoCg.x;
            values.co[i] = yCoCg.y;
            values.cg[i] = yCoCg.z;
        }
    }
    RadianceSh radiance() const { return lookupGridRadiance(bake, values, glm::vec3(0.0f)); }
};

TEST(CacheRadiance, YCoCgRoundTrips) {
    const auto rgb = [](int i) {
        return glm::vec3(0.9f - 0.1f * float(i), 0.2f + 0.05f * float(i),
                         0.4f * std::sin(float(i)));
    };
    const SingleCache cache(4, rgb);
    const RadianceSh radiance = cache.radiance();
    ASSERT_EQ(radiance.bands, 4u);
    for (int i = 0; i < 16; ++i)
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(radiance.rgb[c][i], rgb(i)[c], 1e-6f);
}

TEST(CacheRadiance, BandsAboveLcTakeTheChromaOfBandZero) {
    // Radiance whose every coefficient has band 0's colour, stored with lC = 1: the luma keeps
    // the direction, the prediction the colour, so all 9 RGB coefficients come back.
    const glm::vec3 colour(0.8f, 0.4f, 0.2f);
    const auto rgb = [&](int i) { return colour * (i == 0 ? 2.0f : 0.3f - 0.1f * float(i)); };
    SingleCache cache(3, rgb);
    CacheValues truncated = CacheValues::zeros(1, 3, 1);
    truncated.y = cache.values.y;
    truncated.co = {cache.values.co[0]};
    truncated.cg = {cache.values.cg[0]};
    cache.values = truncated;
    const RadianceSh radiance = cache.radiance();
    for (int i = 0; i < 9; ++i)
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(radiance.rgb[c][i], rgb(i)[c], 1e-6f) << "coefficient " << i << " channel " << c;

    // Chroma per luma is clamped to what non-negative RGB allows (|Co| ≤ 2Y, |Cg| ≤ Y), and a
    // band 0 without light leaves the higher bands grey.
    EXPECT_EQ(chromaPerLuma({1.0f, 5.0f, -3.0f}), glm::vec2(2.0f, -1.0f));
    EXPECT_EQ(chromaPerLuma({0.0f, 1.0f, 1.0f}), glm::vec2(0.0f));
    EXPECT_EQ(chromaPerLuma({-1.0f, 1.0f, 1.0f}), glm::vec2(0.0f));
    for (const glm::vec3 pure : {glm::vec3(1, 0, 0), glm::vec3(0, 1, 0), glm::vec3(0, 0, 1),
                                 glm::vec3(1, 0, 1), glm::vec3(1, 1, 0)}) {
        const glm::vec3 v = rgbToYCoCg(pure);
        EXPECT_EQ(chromaPerLuma(v), glm::vec2(v.y, v.z) / v.x);  // inside the bounds
    }
    cache.values.y[0] = 0.0f;
    const RadianceSh dark = cache.radiance();
    for (int i = 1; i < 9; ++i)
        EXPECT_TRUE(dark.rgb[0][i] == dark.rgb[1][i] && dark.rgb[1][i] == dark.rgb[2][i]) << i;
}

TEST(CacheRadiance, ConstantRadianceGivesPiTimesRadiance) {
    const glm::vec3 radiance(0.5f, 1.25f, 3.0f);
    // A constant L has the single coefficient L / y_0^0 = L · 2√π.
    const SingleCache cache(
        3, [&](int i) { return i == 0 ? radiance * 2.0f * std::sqrt(kPi) : glm::vec3(0.0f); });
    for (const glm::vec3 n : {glm::vec3(0, 1, 0), glm::normalize(glm::vec3(1, -2, 0.5f))}) {
        const glm::vec3 e = irradiance(cache.radiance(), n);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(e[c], kPi * radiance[c], 1e-5f * kPi * radiance[c]);
    }
}

TEST(CacheRadiance, IrradianceOfALobeMatchesQuadrature) {
    // Radiance: the 5-band projection of a clamped-cosine lobe around d, tinted per channel.
    // Being band-limited, its irradiance is exactly ∫ L(ω) max(0, n·ω) dω, which a product
    // rule over the hemisphere around n evaluates independently of the SH kernel.
    constexpr int kBands = 5;
    const glm::vec3 d = glm::normalize(glm::vec3(0.3f, 0.8f, -0.5f));
    const glm::vec3 tint(1.0f, 0.5f, 0.25f);
    float lobe[shCount(kBands)] = {};
    shAddClampedCosine(kBands, d, 1.0f, lobe);
    const SingleCache cache(kBands, [&](int i) { return tint * lobe[i]; });
    const RadianceSh radiance = cache.radiance();

    for (const glm::vec3 n : {d, glm::normalize(glm::vec3(0.0f, 1.0f, 0.2f)),
                              glm::normalize(glm::vec3(-0.6f, 0.1f, 0.7f))}) {
        const glm::vec3 helper = std::abs(n.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
        const glm::dvec3 t = glm::normalize(glm::cross(helper, n));
        const glm::dvec3 b = glm::cross(glm::dvec3(n), t);
        constexpr int kTheta = 256;
        constexpr int kPhi = 512;
        double integral = 0.0;
        float basis[shCount(kBands)];
        for (int i = 0; i < kTheta; ++i) {
            const double theta = (i + 0.5) * (std::numbers::pi / 2) / kTheta;
            for (int j = 0; j < kPhi; ++j) {
                const double phi = (j + 0.5) * 2.0 * std::numbers::pi / kPhi;
                const glm::dvec3 w = std::sin(theta) * (std::cos(phi) * t + std::sin(phi) * b) +
                                     std::cos(theta) * glm::dvec3(n);
                shEvaluate(kBands, glm::vec3(w), basis);
                double l = 0.0;
                for (int k = 0; k < shCount(kBands); ++k) l += double(lobe[k]) * basis[k];
                integral += l * std::cos(theta) * std::sin(theta);
            }
        }
        integral *= (std::numbers::pi / 2 / kTheta) * (2.0 * std::numbers::pi / kPhi);
        const glm::vec3 e = irradiance(radiance, n);
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(e[c], tint[c] * integral, 2e-4 * std::abs(integral) + 1e-6)
                << "channel " << c;
    }
}

// Paper 001 §4: scaling the luma and chroma of every coefficient scales the reconstructed
// light's Y and CoCg alike (YCoCg is linear), and chroma 0 leaves grey light of the same Y.
TEST(ScaleLumaChroma, ScalesTheIrradiancesYAndCoCg) {
    RadianceSh radiance;
    radiance.bands = 3;
    for (int c = 0; c < 3; ++c)
        for (int i = 0; i < 9; ++i) radiance.rgb[c][i] = 0.1f * float(c + 1) + 0.03f * float(i);
    const glm::vec3 n = glm::normalize(glm::vec3(0.3f, 0.8f, -0.2f));
    const glm::vec3 before = rgbToYCoCg(irradiance(radiance, n));
    for (const auto& [y, cocg] : {std::pair{0.5f, 2.0f}, std::pair{1.0f, 0.0f}, std::pair{3.0f, 3.0f}}) {
        RadianceSh scaled = radiance;
        scaleLumaChroma(scaled, y, cocg);
        const glm::vec3 after = rgbToYCoCg(irradiance(scaled, n));
        EXPECT_NEAR(after.x, y * before.x, 1e-5f) << y << " " << cocg;
        EXPECT_NEAR(after.y, cocg * before.y, 1e-5f) << y << " " << cocg;
        EXPECT_NEAR(after.z, cocg * before.z, 1e-5f) << y << " " << cocg;
    }
    RadianceSh grey = radiance;
    scaleLumaChroma(grey, 1.0f, 0.0f);
    const glm::vec3 rgb = irradiance(grey, n);
    EXPECT_NEAR(rgb.r, rgb.g, 1e-5f);
    EXPECT_NEAR(rgb.g, rgb.b, 1e-5f);
}

}  // namespace
}  // namespace pic
