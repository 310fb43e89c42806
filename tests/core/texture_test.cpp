// Mip chains (sizes, means, constants, box weights at even and odd sides), the footprint rule
// (level of detail and anisotropic taps against hand-worked cases) and the filtered lookup on
// a tilted checkerboard against the brute-force average of each pixel's footprint.

#include "core/texture.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <optional>
#include <random>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "core/camera.h"
#include "core/scene.h"

namespace pic {
namespace {

void expectVecNear(const glm::vec4& a, const glm::vec4& b, float tolerance) {
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(a[c], b[c], tolerance) << "component " << c;
}

/// A width × height texture of uniform random texels in [0, 1)⁴.
Texture randomTexture(int width, int height, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    Texture t;
    t.width = width;
    t.height = height;
    for (int i = 0; i < width * height; ++i)
        t.texels.push_back({unit(rng), unit(rng), unit(rng), unit(rng)});
    return t;
}

glm::dvec4 meanOf(const std::vector<glm::vec4>& texels) {
    glm::dvec4 sum(0.0);
    for (const glm::vec4& t : texels) sum += glm::dvec4(t);
    return sum / double(texels.size());
}

TEST(MipChain, SidesHalveRoundingDownToOneByOne) {
    const std::pair<glm::ivec2, std::vector<glm::ivec2>> cases[] = {
        {{16, 16}, {{8, 8}, {4, 4}, {2, 2}, {1, 1}}},
        {{13, 7}, {{6, 3}, {3, 1}, {1, 1}}},
        {{1, 5}, {{1, 2}, {1, 1}}},
        {{1, 1}, {}},
    };
    for (const auto& [size, expected] : cases) {
        Texture t = randomTexture(size.x, size.y, 1);
        buildMipChain(t);
        ASSERT_EQ(t.mips.size(), expected.size()) << size.x << "x" << size.y;
        EXPECT_EQ(t.levelCount(), int(expected.size()) + 1);
        for (size_t k = 0; k < expected.size(); ++k) {
            EXPECT_EQ(t.mips[k].width, expected[k].x) << "level " << k + 1;
            EXPECT_EQ(t.mips[k].height, expected[k].y) << "level " << k + 1;
            EXPECT_EQ(t.mips[k].texels.size(), size_t(expected[k].x * expected[k].y));
        }
    }
}

TEST(MipChain, EveryLevelKeepsTheMean) {
    for (const glm::ivec2 size : {glm::ivec2(64, 32), glm::ivec2(13, 7), glm::ivec2(37, 20),
                                  glm::ivec2(3, 1), glm::ivec2(1, 9)}) {
        Texture t = randomTexture(size.x, size.y, 7);
        buildMipChain(t);
        const glm::dvec4 mean = meanOf(t.texels);
        for (size_t k = 0; k < t.mips.size(); ++k)
            for (int c = 0; c < 4; ++c)
                EXPECT_NEAR(meanOf(t.mips[k].texels)[c], mean[c], 2e-6)
                    << size.x << "x" << size.y << " level " << k + 1 << " component " << c;
        // The 1×1 top is the mean itself.
        ASSERT_FALSE(t.mips.empty());
        expectVecNear(t.mips.back().texels[0], glm::vec4(mean), 2e-6f);
    }
}

TEST(MipChain, ConstantTexturesStayConstant) {
    Texture t;
    t.width = 10;
    t.height = 7;
    t.texels.assign(70, glm::vec4(0.3f, 0.55f, 0.7f, 1.0f));
    buildMipChain(t);
    for (const MipLevel& level : t.mips)
        for (const glm::vec4& texel : level.texels)
            expectVecNear(texel, glm::vec4(0.3f, 0.55f, 0.7f, 1.0f), 1e-6f);
}

TEST(MipChain, EvenSidesAverageTwoByTwoBoxesOddSidesWeighByArea) {
    // Even: texel (x, y) of level 1 is the mean of texels 2x, 2x + 1 × 2y, 2y + 1.
    Texture even = randomTexture(4, 2, 3);
    buildMipChain(even);
    const auto at = [&](int x, int y) { return even.texels[size_t(y * 4 + x)]; };
    expectVecNear(even.mips[0].texels[1], 0.25f * (at(2, 0) + at(3, 0) + at(2, 1) + at(3, 1)),
                  1e-6f);
    // Odd, 5 → 2: texel 0 covers [0, 2.5): texels 0, 1 whole and half of 2.
    Texture odd;
    odd.width = 5;
    odd.height = 1;
    for (float v : {1.0f, 2.0f, 4.0f, 8.0f, 16.0f}) odd.texels.push_back(glm::vec4(v));
    buildMipChain(odd);
    ASSERT_EQ(odd.mips[0].width, 2);
    expectVecNear(odd.mips[0].texels[0], glm::vec4((1.0f + 2.0f + 0.5f * 4.0f) / 2.5f), 1e-6f);
    expectVecNear(odd.mips[0].texels[1], glm::vec4((0.5f * 4.0f + 8.0f + 16.0f) / 2.5f), 1e-6f);
    // 3 → 1: thirds.
    Texture three;
    three.width = 1;
    three.height = 3;
    for (float v : {3.0f, 6.0f, 12.0f}) three.texels.push_back(glm::vec4(v));
    buildMipChain(three);
    expectVecNear(three.mips[0].texels[0], glm::vec4(7.0f), 1e-6f);
}

TEST(TextureFootprint, IsotropicFootprintsPickTheLevelOfTheirSize) {
    // 64 × 32 texels, 7 levels; the footprint in level-0 texels decides.
    const glm::vec2 texel(1.0f / 64.0f, 1.0f / 32.0f);
    for (float side : {1.0f, 2.0f, 3.0f, 4.0f, 16.0f, 64.0f, 1000.0f}) {
        const TextureFootprint f =
            textureFootprint({side * texel.x, 0.0f}, {0.0f, side * texel.y}, 64, 32, 7);
        EXPECT_EQ(f.taps, 1) << side;
        EXPECT_NEAR(f.lod, std::min(std::log2(side), 6.0f), 1e-5f) << side;
    }
    // Under a texel: level 0 (magnified, bilinear).
    const TextureFootprint small =
        textureFootprint({0.3f * texel.x, 0.0f}, {0.0f, 0.2f * texel.y}, 64, 32, 7);
    EXPECT_EQ(small.taps, 1);
    EXPECT_EQ(small.lod, 0.0f);
}

TEST(TextureFootprint, LongFootprintsTakeTapsAlongTheirMajorSide) {
    const float texel = 1.0f / 256.0f;
    struct Case {
        glm::vec2 dx, dy;  // in texels
        int taps;
        float lod;
        bool majorIsX;
    };
    const Case cases[] = {
        {{8, 0}, {0, 1}, 8, 0.0f, true},          // 8:1, one texel per tap
        {{0, 2}, {24, 0}, 12, 1.0f, false},       // 12:1 of two-texel taps, major y
        {{64, 0}, {0, 1}, 16, 2.0f, true},        // 64:1 capped at 16 taps of 4 texels
        {{6, 8}, {-0.8f, 0.6f}, 10, 0.0f, true},  // rotated: |dx| 10, |dy| 1
        {{5, 0}, {0, 0}, 5, 0.0f, true},          // a line: ⌈major⌉ taps
        {{3, 0}, {0, 0.01f}, 3, 0.0f, true},      // never more taps than texels
        {{0.9f, 0}, {0, 0.01f}, 1, 0.0f, true},   // under a texel: one bilinear tap
    };
    for (const Case& c : cases) {
        const TextureFootprint f = textureFootprint(c.dx * texel, c.dy * texel, 256, 256, 9);
        EXPECT_EQ(f.taps, c.taps) << c.dx.x << "," << c.dx.y;
        EXPECT_NEAR(f.lod, c.lod, 1e-5f) << c.dx.x << "," << c.dx.y;
        if (f.taps > 1) {
            const glm::vec2 axis = c.majorIsX ? c.dx * texel : c.dy * texel;
            EXPECT_EQ(f.axis, axis);
        }
    }
}

TEST(TextureFootprint, NonFiniteFootprintsReadTheLastLevel) {
    const float inf = std::numeric_limits<float>::infinity();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (const auto& [dx, dy] : {std::pair{glm::vec2(inf, 0.0f), glm::vec2(0.0f, 1.0f)},
                                 std::pair{glm::vec2(0.1f, 0.0f), glm::vec2(nan, 0.0f)}}) {
        const TextureFootprint f = textureFootprint(dx, dy, 32, 32, 6);
        EXPECT_EQ(f.lod, 5.0f);
        EXPECT_EQ(f.taps, 1);
    }
    Texture t = randomTexture(8, 8, 5);
    buildMipChain(t);
    expectVecNear(t.sampleFootprint({0.3f, 0.6f}, {inf, 0.0f}, {0.0f, 0.0f}),
                  t.mips.back().texels[0], 0.0f);
}

TEST(TextureSampling, TrilinearBlendsNeighbouringLevels) {
    Texture t = randomTexture(16, 16, 9);
    buildMipChain(t);
    const glm::vec2 uv(0.37f, 0.81f);
    expectVecNear(t.sampleTrilinear(uv, 0.0f), t.sample(uv), 0.0f);
    expectVecNear(t.sampleTrilinear(uv, -3.0f), t.sample(uv), 0.0f);
    expectVecNear(t.sampleTrilinear(uv, 2.0f), t.sampleLevel(uv, 2), 0.0f);
    expectVecNear(t.sampleTrilinear(uv, 1.25f),
                  0.75f * t.sampleLevel(uv, 1) + 0.25f * t.sampleLevel(uv, 2), 1e-6f);
    expectVecNear(t.sampleTrilinear(uv, 9.0f), t.mips.back().texels[0], 0.0f);
    // A magnified footprint reads what the point lookup reads.
    expectVecNear(t.sampleFootprint(uv, {0.01f, 0.0f}, {0.0f, 0.02f}), t.sample(uv), 0.0f);
    // Without a chain every lookup is level 0.
    Texture bare = randomTexture(16, 16, 9);
    expectVecNear(bare.sampleTrilinear(uv, 3.0f), bare.sample(uv), 0.0f);
}

TEST(TextureSampling, WrapModesHoldAtEveryLevel) {
    // 8 × 8 whose level 1 (4 × 4) has distinct texels; a lookup past u = 1 wraps or clamps.
    Texture t = randomTexture(8, 8, 11);
    t.repeatS = true;
    t.repeatT = false;
    buildMipChain(t);
    const glm::vec2 inside(0.2f, 0.3f);
    expectVecNear(t.sampleLevel(inside + glm::vec2(1.0f, 0.0f), 1), t.sampleLevel(inside, 1),
                  1e-6f);
    // Clamped along v: anything below v = 0 reads the first row's edge.
    expectVecNear(t.sampleLevel({0.2f, -0.7f}, 1), t.sampleLevel({0.2f, 0.0f}, 1), 1e-6f);
}

/// A floor y = 0 (one big triangle, double-sided) carrying a 2 × 2-texel checkerboard of 0
/// and 1 that repeats every 0.25 m, and a camera 0.4 m above it looking at the horizon.
struct TiltedChecker {
    Scene scene;
    Camera camera;

