#include "bake/ref/probes.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <vector>

#include "core/color.h"
#include "core/geometry.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "core/sh.h"

namespace pic {

namespace {

constexpr double kPi = std::numbers::pi;
/// Fractional part of the golden ratio: consecutive multiples spread azimuths evenly.
constexpr double kGoldenFraction = 0.6180339887498949;

/// Direction i of n stratified directions: cosθ jittered within the i-th of n equal slices
/// (equal solid angle), azimuth on the golden-angle spiral turned by `phiOffset`; z is the
/// polar axis, over the sphere or only its upper half. Every direction is uniformly
/// distributed on its own, so the estimate stays unbiased.
glm::vec3 stratifiedDirection(uint32_t i, uint32_t n, float jitter, double phiOffset,
                              bool hemisphere) {
    double u = (double(i) + double(jitter)) / double(n);
    double z = hemisphere ? 1.0 - u : 1.0 - 2.0 * u;
    double turns = double(i) * kGoldenFraction + phiOffset;
    double phi = 2.0 * kPi * (turns - std::floor(turns));
    double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    return glm::vec3(float(r * std::cos(phi)), float(r * std::sin(phi)), float(z));
}

}  // namespace

Result<CacheValues> pathTraceProbes(const Scene& scene, const EmbreeScene& rays,
                                    const BakeData& bake, const LightSet& lights,
                                    const ProbeParams& params, PathTraceStats* stats) {
    if (bake.sceneHash != scene.hash)
        return fail(ErrorCode::InvalidInput,
                    "the bake was made for scene hash {:016x}, scene '{}' has hash {:016x}",
                    bake.sceneHash, scene.sourcePath, scene.hash);
    const uint32_t bandsY = bake.params.bandsY, bandsC = bake.params.bandsC;
    if (bandsY < 1 || bandsY > uint32_t(kMaxShBands) || bandsC < 1 || bandsC > bandsY)
        return fail(ErrorCode::InvalidInput,
                    "bake band counts y {} c {} are outside 1 <= c <= y <= {}", bandsY, bandsC,
                    kMaxShBands);
    if (params.samples == 0)
        return fail(ErrorCode::InvalidInput, "probe samples must be at least 1, got 0");
    if (params.bounces < -1)
        return fail(ErrorCode::InvalidInput, "bounces must be -1 (unlimited) or >= 0, got {}",
                    params.bounces);

    auto start = std::chrono::steady_clock::now();
    PathTracer tracer(scene, rays, lights);
    const size_t cacheCount = bake.caches.size();
    CacheValues values = CacheValues::zeros(cacheCount, bandsY, bandsC);
    const size_t countY = size_t(shCount(int(bandsY))), countC = size_t(shCount(int(bandsC)));
    std::vector<uint64_t> rejectedPerCache(cacheCount, 0);

    Progress progress("ideal caches", cacheCount);
    parallelFor(
        0, cacheCount,
        [&](size_t c) {
            const Cache& cache = bake.caches[c];
            const bool hemisphere = cache.kind == gpu::kCacheKindLightmap;
            glm::vec3 tangent(1.0f, 0.0f, 0.0f), bitangent(0.0f, 1.0f, 0.0f),
                normal(0.0f, 0.0f, 1.0f);
            if (hemisphere) {
                normal = glm::normalize(cache.normal);
                orthonormalBasis(normal, tangent, bitangent);
            }
            // One stream per cache: its samples run in order on one thread.
            Rng rng(params.seed, c);
            const double phiOffset = rng.uniform();
            std::vector<double> sumY(countY, 0.0), sumCo(countC, 0.0), sumCg(countC, 0.0);
            float basis[shCount(kMaxShBands)];

            for (uint32_t i = 0; i < params.samples; ++i) {
                glm::vec3 local =
                    stratifiedDirection(i, params.samples, rng.uniform(), phiOffset, hemisphere);
                glm::vec3 direction =
                    glm::normalize(local.x * tangent + local.y * bitangent + local.z * normal);
                // The cache is a shading point: what arrives there after at most B reflections,
                // emitters seen directly included (the caches carry area lights too).
                glm::vec3 radiance = tracer.traceRadiance(cache.position, direction, params.bounces,
                                                          PathTraceParams::Component::Full, rng);
                if (!isValidRadiance(radiance)) {
                    ++rejectedPerCache[c];
                    continue;
                }
                glm::vec3 yCoCg = rgbToYCoCg(radiance);
                shEvaluate(int(bandsY), direction, basis);
                for (size_t j = 0; j < countY; ++j) sumY[j] += double(yCoCg.x) * basis[j];
                for (size_t j = 0; j < countC; ++j) {
                    sumCo[j] += double(yCoCg.y) * basis[j];
                    sumCg[j] += double(yCoCg.z) * basis[j];
                }
            }
            // Uniform directions over the (hemi)sphere: each sample stands for Ω/N steradians.
            const double weight = (hemisphere ? 2.0 : 4.0) * kPi / double(params.samples);
            for (size_t j = 0; j < countY; ++j) sumY[j] *= weight;
            for (size_t j = 0; j < countC; ++j) {
                sumCo[j] *= weight;
                sumCg[j] *= weight;
            }

            if (!params.indirectOnly) {
                // Punctual lights are deltas in direction: radiance I/d² projects to E·y(ω).
                for (const Light& light : lights.lights) {
                    glm::vec3 toLight;
                    float distance = 0.0f;
                    // The first call only finds the direction to the light.
                    lightIrradiance(light, cache.position, normal, toLight, distance);
                    if (hemisphere && glm::dot(toLight, normal) <= 0.0f) continue;
                    // Irradiance on a surface facing the light has no cosine factor left.
                    const glm::vec3 facing = toLight;
                    glm::vec3 irradiance =
                        lightIrradiance(light, cache.position, facing, toLight, distance);
                    if (!isValidRadiance(irradiance) || !(glm::dot(irradiance, irradiance) > 0.0f))
                        continue;
                    if (rays.occluded(cache.position, toLight, 0.0f,
                                      std::max(0.0f, distance - rays.epsilon())))
                        continue;
                    glm::vec3 yCoCg = rgbToYCoCg(irradiance);
                    shEvaluate(int(bandsY), toLight, basis);
                    for (size_t j = 0; j < countY; ++j) sumY[j] += double(yCoCg.x) * basis[j];
                    for (size_t j = 0; j < countC; ++j) {
                        sumCo[j] += double(yCoCg.y) * basis[j];
                        sumCg[j] += double(yCoCg.z) * basis[j];
                    }
                }
            }

            for (size_t j = 0; j < countY; ++j) values.y[c * countY + j] = float(sumY[j]);
            for (size_t j = 0; j < countC; ++j) {
                values.co[c * countC + j] = float(sumCo[j]);
                values.cg[c * countC + j] = float(sumCg[j]);
            }
            progress.advance();
        },
        1);
    progress.finish();

    if (stats) {
        stats->samples = uint64_t(cacheCount) * params.samples;
        stats->rejected = 0;
        for (uint64_t r : rejectedPerCache) stats->rejected += r;
        stats->seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    return values;
}

}  // namespace pic
