#include <cmath>
#include <cstring>
#include <numbers>
#include <random>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "bake/lightmap_caches.h"
#include "bake/lightmap_charts.h"
#include "core/parallel.h"
#include "rays/embree_scene.h"

namespace pic {
namespace {

/// Builds flat-shaded scenes by hand (every triangle owns its three vertices, as glTF
/// exports of flat-shaded meshes do).
class SceneBuilder {
public:
    SceneBuilder() {
        Material white;
        white.name = "white";
        white.baseColorFactor = glm::vec4(0.8f, 0.8f, 0.8f, 1.0f);
        mScene.materials.push_back(white);
    }

    /// Starts a new primitive; following triangles belong to it.
    void primitive(const std::string& name, bool hasUv1 = false) {
        Primitive p;
        p.name = name;
        p.firstTriangle = static_cast<uint32_t>(mScene.triangles.size());
        p.hasUv1 = hasUv1;
        mScene.primitives.push_back(p);
    }

    void triangle(glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec2 uvA = {}, glm::vec2 uvB = {},
                  glm::vec2 uvC = {}) {
        if (mScene.primitives.empty()) primitive("mesh/0");
        glm::vec3 n = glm::normalize(glm::cross(b - a, c - a));
        Triangle tri;
        const glm::vec3 p[3] = {a, b, c};
        const glm::vec2 uv[3] = {uvA, uvB, uvC};
        for (int k = 0; k < 3; ++k) {
            Vertex v;
            v.position = p[k];
            v.normal = n;
            v.uv1 = uv[k];
            tri.v[k] = static_cast<uint32_t>(mScene.vertices.size());
            mScene.vertices.push_back(v);
        }
        tri.primitive = static_cast<uint32_t>(mScene.primitives.size() - 1);
        mScene.triangles.push_back(tri);
        ++mScene.primitives.back().triangleCount;
    }

    /// Parallelogram o, o+u, o+u+v, o+v facing u × v.
    void quad(glm::vec3 o, glm::vec3 u, glm::vec3 v) {
        triangle(o, o + u, o + u + v);
        triangle(o, o + u + v, o + v);
    }

    /// Closed axis-aligned box with outward faces.
    void box(glm::vec3 lo, glm::vec3 hi) {
        glm::vec3 d = hi - lo;
        glm::vec3 x(d.x, 0, 0), y(0, d.y, 0), z(0, 0, d.z);
        quad(lo, x, z);                           // -Y
        quad(glm::vec3(lo.x, hi.y, lo.z), z, x);  // +Y
        quad(lo, z, y);                           // -X
        quad(glm::vec3(hi.x, lo.y, lo.z), y, z);  // +X
        quad(lo, y, x);                           // -Z
        quad(glm::vec3(lo.x, lo.y, hi.z), x, y);  // +Z
    }

    /// Floor at height y facing up over [x0, x1] × [z0, z1].
    void floor(float x0, float z0, float x1, float z1, float y = 0.0f) {
        quad(glm::vec3(x0, y, z0), glm::vec3(0, 0, z1 - z0), glm::vec3(x1 - x0, 0, 0));
    }

    /// Flat-shaded UV sphere with outward faces.
    void sphere(glm::vec3 centre, float radius, int slices, int stacks) {
        auto at = [&](int i, int j) {
            double theta = std::numbers::pi * j / stacks;
            double phi = 2.0 * std::numbers::pi * i / slices;
            return centre + radius * glm::vec3(std::sin(theta) * std::cos(phi), std::cos(theta),
                                               std::sin(theta) * std::sin(phi));
        };
        for (int j = 0; j < stacks; ++j)
            for (int i = 0; i < slices; ++i) {
                glm::vec3 a = at(i, j), b = at(i + 1, j), c = at(i + 1, j + 1), d = at(i, j + 1);
                if (j > 0) triangle(a, b, d);
                if (j < stacks - 1) triangle(b, c, d);
            }
    }