    TiltedChecker() {
        Texture checker;
        checker.name = "checker";
        checker.width = checker.height = 2;
        checker.texels = {glm::vec4(0, 0, 0, 1), glm::vec4(1, 1, 1, 1), glm::vec4(1, 1, 1, 1),
                          glm::vec4(0, 0, 0, 1)};
        buildMipChain(checker);
        scene.textures.push_back(std::move(checker));
        scene.materials.push_back(Material{.name = "floor", .baseColorTexture = 0});
        for (const glm::vec3 p :
             {glm::vec3(-200, 0, 20), glm::vec3(200, 0, 20), glm::vec3(0, 0, -400)}) {
            Vertex v;
            v.position = p;
            v.normal = {0, 1, 0};
            v.uv0 = glm::vec2(p.x, p.z) * 4.0f;
            scene.vertices.push_back(v);
        }
        scene.triangles.push_back(Triangle{{0, 2, 1}, 0, 0});
        camera.eye = {0.05f, 0.4f, 0.0f};
        camera.target = {0.0f, 0.25f, -2.0f};
        camera.fovyDegrees = 40.0f;
    }

    /// Barycentrics (b1, b2) of the floor point p.
    std::pair<float, float> barycentrics(const glm::vec3& p) const {
        const glm::vec3 a = scene.vertices[0].position, b = scene.vertices[2].position,
                        c = scene.vertices[1].position;
        const glm::vec2 e1(b.x - a.x, b.z - a.z), e2(c.x - a.x, c.z - a.z), d(p.x - a.x, p.z - a.z);
        const float det = e1.x * e2.y - e1.y * e2.x;
        return {(d.x * e2.y - d.y * e2.x) / det, (e1.x * d.y - e1.y * d.x) / det};
    }

