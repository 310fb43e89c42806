#include "bench/traced_probes.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <utility>

#include "bake/ref/path_tracer.h"
#include "bake/ref/probe_projection.h"
#include "core/parallel.h"
#include "core/sampling.h"
#include "core/sh.h"
#include "render/runtime.h"

namespace pic {

namespace {

constexpr float kInvPi = std::numbers::inv_pi_v<float>;
constexpr float kInfinity = std::numeric_limits<float>::infinity();

/// Most subsets: beyond that a cache waits too long between its updates to be a baseline.
constexpr uint32_t kMaxSubsets = 64;
/// Caches per task: a cache costs K rays, so a few per task balance the two cores.
constexpr size_t kCacheGrain = 4;
/// The random stream of the subsets' cache order, apart from the caches' streams.
constexpr uint64_t kOrderStream = ~uint64_t{0};

/// Bytes a vector's storage takes.
template <class T>
uint64_t bytesOf(const std::vector<T>& v) {
    return uint64_t(v.capacity()) * sizeof(T);
}

uint64_t bytesOf(const CacheValues& values) {
    return bytesOf(values.y) + bytesOf(values.co) + bytesOf(values.cg) + bytesOf(values.irradiance);
}

}  // namespace

TracedProbes::TracedProbes(const Scene& scene, const EmbreeScene& rays, const BakeData& bake,
                           const TracedProbeParams& params)
    : mScene(&scene), mRays(&rays), mBake(&bake), mParams(params) {}

Result<std::unique_ptr<TracedProbes>> TracedProbes::create(const Scene& scene,
                                                           const EmbreeScene& rays,
                                                           const BakeData& bake,
                                                           const TracedProbeParams& params) {
    if (params.raysPerCache == 0)
        return fail(ErrorCode::InvalidInput, "raysPerCache (K) must be at least 1, got 0");
    if (!(params.hysteresis >= 0.0f && params.hysteresis < 1.0f))
        return fail(ErrorCode::InvalidInput, "hysteresis must be in [0, 1), got {}",
                    params.hysteresis);
    if (params.subsets == 0 || params.subsets > kMaxSubsets)
        return fail(ErrorCode::InvalidInput, "subsets must be in [1, {}], got {}", kMaxSubsets,
                    params.subsets);
    // The bake's own checks, as every runtime backend makes them: its scene, bands, surfels.
    PIC_TRY(checkRuntimeBake(scene, bake));
    if (rays.scene().hash != scene.hash)
        return fail(ErrorCode::InvalidInput,
                    "the Embree scene was built for scene hash {:016x}, scene '{}' has hash "
                    "{:016x}",
                    rays.scene().hash, scene.sourcePath, scene.hash);
    const uint32_t bandsY = bake.params.bandsY, bandsC = bake.params.bandsC;

    std::unique_ptr<TracedProbes> probes(new TracedProbes(scene, rays, bake, params));
    const size_t cacheCount = bake.caches.size();
    probes->mValues = CacheValues::zeros(cacheCount, bandsY, bandsC);
    probes->mPrevious = probes->mValues;

    // A fixed random order, cut into parts of floor or ceil of nC / subsets caches: each cache
    // keeps its slot, so it is traced exactly once every `subsets` updates (paper 003 §5.3's
    // randomised index pattern) and neighbouring caches are spread over the parts.
    probes->mOrder.resize(cacheCount);
    for (size_t c = 0; c < cacheCount; ++c) probes->mOrder[c] = uint32_t(c);
    if (params.subsets > 1) {
        Rng rng(params.seed, kOrderStream);
        for (size_t i = cacheCount; i > 1; --i)
            std::swap(probes->mOrder[i - 1], probes->mOrder[size_t(rng.next() % i)]);
    }
    probes->mSubsetBegin.resize(params.subsets + 1);
    for (uint32_t s = 0; s <= params.subsets; ++s)
        probes->mSubsetBegin[s] = uint32_t(uint64_t(cacheCount) * s / params.subsets);
    return probes;
}

Result<const CacheValues*> TracedProbes::update(const LightSet& lights) {
    PIC_TRY(checkLightSet(lights, *mScene));
    mEmissiveScale.resize(mScene->materials.size());
    for (size_t m = 0; m < mScene->materials.size(); ++m)
        mEmissiveScale[m] = lights.emissiveScaleOf(mScene->materials[m].name);

    // Hits read the bounce from the values before this update, whichever caches it rewrites.
    mPrevious.y = mValues.y;
    mPrevious.co = mValues.co;
    mPrevious.cg = mValues.cg;
    // Until the first update every cache is zero: no bounce to read.
    const bool bounce = mUpdates > 0;
    const uint64_t update = mUpdates;
    const uint32_t subset = uint32_t(update % mParams.subsets);
    const uint32_t rayCount = mParams.raysPerCache;
    const double keep = double(mParams.hysteresis);
    const uint32_t bandsY = mValues.bandsY, bandsC = mValues.bandsC;
    const size_t countY = size_t(shCount(int(bandsY))), countC = size_t(shCount(int(bandsC)));

    parallelFor(
        mSubsetBegin[subset], mSubsetBegin[subset + 1],
        [&](size_t k) {
            const uint32_t c = mOrder[k];
            const Cache& cache = mBake->caches[c];
            // One stream per (update, cache): its rays run in order on one thread.
            Rng rng(mParams.seed, (update << 32) ^ uint64_t(c));
            // A random rotation per update: a grid cache's stratification axis is a uniform
            // direction and, like a light-map cache's fixed normal, it is turned by a uniform
            // azimuth (phiOffset); both make each direction uniform over its domain.
            ProbeFrame frame;
            if (cache.kind == gpu::kCacheKindLightmap) {
                frame = ProbeFrame::of(cache);
            } else {
                const float u1 = rng.uniform();
                const float u2 = rng.uniform();
                frame = ProbeFrame::about(sampleUniformSphere(u1, u2), false);
            }
            const double phiOffset = rng.uniform();
            ShProjectionSums sums(bandsY, bandsC);
            for (uint32_t i = 0; i < rayCount; ++i) {
                const glm::vec3 direction = frame.toWorld(
                    stratifiedDirection(i, rayCount, rng.uniform(), phiOffset, frame.hemisphere));
                const glm::vec3 radiance =
                    tracedRadiance(cache.position, direction, lights, bounce);
                // The path tracer's guard: a NaN, infinite or negative sample counts as 0.
                if (isValidRadiance(radiance)) sums.add(direction, radiance);
            }
            // Uniform directions over the (hemi)sphere: each ray stands for Ω/K steradians.
            sums.scale(frame.solidAngle() / double(rayCount));

            // DDGI's temporal blend; h = 0 stores the traced values exactly.
            for (size_t j = 0; j < countY; ++j) {
                float& v = mValues.y[c * countY + j];
                v = float(keep * double(v) + (1.0 - keep) * sums.y()[j]);
            }
            for (size_t j = 0; j < countC; ++j) {
                float& co = mValues.co[c * countC + j];
                float& cg = mValues.cg[c * countC + j];
                co = float(keep * double(co) + (1.0 - keep) * sums.co()[j]);
                cg = float(keep * double(cg) + (1.0 - keep) * sums.cg()[j]);
            }
        },
        kCacheGrain);
    ++mUpdates;
    return &mValues;
}

glm::vec3 TracedProbes::tracedRadiance(const glm::vec3& origin, const glm::vec3& direction,
                                       const LightSet& lights, bool bounce) const {
    const std::optional<RayHit> hit = mRays->intersect(origin, direction, 0.0f, kInfinity);
    // No sky: rays that leave the scene bring nothing.
    if (!hit) return glm::vec3(0.0f);
    const uint32_t t = hit->triangle;
    glm::vec3 radiance(0.0f);
    // Emitters radiate from their front side only (as the path tracer has it).
    if (!hit->backFace)
        radiance +=
            mScene->emissionAt(t, hit->b1, hit->b2) * mEmissiveScale[mScene->triangles[t].material];
    const glm::vec3 albedo = mScene->albedoAt(t, hit->b1, hit->b2);
    if (!(std::max(albedo.r, std::max(albedo.g, albedo.b)) > 0.0f)) return radiance;
    // Two-sided reflection: shade with the geometric normal facing the arriving ray.
    const glm::vec3 normal = hit->backFace ? -hit->geometricNormal : hit->geometricNormal;
    const glm::vec3 position = origin + hit->t * direction;

    // Direct light: each punctual light's irradiance (lightIrradiance) times the visibility
    // of one shadow ray from just above the surface, as the path tracer and surfel lighting.
    const float epsilon = mRays->epsilon();
    const glm::vec3 shadowOrigin = position + epsilon * normal;
    glm::vec3 received(0.0f);
    for (const Light& light : lights.lights) {
        glm::vec3 toLight;
        float distance = kInfinity;
        const glm::vec3 e = lightIrradiance(light, position, normal, toLight, distance);
        if (!(e.r > 0.0f || e.g > 0.0f || e.b > 0.0f)) continue;
        if (mRays->occluded(shadowOrigin, toLight, 0.0f, std::max(0.0f, distance - epsilon)))
            continue;
        received += e;
    }
    // Further bounces: the previous update's caches around the hit, as a renderer reads them,
    // SH ringing below zero cut per channel (render/cpu/cache_shading.h does the same).
    if (bounce)
        received += glm::max(
            irradiance(lookupSurfaceRadiance(*mBake, mPrevious, t, hit->b1, hit->b2, position),
                       normal),
            glm::vec3(0.0f));
    return radiance + albedo * kInvPi * received;
}

uint64_t TracedProbes::memoryBytes() const {
    return sizeof(*this) + bytesOf(mValues) + bytesOf(mPrevious) + bytesOf(mOrder) +
           bytesOf(mSubsetBegin) + bytesOf(mEmissiveScale);
}

}  // namespace pic
