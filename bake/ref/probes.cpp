#include "bake/ref/probes.h"

#include <algorithm>
#include <chrono>
#include <vector>

#include "bake/ref/probe_projection.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "core/sh.h"

namespace pic {

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
    PIC_TRY_ASSIGN(const PathTracer tracer, PathTracer::create(scene, rays, lights));
    const size_t cacheCount = bake.caches.size();
    CacheValues values = CacheValues::zeros(cacheCount, bandsY, bandsC);
    std::vector<uint64_t> rejectedPerCache(cacheCount, 0);

    Progress progress("ideal caches", cacheCount);
    parallelFor(
        0, cacheCount,
        [&](size_t c) {
            const Cache& cache = bake.caches[c];
            const ProbeFrame frame = ProbeFrame::of(cache);
            // One stream per cache: its samples run in order on one thread.
            Rng rng(params.seed, c);
            const double phiOffset = rng.uniform();
            ShProjectionSums sums(bandsY, bandsC);

            for (uint32_t i = 0; i < params.samples; ++i) {
                glm::vec3 direction = frame.toWorld(stratifiedDirection(
                    i, params.samples, rng.uniform(), phiOffset, frame.hemisphere));
                // The cache is a shading point: what arrives there after at most B reflections,
                // emitters and the sky seen directly included (the caches carry area lights and
                // the sky too).
                glm::vec3 radiance = tracer.traceRadiance(cache.position, direction, params.bounces,
                                                          PathTraceParams::Component::Full, rng,
                                                          PathTracer::Escape::Sky);
                if (!isValidRadiance(radiance)) {
                    ++rejectedPerCache[c];
                    continue;
                }
                sums.add(direction, radiance);
            }
            // Uniform directions over the (hemi)sphere: each sample stands for Ω/N steradians.
            sums.scale(frame.solidAngle() / double(params.samples));

            if (!params.indirectOnly) {
                // Punctual lights are deltas in direction: radiance I/d² projects to E·y(ω).
                for (const Light& light : lights.lights) {
                    glm::vec3 toLight;
                    float distance = 0.0f;
                    // The first call only finds the direction to the light.
                    lightIrradiance(light, cache.position, frame.normal, toLight, distance);
                    if (frame.hemisphere && glm::dot(toLight, frame.normal) <= 0.0f) continue;
                    // Irradiance on a surface facing the light has no cosine factor left.
                    const glm::vec3 facing = toLight;
                    glm::vec3 irradiance =
                        lightIrradiance(light, cache.position, facing, toLight, distance);
                    if (!isValidRadiance(irradiance) || !(glm::dot(irradiance, irradiance) > 0.0f))
                        continue;
                    if (rays.occluded(cache.position, toLight, 0.0f,
                                      std::max(0.0f, distance - rays.epsilon())))
                        continue;
                    sums.add(toLight, irradiance);
                }
            }

            sums.store(values, c);
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