    /// Where the ray through image point (x, y) meets the floor, if ahead.
    std::optional<glm::vec3> floorHit(const CameraRays& rays, float x, float y) const {
        const glm::vec3 d = rays.direction(x, y);
        if (!(d.y < 0.0f)) return std::nullopt;
        return rays.origin() + (-rays.origin().y / d.y) * d;
    }
};

TEST(TextureFiltering, TiltedCheckerMatchesThePixelFootprintAverage) {
    // Per pixel: the filtered albedo at the centre's hit, the point (level-0) albedo there, and
    // the reference, the mean of point albedos over 32 × 32 points of the pixel.
    const TiltedChecker t;
    constexpr uint32_t kWidth = 48, kHeight = 64;
    const CameraRays rays(t.camera, kWidth, kHeight);
    double filteredSquared = 0.0, pointSquared = 0.0;
    int pixels = 0, grazing = 0;
    for (uint32_t y = 0; y < kHeight; ++y)
        for (uint32_t x = 0; x < kWidth; ++x) {
            const auto centre = t.floorHit(rays, float(x) + 0.5f, float(y) + 0.5f);
            if (!centre) continue;
            constexpr int kSub = 32;
            double reference = 0.0;
            int inside = 0;
            for (int sy = 0; sy < kSub; ++sy)
                for (int sx = 0; sx < kSub; ++sx) {
                    const auto p = t.floorHit(rays, float(x) + (float(sx) + 0.5f) / kSub,
                                              float(y) + (float(sy) + 0.5f) / kSub);
                    if (!p) continue;
                    const auto [b1, b2] = t.barycentrics(*p);
                    reference += t.scene.albedoAt(0, b1, b2).x;
                    ++inside;
                }
            if (inside < kSub * kSub) continue;  // the horizon cuts this pixel
            reference /= inside;
            const auto [b1, b2] = t.barycentrics(*centre);
            const PixelFootprint footprint = rays.footprintOnPlane(*centre, glm::vec3(0, 1, 0));
            const float filtered =
                t.scene.albedoOverFootprint(0, b1, b2, footprint.dPdx, footprint.dPdy).x;
            const float point = t.scene.albedoAt(0, b1, b2).x;
            filteredSquared += (filtered - reference) * (filtered - reference);
            pointSquared += (point - reference) * (point - reference);
            ++pixels;
            // Where a pixel spans ≥ 8 checker periods along its long side (near the horizon)
            // the footprint average is the checker's mean, ½, and so is the filtered value.
            if (glm::length(footprint.dPdy) > 8.0f * 0.25f) {
                EXPECT_NEAR(filtered, 0.5f, 0.02f) << "pixel " << x << "," << y;
                ++grazing;
            }
        }
    ASSERT_GT(pixels, 1500);
    EXPECT_GT(grazing, 100);
    const double filteredRmse = std::sqrt(filteredSquared / pixels);
    const double pointRmse = std::sqrt(pointSquared / pixels);
    std::printf(
        "tilted checker, %d pixels: RMSE against the footprint average %.4f filtered, "
        "%.4f point-sampled\n",
        pixels, filteredRmse, pointRmse);
    EXPECT_LT(filteredRmse, 0.1);
    EXPECT_LT(filteredRmse, 0.4 * pointRmse);
}

TEST(PixelFootprint, MatchesFiniteDifferencesOfTheCameraRays) {
    // The analytic derivative against central differences of where neighbouring rays meet a
    // tilted plane.
    Camera camera;
    camera.eye = {0.3f, 1.2f, 2.5f};
    camera.target = {-0.1f, 0.4f, 0.0f};
    camera.fovyDegrees = 55.0f;
    const CameraRays rays(camera, 80, 60);
    const glm::vec3 normal = glm::normalize(glm::vec3(0.2f, 1.0f, 0.4f));
    const glm::vec3 onPlane(0.0f, 0.1f, 0.0f);
    const auto hit = [&](float x, float y) {
        const glm::vec3 d = rays.direction(x, y);
        return rays.origin() + glm::dot(onPlane - rays.origin(), normal) / glm::dot(d, normal) * d;
    };
    for (const glm::vec2 pixel : {glm::vec2(10.5f, 40.5f), glm::vec2(70.5f, 55.5f)}) {
        const PixelFootprint f = rays.footprintOnPlane(hit(pixel.x, pixel.y), normal);
        const float h = 0.01f;
        const glm::vec3 dx = (hit(pixel.x + h, pixel.y) - hit(pixel.x - h, pixel.y)) / (2 * h);
        const glm::vec3 dy = (hit(pixel.x, pixel.y + h) - hit(pixel.x, pixel.y - h)) / (2 * h);
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(f.dPdx[c], dx[c], 1e-3f * glm::length(dx));
            EXPECT_NEAR(f.dPdy[c], dy[c], 1e-3f * glm::length(dy));
        }
    }
}

}  // namespace
}  // namespace pic
