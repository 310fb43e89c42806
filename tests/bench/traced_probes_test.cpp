// The ray-traced probes baseline (bench/traced_probes.h) on a small Cornell bake: against the
// ideal caches of the path tracer (one update = one bounce; converged updates = all bounces),
// its hysteresis, its subsets and its determinism. Bounds were measured with margin; the
// measured value is in the comment beside each.

#include "bench/traced_probes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "bake/ref/probes.h"
#include "core/color.h"
#include "core/light_set.h"
#include "core/parallel.h"
#include "core/shade_params.h"
#include "render/cpu/cache_shading.h"
#include "tests/support/baked_scene.h"

namespace pic {
namespace {

/// The Cornell box baked small (a couple of seconds on two cores); links do not matter here.
/// Without sky transfer, so that every cache sees a surface (a light-map cache that sees only
/// the sky is kept in a bake with sky transfer, and no light set here lights it).
const test::BakedScene& cornell() {
    BakeOptions options = test::smallBakeOptions(2048, 32);
    options.skyRays = 0;
    return test::bakedScene("cornell", options, 0.12f, 0.06f);
}

/// A baseline over the Cornell bake; a test failure and null when it cannot be made.
std::unique_ptr<TracedProbes> makeProbes(const TracedProbeParams& params) {
    const test::BakedScene& b = cornell();
    auto probes = TracedProbes::create(b.scene, *b.rays, b.bake, params);
    EXPECT_TRUE(probes) << (probes ? "" : probes.error().message);
    return probes ? std::move(*probes) : nullptr;
}

/// The scene's lamp plus six directional lights of 0.5 W/m² along ±x, ±y, ±z: they light the
/// outside of the box too, so that every cache, the grid's outside the box included, sees some
/// light with a few dozen rays.
LightSet litEverywhere() {
    LightSet lights = defaultLightSet(cornell().scene);
    const glm::vec3 axes[] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (const glm::vec3& axis : axes) {
        Light light;
        light.id = "axis" + std::to_string(lights.lights.size());
        light.type = LightType::Directional;
        light.direction = axis;
        light.intensity = 0.5f;
        lights.lights.push_back(light);
    }
    return lights;
}

/// The values after `updates` updates under `lights` (default: the scene's).
CacheValues run(TracedProbes& probes, int updates,
                const LightSet& lights = defaultLightSet(cornell().scene)) {
    CacheValues values;
    for (int u = 0; u < updates; ++u) {
        auto result = probes.update(lights);
        EXPECT_TRUE(result) << (result ? "" : result.error().message);
        if (!result) return values;
        values = **result;
    }
    return values;
}

/// Band-0 luma of cache c.
float luma0(const CacheValues& values, size_t c) {
    return values.y[c * values.bandsY * values.bandsY];
}

/// How band-0 luma of `values` compares with `reference`: the ratio of their means over the
/// caches and the RMS difference per cache relative to the reference's mean.
struct Agreement {
    double meanRatio = 0.0;
    double relativeRms = 0.0;
};

Agreement agreement(const CacheValues& values, const CacheValues& reference) {
    const size_t n = reference.cacheCount();
    EXPECT_EQ(values.cacheCount(), n);
    double sum = 0.0, sumReference = 0.0, squares = 0.0;
    std::vector<double> relative;
    for (size_t c = 0; c < n; ++c) {
        const double a = luma0(values, c), b = luma0(reference, c);
        sum += a;
        sumReference += b;
        squares += (a - b) * (a - b);
        if (b > 0.0) relative.push_back(std::abs(a - b) / b);
    }
    std::sort(relative.begin(), relative.end());
    std::printf("  (median per-cache relative difference %.4f, 90th percentile %.4f)\n",
                relative[relative.size() / 2], relative[relative.size() * 9 / 10]);
    const double meanReference = sumReference / double(n);
    return {sum / sumReference, std::sqrt(squares / double(n)) / meanReference};
}

/// The ideal caches of the Cornell bake under its lights, path-traced once per bounce count.
const CacheValues& ideal(int bounces, uint32_t samples) {
    static std::map<std::pair<int, uint32_t>, CacheValues> made;
    const auto key = std::pair(bounces, samples);
    auto found = made.find(key);
    if (found != made.end()) return found->second;
    const test::BakedScene& b = cornell();
    ProbeParams params;
    params.samples = samples;
    params.bounces = bounces;
    params.indirectOnly = true;
    auto values = pathTraceProbes(b.scene, *b.rays, b.bake, defaultLightSet(b.scene), params);
    EXPECT_TRUE(values) << (values ? "" : values.error().message);
    return made[key] = values ? std::move(*values) : CacheValues{};
}

/// Caches whose values differ between `before` and `after`.
std::set<size_t> changedCaches(const CacheValues& before, const CacheValues& after) {
    std::set<size_t> changed;
    const size_t countY = size_t{after.bandsY} * after.bandsY;
    for (size_t c = 0; c < after.cacheCount(); ++c)
        for (size_t j = 0; j < countY; ++j)
            if (before.y[c * countY + j] != after.y[c * countY + j]) {
                changed.insert(c);
                break;
            }
    return changed;
}

TEST(TracedProbes, OneUpdateIsOneBounce) {
    ASSERT_TRUE(cornell().ok);
    // The box has no emitters: one update holds direct light reflected once, which is what
    // the path tracer's paths of at most one reflection carry. Only noise tells them apart,
    // most of it from the lamp's hot spot 5 cm under the ceiling, which a few rays of a cache
    // hit or miss (seeds 1-4 measured mean ratios 1.0010-1.0054, relative RMS 0.062-0.073).
    auto probes = makeProbes({.raysPerCache = 1024});
    ASSERT_TRUE(probes);
    const CacheValues values = run(*probes, 1);
    const Agreement a = agreement(values, ideal(1, 4096));
    std::printf("one update, K = 1024, against 1 bounce: mean ratio %.4f, relative RMS %.4f\n",
                a.meanRatio, a.relativeRms);
    EXPECT_NEAR(a.meanRatio, 1.0, 0.02);  // measured 1.0027
    EXPECT_LT(a.relativeRms, 0.12);       // measured 0.0725
}

TEST(TracedProbes, ConvergedUpdatesMatchIdealCaches) {
    ASSERT_TRUE(cornell().ok);
    // h = 0 and ten updates: each update adds a bounce, read from the previous update's
    // caches rather than traced on (seeds 1-4 measured mean ratios 0.9977-1.0014, relative
    // RMS 0.036-0.039: the caches' interpolation costs little in this box).
    auto probes = makeProbes({.raysPerCache = 1024});
    ASSERT_TRUE(probes);
    const auto start = std::chrono::steady_clock::now();
    const CacheValues values = run(*probes, 10);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    const Agreement a = agreement(values, ideal(-1, 4096));
    std::printf(
        "%zu caches, 10 updates of K = 1024 (%.1f ms each), against all bounces: mean "
        "ratio %.4f, relative RMS %.4f; %llu bytes\n",
        values.cacheCount(), ms / 10.0, a.meanRatio, a.relativeRms,
        static_cast<unsigned long long>(probes->memoryBytes()));
    EXPECT_NEAR(a.meanRatio, 1.0, 0.03);  // measured 1.0007
    EXPECT_LT(a.relativeRms, 0.08);       // measured 0.0394

    // A renderer shades from the returned values as from any caches: the camera's indirect
    // light from them against that from the ideal caches.
    const test::BakedScene& b = cornell();
    ASSERT_FALSE(b.scene.cameras.empty());
    ShadeParams shade;
    shade.width = shade.height = 32;
    shade.component = ShadeComponent::Indirect;
    const LightSet lights = defaultLightSet(b.scene);
    auto traced =
        shadeFromCaches(b.scene, *b.rays, b.bake, values, lights, b.scene.cameras[0], shade);
    auto reference = shadeFromCaches(b.scene, *b.rays, b.bake, ideal(-1, 4096), lights,
                                     b.scene.cameras[0], shade);
    ASSERT_TRUE(traced && reference);
    double sum = 0.0, sumReference = 0.0;
    for (size_t i = 0; i < traced->pixels.size(); ++i) {
        const glm::vec3 p = traced->pixels[i];
        ASSERT_TRUE(std::isfinite(p.r + p.g + p.b) && p.r >= 0.0f && p.g >= 0.0f && p.b >= 0.0f)
            << i;
        sum += luminance(p);
        sumReference += luminance(reference->pixels[i]);
    }
    std::printf("indirect image from the traced caches: mean %.4f of the ideal ones\n",
                sum / sumReference);
    EXPECT_NEAR(sum / sumReference, 1.0, 0.03);  // measured 1.0037
}

TEST(TracedProbes, HysteresisBlendsUpdates) {
    ASSERT_TRUE(cornell().ok);
    // Same seed: every run traces the same directions at update u. With prior values P the
    // traced values are D_u + I_u(P), D_u the direct light, I_u linear in P; and
    // new = h·old + (1 − h)·traced. From zero: after one update h·0 + (1 − h)·D_1.
    auto replace = makeProbes({.raysPerCache = 256});
    auto half = makeProbes({.raysPerCache = 256, .hysteresis = 0.5f});
    auto quarter = makeProbes({.raysPerCache = 256, .hysteresis = 0.25f});
    ASSERT_TRUE(replace && half && quarter);
    const CacheValues r1 = run(*replace, 1), h1 = run(*half, 1), q1 = run(*quarter, 1);
    const CacheValues r2 = run(*replace, 1), h2 = run(*half, 1), q2 = run(*quarter, 1);
    ASSERT_EQ(r1.y.size(), h1.y.size());
    double scale = 0.0;
    for (float v : r1.y) scale = std::max(scale, double(std::abs(v)));
    ASSERT_GT(scale, 0.0);
    const double tolerance = 1e-5 * scale;
    double sumR1 = 0.0, sumH2 = 0.0, sumDirect = 0.0;
    for (size_t i = 0; i < r1.y.size(); ++i) {
        // One update: (1 − h) of the one-bounce values, exactly.
        ASSERT_EQ(h1.y[i], 0.5f * r1.y[i]) << i;
        ASSERT_NEAR(q1.y[i], 0.75 * r1.y[i], tolerance) << i;
        // Two updates. h = 0 gives D_2 + I_2(D_1); h = 0.5 traced D_2 + I_2(D_1)/2, i.e.
        // 2·h2 − h1. The two give D_2 and I_2(D_1), and with them h = 0.25 is foretold:
        // 0.25·(0.75·D_1) + 0.75·(D_2 + 0.75·I_2(D_1)).
        const double tracedHalf = 2.0 * h2.y[i] - h1.y[i];
        const double bounce = 2.0 * (r2.y[i] - tracedHalf);
        const double direct = r2.y[i] - bounce;
        EXPECT_NEAR(q2.y[i], 0.25 * q1.y[i] + 0.75 * (direct + 0.75 * bounce), 4.0 * tolerance)
            << i;
        sumR1 += r1.y[i];
        sumH2 += h2.y[i];
        sumDirect += 0.25 * r1.y[i] + 0.5 * direct;
    }
    // Under unchanged lights two updates with h = 0.5 hold 1 − 0.5² = 0.75 of the one-bounce
    // light (D_1 and D_2 sample the same light, so only in the mean: seeds 1-4 measured
    // 0.735-0.750) plus a quarter of the second bounce.
    std::printf("h = 0.5, two updates: one-bounce part %.4f of one update, all %.4f\n",
                sumDirect / sumR1, sumH2 / sumR1);
    EXPECT_NEAR(sumDirect / sumR1, 0.75, 0.04);  // measured 0.7426
}

TEST(TracedProbes, SubsetsTraceEachCacheOnceInFourUpdates) {
    ASSERT_TRUE(cornell().ok);
    const size_t n = cornell().bake.caches.size();
    // Lit from every side, every cache gets light when it is traced, so the caches an update
    // traced are the ones whose values changed.
    const LightSet lights = litEverywhere();
    auto probes = makeProbes({.raysPerCache = 64, .subsets = 4});
    ASSERT_TRUE(probes);
    CacheValues before =
        CacheValues::zeros(n, cornell().bake.params.bandsY, cornell().bake.params.bandsC);
    std::set<size_t> seen;
    std::vector<std::set<size_t>> parts;
    for (int u = 0; u < 4; ++u) {
        const CacheValues after = run(*probes, 1, lights);
        const std::set<size_t> changed = changedCaches(before, after);
        EXPECT_GE(changed.size(), n / 4) << "update " << u;
        EXPECT_LE(changed.size(), (n + 3) / 4) << "update " << u;
        for (size_t c : changed) EXPECT_TRUE(seen.insert(c).second) << "cache " << c;
        EXPECT_EQ(seen.size() == n, u == 3) << "update " << u;
        parts.push_back(changed);
        before = after;
    }
    // The pattern repeats: update 5 traces update 1's caches again.
    EXPECT_EQ(changedCaches(before, run(*probes, 1, lights)), parts[0]);
}

TEST(TracedProbes, DeterministicPerSeedAndThreadCount) {
    ASSERT_TRUE(cornell().ok);
    const TracedProbeParams params{.raysPerCache = 8, .hysteresis = 0.25f, .subsets = 2};
    auto a = makeProbes(params);
    auto b = makeProbes(params);
    auto other = makeProbes({.raysPerCache = 8, .hysteresis = 0.25f, .subsets = 2, .seed = 2});
    ASSERT_TRUE(a && b && other);
    const CacheValues va = run(*a, 3);
    setWorkerCount(1);
    const CacheValues vb = run(*b, 3);
    setWorkerCount(0);
    EXPECT_EQ(va.y, vb.y);
    EXPECT_EQ(va.co, vb.co);
    EXPECT_EQ(va.cg, vb.cg);
    EXPECT_NE(run(*other, 3).y, va.y);
}

TEST(TracedProbes, RejectsBadParams) {
    const test::BakedScene& b = cornell();
    ASSERT_TRUE(b.ok);
    const auto rejects = [&](const TracedProbeParams& params, const char* name, const char* value) {
        auto probes = TracedProbes::create(b.scene, *b.rays, b.bake, params);
        ASSERT_FALSE(probes) << name;
        EXPECT_EQ(probes.error().code, ErrorCode::InvalidInput);
        EXPECT_NE(probes.error().message.find(name), std::string::npos) << probes.error().message;
        EXPECT_NE(probes.error().message.find(value), std::string::npos) << probes.error().message;
    };
    rejects({.raysPerCache = 0}, "raysPerCache", "0");
    rejects({.hysteresis = 1.0f}, "hysteresis", "1");
    rejects({.hysteresis = -0.5f}, "hysteresis", "-0.5");
    rejects({.hysteresis = std::numeric_limits<float>::quiet_NaN()}, "hysteresis", "nan");
    rejects({.subsets = 0}, "subsets", "0");
    rejects({.subsets = 65}, "subsets", "65");

    // A bake of the Cornell box does not fit another scene.
    const Scene other = test::loadTestScene("closed_box");
    auto otherRays = EmbreeScene::create(other);
    ASSERT_TRUE(otherRays);
    auto probes = TracedProbes::create(other, **otherRays, b.bake, {});
    ASSERT_FALSE(probes);
    EXPECT_EQ(probes.error().code, ErrorCode::InvalidInput);
    EXPECT_NE(probes.error().message.find("scene hash"), std::string::npos)
        << probes.error().message;

    // Nor does a light set that scales a material the scene lacks.
    auto good = TracedProbes::create(b.scene, *b.rays, b.bake, {});
    ASSERT_TRUE(good);
    LightSet lights = defaultLightSet(b.scene);
    lights.emissiveScale["no_such_material"] = 2.0f;
    auto updated = (*good)->update(lights);
    ASSERT_FALSE(updated);
    EXPECT_EQ(updated.error().code, ErrorCode::InvalidInput);
}

}  // namespace
}  // namespace pic