    Scene finish() {
        Scene scene = mScene;
        for (const Vertex& v : scene.vertices) scene.bounds.extend(v.position);
        for (uint32_t t = 0; t < scene.triangles.size(); ++t) {
            const Triangle& tri = scene.triangles[t];
            glm::vec3 p0 = scene.vertices[tri.v[0]].position;
            scene.totalArea +=
                0.5 * glm::length(glm::cross(scene.vertices[tri.v[1]].position - p0,
                                             scene.vertices[tri.v[2]].position - p0));
        }
        return scene;
    }

private:
    Scene mScene;
};

float triangleArea(const Scene& scene, uint32_t t) {
    const Triangle& tri = scene.triangles[t];
    glm::vec3 p0 = scene.vertices[tri.v[0]].position;
    return 0.5f * glm::length(glm::cross(scene.vertices[tri.v[1]].position - p0,
                                         scene.vertices[tri.v[2]].position - p0));
}

LightmapCharts charts(const Scene& scene, float texel,
                      uint32_t padding = LightmapChartParams{}.padding) {
    LightmapChartParams params;
    params.texelSize = texel;
    params.padding = padding;
    auto result = buildLightmapCharts(scene, params);
    EXPECT_TRUE(result.has_value()) << result.error().message;
    return result ? *result : LightmapCharts{};
}

struct Baked {
    std::unique_ptr<EmbreeScene> rays;
    LightmapCacheSet set;
};

Baked bake(const Scene& scene, float texel, uint32_t firstCacheIndex = 0,
           uint32_t padding = LightmapChartParams{}.padding) {
    Baked baked;
    auto rays = EmbreeScene::create(scene);
    EXPECT_TRUE(rays.has_value()) << rays.error().message;
    baked.rays = std::move(*rays);
    auto set = placeLightmapCaches(scene, *baked.rays, charts(scene, texel, padding),
                                   firstCacheIndex, LightmapCacheParams{texel});
    EXPECT_TRUE(set.has_value()) << set.error().message;
    if (set) baked.set = std::move(*set);
    return baked;
}

/// Number of bilinear lookups, at random points (corners and edges included) of the given
/// triangles, that read a texel outside the atlas or without a cache.
int emptyBilinearReads(const LightmapLayout& layout, const std::vector<uint32_t>& triangles,
                       int perTriangle) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    int empty = 0;
    for (uint32_t t : triangles) {
        for (int s = 0; s < perTriangle; ++s) {
            float b1 = unit(rng), b2 = unit(rng);
            if (s < 3) b1 = s == 1 ? 1.0f : 0.0f, b2 = s == 2 ? 1.0f : 0.0f;
            if (s >= 3 && s < 6) b2 = 0.0f;
            if (b1 + b2 > 1.0f) b1 = 1.0f - b1, b2 = 1.0f - b2;
            glm::vec2 uv = layout.triangleUvs[3 * t] * (1.0f - b1 - b2) +
                           layout.triangleUvs[3 * t + 1] * b1 + layout.triangleUvs[3 * t + 2] * b2;
            glm::vec2 texel = uv * glm::vec2(layout.width, layout.height) - 0.5f;
            int x0 = int(std::floor(texel.x)), y0 = int(std::floor(texel.y));
            bool filled = true;
            for (int dy = 0; dy < 2; ++dy)
                for (int dx = 0; dx < 2; ++dx) {
                    int x = x0 + dx, y = y0 + dy;
                    filled = filled && x >= 0 && y >= 0 && x < int(layout.width) &&
                             y < int(layout.height) &&
                             layout.cacheIndex[size_t(x) + size_t(y) * layout.width] != kNoCache;
                }
            empty += !filled;
        }
    }
    return empty;
}

std::vector<uint32_t> allTriangles(const Scene& scene) {
    std::vector<uint32_t> all(scene.triangles.size());
    for (uint32_t t = 0; t < all.size(); ++t) all[t] = t;
    return all;
}

TEST(LightmapCaches, UnitQuadHasOneCachePerTexel) {
    SceneBuilder builder;
    builder.floor(0.0f, 0.0f, 1.0f, 1.0f);
    Scene scene = builder.finish();
    Baked baked = bake(scene, 0.1f, 1000);
    const LightmapCacheSet& set = baked.set;

    // A 1 m quad at 0.1 m per texel has exactly 10 × 10 texel centres.
    ASSERT_EQ(set.caches.size(), 100u);
    EXPECT_EQ(set.relocated, 0u);
    EXPECT_EQ(set.rejected, 0u);
    EXPECT_GT(set.duplicateTexels, 0u);
    std::set<std::pair<int, int>> cells;
    for (size_t i = 0; i < set.caches.size(); ++i) {
        const Cache& cache = set.caches[i];
        EXPECT_EQ(cache.kind, gpu::kCacheKindLightmap);
        EXPECT_NEAR(cache.normal.y, 1.0f, 1e-6f);
        EXPECT_GT(cache.position.y, 0.0f);
        EXPECT_LT(cache.position.y, 1e-4f);
        EXPECT_GT(cache.position.x, 0.0f);
        EXPECT_LT(cache.position.x, 1.0f);
        EXPECT_GT(cache.position.z, 0.0f);
        EXPECT_LT(cache.position.z, 1.0f);
        // Texel centres sit in the middle of 0.1 m cells.
        float fx = cache.position.x * 10.0f - 0.5f, fz = cache.position.z * 10.0f - 0.5f;
        EXPECT_NEAR(fx, std::round(fx), 1e-3f);
        EXPECT_NEAR(fz, std::round(fz), 1e-3f);
        cells.insert({int(std::round(fx)), int(std::round(fz))});
        // The cache's own texel points at it.
        EXPECT_EQ(set.layout.cacheIndex[cache.texel], 1000u + i);
    }
    EXPECT_EQ(cells.size(), 100u);
    EXPECT_EQ(emptyBilinearReads(set.layout, allTriangles(scene), 2000), 0);
}

TEST(LightmapCaches, DilationFillsPaddingRingsAroundCharts) {
    SceneBuilder builder;
    builder.floor(0.0f, 0.0f, 1.0f, 1.0f);
    Scene scene = builder.finish();
    for (uint32_t padding : {1u, 2u, 3u}) {
        Baked baked = bake(scene, 0.1f, 0, padding);
        const LightmapLayout& layout = baked.set.layout;
        size_t filled = 0;
        for (uint32_t y = 0; y < layout.height; ++y)
            for (uint32_t x = 0; x < layout.width; ++x) {
                uint32_t index = layout.cacheIndex[x + y * layout.width];
                if (index == kNoCache) continue;
                ++filled;
                // A duplicate points at a cache at most `padding` texels away.
                const Cache& cache = baked.set.caches[index];
                int cx = int(cache.texel % layout.width), cy = int(cache.texel / layout.width);
                EXPECT_LE(std::max(std::abs(cx - int(x)), std::abs(cy - int(y))), int(padding));
            }
        // 10 × 10 texels plus `padding` rings around them.
        size_t side = 10 + 2 * padding;
        EXPECT_EQ(filled, side * side) << "padding " << padding;
        EXPECT_EQ(baked.set.duplicateTexels, side * side - 100u) << "padding " << padding;
        EXPECT_EQ(emptyBilinearReads(layout, allTriangles(scene), 1000), 0);
    }
}

TEST(LightmapCaches, NoCacheInsideBoxStandingOnFloor) {
    SceneBuilder builder;
    builder.primitive("floor");
    builder.floor(-2.0f, -2.0f, 2.0f, 2.0f);
    builder.primitive("box");
    builder.box(glm::vec3(-0.5f, 0.0f, -0.5f), glm::vec3(0.5f, 1.0f, 0.5f));
    Scene scene = builder.finish();
    Baked baked = bake(scene, 0.1f);
    const LightmapCacheSet& set = baked.set;

    auto insideBox = [](const glm::vec3& p) {
        return std::abs(p.x) < 0.5f && std::abs(p.z) < 0.5f && p.y > 0.0f && p.y < 1.0f;
    };
    for (const Cache& cache : set.caches)
        EXPECT_FALSE(insideBox(cache.position)) << "cache at " << cache.position.x << ", "
                                                << cache.position.y << ", " << cache.position.z;
    // The floor texel centres under the box (10 × 10) were all found enclosed.
    EXPECT_EQ(set.rejected, 100u);
    // Floor texels under the box are dilated from caches outside it.
    EXPECT_EQ(emptyBilinearReads(set.layout, {0, 1}, 3000), 0);
    size_t floorCaches = 0;
    for (const Cache& cache : set.caches)
        floorCaches += cache.normal.y > 0.99f && cache.position.y < 0.01f;
    EXPECT_EQ(floorCaches, 40u * 40u - 100u);
}

TEST(LightmapCaches, SunkenBoxRejectsCachesBelowTheFloor) {
    // A box sunk half into a floor slab: its sides below the floor and the floor inside it
    // are behind geometry.
    SceneBuilder builder;
    builder.primitive("floor");
    builder.box(glm::vec3(-2.0f, -0.2f, -2.0f), glm::vec3(2.0f, 0.0f, 2.0f));
    builder.primitive("box");
    builder.box(glm::vec3(-0.5f, -0.5f, -0.5f), glm::vec3(0.5f, 0.5f, 0.5f));
    Scene scene = builder.finish();
    Baked baked = bake(scene, 0.1f);
    for (const Cache& cache : baked.set.caches) {
        const glm::vec3& p = cache.position;
        bool inSlab = p.y < 0.0f && p.y > -0.2f && std::abs(p.x) < 2.0f && std::abs(p.z) < 2.0f;
        bool inBox = std::abs(p.x) < 0.5f && std::abs(p.y) < 0.5f && std::abs(p.z) < 0.5f;
        EXPECT_FALSE(inSlab || inBox) << p.x << ", " << p.y << ", " << p.z;
    }
    EXPECT_GT(baked.set.rejected, 0u);
}

TEST(LightmapCaches, IsolatedTinyTriangleIsShadedFromTheGrid) {
    // A chart that holds no texel centre would cost a cache per triangle on detailed meshes:
    // it is left to the grid instead.
    SceneBuilder builder;
    glm::vec3 a(0.31f, 0.0f, 0.52f), b(0.33f, 0.0f, 0.52f), c(0.32f, 0.0f, 0.54f);
    builder.triangle(a, c, b);
    Scene scene = builder.finish();
    Baked baked = bake(scene, 0.1f);
    EXPECT_EQ(baked.set.caches.size(), 0u);
    EXPECT_EQ(baked.set.gridShadedTriangles, 1u);
    for (const glm::vec2& uv : baked.set.layout.triangleUvs) EXPECT_EQ(uv, glm::vec2(kNotLightmapped));
}

TEST(LightmapCaches, SliverTriangleLookupsAreFilled) {
    // A 2 m long, 1 cm wide sliver sharing an edge with a quad covers few or no texel
    // centres at 0.1 m; it joins the quad's chart and its lookups must all be filled.
    SceneBuilder builder;
    builder.floor(0.0f, 0.0f, 1.0f, 2.0f);
    builder.triangle(glm::vec3(0.0f, 0.0f, 0.0f), glm::vec3(-0.011f, 0.0f, 0.0f),
                     glm::vec3(0.0f, 0.0f, 2.0f));
    Scene scene = builder.finish();
    Baked baked = bake(scene, 0.1f);
    EXPECT_EQ(baked.set.gridShadedTriangles, 0u);
    EXPECT_EQ(emptyBilinearReads(baked.set.layout, {2}, 3000), 0);
}

/// A scene of many charts: a room of boxes, a sphere and scattered triangles.
Scene clutteredScene() {
    SceneBuilder builder;
    builder.primitive("room");
    builder.floor(-3.0f, -3.0f, 3.0f, 3.0f);
    builder.box(glm::vec3(-1.0f, 0.0f, -1.0f), glm::vec3(-0.2f, 0.7f, 0.3f));
    builder.box(glm::vec3(1.0f, 0.0f, 1.0f), glm::vec3(1.3f, 2.0f, 1.2f));
    builder.primitive("ball");
    builder.sphere(glm::vec3(0.5f, 0.5f, -1.5f), 0.4f, 24, 12);
    builder.primitive("debris");
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> pos(-2.5f, 2.5f), size(0.005f, 0.3f);
    for (int i = 0; i < 60; ++i) {
        glm::vec3 o(pos(rng), 2.5f + 0.08f * pos(rng), pos(rng));
        builder.triangle(o, o + glm::vec3(size(rng), size(rng), 0.0f),
                         o + glm::vec3(0.0f, size(rng), size(rng)));
    }
    return builder.finish();
}

TEST(LightmapCharts, ChartsStayInsideTheAtlasAndApart) {
    Scene scene = clutteredScene();
    LightmapCharts result = charts(scene, 0.05f);
    ASSERT_EQ(result.triangleUvs.size(), 3 * scene.triangles.size());
    EXPECT_EQ(result.uv1Primitives, 0u);
    EXPECT_EQ(result.chartCount, result.charts.size());

    // Rectangles lie inside the atlas and do not overlap.
    std::vector<uint32_t> owner(size_t{result.width} * result.height, kNoCache);
    for (uint32_t c = 0; c < result.charts.size(); ++c) {
        const LightmapChart& chart = result.charts[c];
        ASSERT_LE(chart.x + chart.width, result.width);
        ASSERT_LE(chart.y + chart.height, result.height);
        for (uint32_t y = chart.y; y < chart.y + chart.height; ++y)
            for (uint32_t x = chart.x; x < chart.x + chart.width; ++x) {
                ASSERT_EQ(owner[x + y * result.width], kNoCache)
                    << "charts overlap at " << x << ", " << y;
                owner[x + y * result.width] = c;
            }
    }

    // Every texel a bilinear lookup on a triangle can read (centre within one texel of the
    // triangle, tested on a dense sample of its points) belongs to the triangle's chart, and
    // planar charts keep the texel size: UV area × atlas texels × texel² = world area. Sphere
    // facets may share a chart with neighbours up to 10° from its seed, which shrinks their
    // projection by at most cos 20°.
    const Primitive& ball = scene.primitives[1];
    glm::vec2 atlas(result.width, result.height);
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    for (uint32_t t = 0; t < scene.triangles.size(); ++t) {
        glm::vec2 p[3];
        for (int k = 0; k < 3; ++k) {
            glm::vec2 uv = result.triangleUvs[3 * t + k];
            ASSERT_TRUE(uv.x >= 0.0f && uv.x <= 1.0f && uv.y >= 0.0f && uv.y <= 1.0f);
            p[k] = uv * atlas;
        }
        for (int s = 0; s < 200; ++s) {
            float b1 = unit(rng), b2 = unit(rng);
            if (b1 + b2 > 1.0f) b1 = 1.0f - b1, b2 = 1.0f - b2;
            glm::vec2 q = p[0] * (1.0f - b1 - b2) + p[1] * b1 + p[2] * b2 - 0.5f;
            for (int dy = 0; dy < 2; ++dy)
                for (int dx = 0; dx < 2; ++dx) {
                    size_t texel =
                        size_t(std::floor(q.x) + dx) + size_t(std::floor(q.y) + dy) * result.width;
                    ASSERT_EQ(owner[texel], result.triangleChart[t]) << "triangle " << t;
                }
        }
        glm::vec2 e1 = p[1] - p[0], e2 = p[2] - p[0];
        float texelArea = 0.5f * std::abs(e1.x * e2.y - e1.y * e2.x) * 0.05f * 0.05f;
        float area = triangleArea(scene, t);
        if (t >= ball.firstTriangle && t < ball.firstTriangle + ball.triangleCount) {
            EXPECT_LE(texelArea, area * 1.001f) << "triangle " << t;
            EXPECT_GE(texelArea, area * std::cos(glm::radians(20.0f))) << "triangle " << t;
        } else {
            EXPECT_NEAR(texelArea, area, 1e-3f * area + 1e-7f) << "triangle " << t;
        }
    }
}

TEST(LightmapCharts, ChartsGrowOverNearlyCoplanarSameFacingNeighbours) {
    // A strip of 1 m quads hinged along z; each quad rises at its own angle.
    SceneBuilder builder;
    const float degrees[5] = {0.0f, 0.0f, 5.0f, 12.0f, 12.0f};
    glm::vec3 o(0.0f);
    for (float angle : degrees) {
        glm::vec3 u(std::cos(glm::radians(angle)), std::sin(glm::radians(angle)), 0.0f);
        builder.quad(o, glm::vec3(0, 0, 1), u);
        o += u;
    }
    // The same plane as the last quad, extended but facing the other way.
    glm::vec3 u(std::cos(glm::radians(12.0f)), std::sin(glm::radians(12.0f)), 0.0f);
    builder.quad(o, u, glm::vec3(0, 0, 1));
    Scene scene = builder.finish();
    LightmapCharts result = charts(scene, 0.1f);
    // Quads 0-2 lie within 10° of the seed's normal; quad 3 starts a chart that quad 4
    // joins; the flipped quad is its own chart.
    ASSERT_EQ(result.chartCount, 3u);
    for (uint32_t t = 1; t < 6; ++t) EXPECT_EQ(result.triangleChart[t], result.triangleChart[0]);
    for (uint32_t t = 7; t < 10; ++t) EXPECT_EQ(result.triangleChart[t], result.triangleChart[6]);
    EXPECT_NE(result.triangleChart[6], result.triangleChart[0]);
    EXPECT_NE(result.triangleChart[10], result.triangleChart[6]);
    EXPECT_EQ(result.triangleChart[11], result.triangleChart[10]);
}

TEST(LightmapCharts, Uv1PrimitiveKeepsItsLayout) {
    SceneBuilder builder;
    builder.primitive("generated");
    builder.floor(0.0f, 0.0f, 1.0f, 1.0f);
    builder.primitive("unwrapped", true);
    // A 2 m × 1 m wall unwrapped into the lower half of UV space, and a second island.
    glm::vec3 o(0.0f, 0.0f, 3.0f);
    builder.triangle(o, o + glm::vec3(2, 0, 0), o + glm::vec3(2, 1, 0), {0.0f, 0.0f}, {0.5f, 0.0f},
                     {0.5f, 0.25f});
    builder.triangle(o, o + glm::vec3(2, 1, 0), o + glm::vec3(0, 1, 0), {0.0f, 0.0f}, {0.5f, 0.25f},
                     {0.0f, 0.25f});
    builder.triangle(o + glm::vec3(0, 2, 0), o + glm::vec3(2, 2, 0), o + glm::vec3(2, 3, 0),
                     {0.6f, 0.7f}, {1.1f, 0.7f}, {1.1f, 0.95f});
    Scene scene = builder.finish();
    const float texel = 0.05f;
    LightmapCharts result = charts(scene, texel);
    EXPECT_EQ(result.uv1Primitives, 1u);
    EXPECT_EQ(result.chartCount, 1u);
    ASSERT_EQ(result.charts.size(), 2u);
    EXPECT_TRUE(result.charts[result.triangleChart[2]].fromUv1);
    EXPECT_EQ(result.triangleChart[2], result.triangleChart[4]);

    // Atlas texel = offset + scale · uv1 with one scale for both axes; the scale gives
    // the requested texel size: world area 2 + 1 m², UV area 0.125 + 0.0625.
    glm::vec2 atlas(result.width, result.height);
    float expectedScale = std::sqrt(3.0f / 0.1875f) / texel;
    glm::vec2 offset =
        result.triangleUvs[6] * atlas - scene.vertices[scene.triangles[2].v[0]].uv1 * expectedScale;
    for (uint32_t t = 2; t < 5; ++t)
        for (int k = 0; k < 3; ++k) {
            glm::vec2 uv1 = scene.vertices[scene.triangles[t].v[k]].uv1;
            glm::vec2 texelPos = result.triangleUvs[3 * t + k] * atlas;
            EXPECT_NEAR(texelPos.x, offset.x + uv1.x * expectedScale, 1e-2f);
            EXPECT_NEAR(texelPos.y, offset.y + uv1.y * expectedScale, 1e-2f);
        }
}

TEST(LightmapCharts, DegenerateUv1FallsBackToGeneratedCharts) {
    SceneBuilder builder;
    builder.primitive("no-unwrap", true);
    builder.floor(0.0f, 0.0f, 1.0f, 1.0f);  // all TEXCOORD_1 are (0, 0)
    Scene scene = builder.finish();
    LightmapCharts result = charts(scene, 0.1f);
    EXPECT_EQ(result.uv1Primitives, 0u);
    EXPECT_EQ(result.chartCount, 1u);
}

TEST(LightmapCaches, ResultIsDeterministic) {
    Scene scene = clutteredScene();
    Baked first = bake(scene, 0.04f);
    setWorkerCount(1);
    Baked second = bake(scene, 0.04f);
    setWorkerCount(0);
    ASSERT_EQ(first.set.caches.size(), second.set.caches.size());
    EXPECT_EQ(std::memcmp(first.set.caches.data(), second.set.caches.data(),
                          first.set.caches.size() * sizeof(Cache)),
              0);
    EXPECT_EQ(first.set.layout.cacheIndex, second.set.layout.cacheIndex);
    ASSERT_EQ(first.set.layout.triangleUvs.size(), second.set.layout.triangleUvs.size());
    EXPECT_EQ(std::memcmp(first.set.layout.triangleUvs.data(), second.set.layout.triangleUvs.data(),
                          first.set.layout.triangleUvs.size() * sizeof(glm::vec2)),
              0);
    EXPECT_EQ(first.set.duplicateTexels, second.set.duplicateTexels);
    EXPECT_EQ(first.set.rejected, second.set.rejected);
    // Every triangle's lookups are filled in this scene too (no chart is fully enclosed).
    EXPECT_EQ(emptyBilinearReads(first.set.layout, allTriangles(scene), 200), 0);
}

/// The texel size an atlas error suggests ("… use a texel size of X m or more").
float suggestedTexelSize(const std::string& message) {
    const std::string key = "use a texel size of ";
    size_t at = message.find(key);
    return at == std::string::npos ? 0.0f : std::stof(message.substr(at + key.size()));
}

TEST(LightmapCharts, TooSmallTexelSizeIsAClearError) {
    SceneBuilder builder;
    builder.floor(0.0f, 0.0f, 10.0f, 10.0f);
    Scene scene = builder.finish();
    LightmapChartParams params;
    params.texelSize = 1e-4f;
    auto result = buildLightmapCharts(scene, params);
    ASSERT_FALSE(result.has_value());
    EXPECT_EQ(result.error().code, ErrorCode::InvalidInput);
    EXPECT_NE(result.error().message.find("0.0001"), std::string::npos) << result.error().message;
    float suggestion = suggestedTexelSize(result.error().message);
    EXPECT_GT(suggestion, 10.0f / 16384.0f) << result.error().message;
    params.texelSize = suggestion;
    EXPECT_TRUE(buildLightmapCharts(scene, params).has_value());
}

TEST(LightmapCharts, AtlasOverflowSuggestsATexelSizeThatFits) {
    // Twenty separate 1 m quads at 0.1 m need 20 rectangles of 14 × 14 texels: too many for
    // a 64 × 64 atlas although their content alone would fit.
    SceneBuilder builder;
    for (int i = 0; i < 20; ++i) builder.floor(2.0f * i, 0.0f, 2.0f * i + 1.0f, 1.0f);
    Scene scene = builder.finish();
    LightmapChartParams params;
    params.texelSize = 0.1f;
    params.padding = 2;
    params.maxAtlasSize = 64;
    auto result = buildLightmapCharts(scene, params);
    ASSERT_FALSE(result.has_value());
    EXPECT_EQ(result.error().code, ErrorCode::InvalidInput);
    EXPECT_NE(result.error().message.find("0.1 m"), std::string::npos) << result.error().message;
    params.texelSize = suggestedTexelSize(result.error().message);
    EXPECT_GT(params.texelSize, 0.1f) << result.error().message;
    auto retried = buildLightmapCharts(scene, params);
    ASSERT_TRUE(retried.has_value()) << retried.error().message;
    EXPECT_LE(retried->width, 64u);
    EXPECT_LE(retried->height, 64u);
}

TEST(LightmapCharts, LargeChartsAreSplitToFitTheAtlas) {
    SceneBuilder builder;
    // A 10 m × 1 m strip of 20 quads at 0.1 m: 100 texels long, more than a 64 atlas.
    for (int i = 0; i < 20; ++i) builder.floor(0.5f * i, 0.0f, 0.5f * (i + 1), 1.0f);
    Scene scene = builder.finish();
    LightmapChartParams params;
    params.texelSize = 0.1f;
    params.maxAtlasSize = 64;
    auto result = buildLightmapCharts(scene, params);
    ASSERT_TRUE(result.has_value()) << result.error().message;
    EXPECT_GE(result->chartCount, 2u);
    for (const LightmapChart& chart : result->charts) {
        EXPECT_LE(chart.width, 64u);
        EXPECT_LE(chart.height, 64u);
    }
}

TEST(LightmapCharts, BadParametersAreErrors) {
    SceneBuilder builder;
    builder.floor(0.0f, 0.0f, 1.0f, 1.0f);
    Scene scene = builder.finish();
    for (float texel : {0.0f, -1.0f, std::nanf(""), INFINITY}) {
        auto result = buildLightmapCharts(scene, LightmapChartParams{texel});
        ASSERT_FALSE(result.has_value()) << texel;
        EXPECT_EQ(result.error().code, ErrorCode::InvalidInput);
        EXPECT_NE(result.error().message.find("texel size"), std::string::npos);
    }
    auto noPadding = buildLightmapCharts(scene, LightmapChartParams{0.1f, 0});
    ASSERT_FALSE(noPadding.has_value());
    EXPECT_NE(noPadding.error().message.find("padding"), std::string::npos);

    auto rays = EmbreeScene::create(scene);
    ASSERT_TRUE(rays.has_value());
    auto mismatch =
        placeLightmapCaches(scene, **rays, charts(scene, 0.1f), 0, LightmapCacheParams{0.2f});
    ASSERT_FALSE(mismatch.has_value());
    EXPECT_EQ(mismatch.error().code, ErrorCode::InvalidInput);
}

}  // namespace
}  // namespace pic

namespace pic {
namespace {

TEST(LightmapCaches, ChartsWithoutCachesLeaveTheRepackedAtlas) {
    // Debris triangles too small for a texel centre are shaded from the grid; the atlas is
    // packed again without them, and every light-mapped lookup still reads filled texels.
    Scene scene = clutteredScene();
    LightmapCharts before = charts(scene, 0.05f);
    Baked baked = bake(scene, 0.05f);
    const LightmapCacheSet& set = baked.set;
    EXPECT_GT(set.gridShadedTriangles, 0u);
    EXPECT_LT(uint64_t{set.layout.width} * set.layout.height, uint64_t{before.width} * before.height);
    std::vector<uint32_t> lightmapped;
    for (uint32_t t = 0; t < scene.triangles.size(); ++t) {
        bool mapped = set.layout.triangleUvs[3 * t] != glm::vec2(kNotLightmapped);
        for (int k = 0; k < 3; ++k)
            EXPECT_EQ(set.layout.triangleUvs[3 * t + k] != glm::vec2(kNotLightmapped), mapped);
        if (mapped) lightmapped.push_back(t);
    }
    EXPECT_EQ(lightmapped.size() + set.gridShadedTriangles, scene.triangles.size());
    EXPECT_EQ(emptyBilinearReads(set.layout, lightmapped, 500), 0);
    for (uint32_t i = 0; i < set.caches.size(); ++i) {
        ASSERT_LT(set.caches[i].texel, set.layout.cacheIndex.size());
        EXPECT_EQ(set.layout.cacheIndex[set.caches[i].texel], i);
    }
}

}  // namespace
}  // namespace pic
