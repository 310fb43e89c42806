#include "render/gpu_runtime.h"

#include <chrono>

#include "core/cache_textures.h"
#include "core/color.h"
#include "render/node_spread.h"
#include "render/passes/cache_lighting_pass.h"
#include "render/passes/lightmap_copy_pass.h"
#include "render/passes/pass.h"
#include "render/passes/pull_pass.h"
#include "render/passes/ray_visibility_pass.h"
#include "render/passes/shadow_map_pass.h"
#include "render/passes/sky_caches_pass.h"
#include "render/passes/surfel_lighting_pass.h"
#include "render/sh_tables.h"

namespace pic {
namespace {

using Clock = std::chrono::steady_clock;

double millisecondsSince(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

/// Timestamp pairs one submission may hold: shadow maps, surfel lighting, pull, cache
/// lighting, light-map copy, with room to spare.
constexpr uint32_t kTimedPasses = 16;

}  // namespace

Result<std::unique_ptr<GpuRuntime>> GpuRuntime::create(const Scene& scene, const EmbreeScene& rays,
                                                       const BakeData& bake,
                                                       const BounceParams& bounces,
                                                       const GpuRuntimeOptions& options) {
    PIC_TRY(checkRuntimeBake(scene, bake));
    PIC_TRY(checkBounceParams(bounces));
    std::unique_ptr<GpuRuntime> runtime(new GpuRuntime(scene, bake, bounces));
    PIC_TRY(runtime->init(rays, options));
    return runtime;
}

GpuRuntime::GpuRuntime(const Scene& scene, const BakeData& bake, const BounceParams& bounces)
    : mScene(scene),
      mBake(bake),
      mBounces(bounces),
      mRatioBound(bounceRatioBound(bake)),
      mSky(scene, bake) {}

GpuRuntime::~GpuRuntime() = default;

Result<void> GpuRuntime::init(const EmbreeScene& rays, const GpuRuntimeOptions& options) {
    using namespace gpu;
    const ContextOptions contextOptions{options.deviceName, options.validation,
                                        options.mapDeviceMemory};
    PIC_TRY_ASSIGN(mContext, Context::create(contextOptions));
    Context& ctx = *mContext;
    const size_t nC = mBake.caches.size();
    const uint32_t countY = mBake.params.bandsY * mBake.params.bandsY;
    const uint32_t countC = mBake.params.bandsC * mBake.params.bandsC;

    // The pull reads the node flux, cache lighting the node radiance, and the bounce's surfel
    // lighting the caches as uniform texel buffers.
    constexpr VkBufferUsageFlags kTexels = VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT;
    PIC_TRY_ASSIGN(mNodeFlux, Buffer::create(ctx, mBake.nodes.size() * sizeof(glm::vec4), kTexels,
                                             MemoryUse::Device, "node flux"));
    // Leaves have no flux gradient: the words surfel lighting leaves alone start at zero.
    const std::vector<glm::uvec4> noLight(mBake.nodes.size(), glm::uvec4(0u));
    PIC_TRY_ASSIGN(mNodeLight, Buffer::createWith(ctx, std::span<const glm::uvec4>(noLight),
                                                  kTexels, "node light"));
    PIC_TRY_ASSIGN(mCacheY,
                   Buffer::create(ctx, 2 * nC * countY, kTexels, MemoryUse::Device, "caches Y"));
    PIC_TRY_ASSIGN(mCacheCo,
                   Buffer::create(ctx, 2 * nC * countC, kTexels, MemoryUse::Device, "caches Co"));
    PIC_TRY_ASSIGN(mCacheCg,
                   Buffer::create(ctx, 2 * nC * countC, kTexels, MemoryUse::Device, "caches Cg"));
    // The bounce reads the irradiance along the light-map caches' normals as RGBA32F texels.
    PIC_TRY_ASSIGN(mCacheIrradiance, Buffer::create(ctx, nC * sizeof(glm::vec4), kTexels,
                                                    MemoryUse::Device, "cache irradiance"));
    if (!mCacheY.mapped() || !mCacheCo.mapped() || !mCacheCg.mapped()) {
        const VkDeviceSize bytes = mCacheY.size() + mCacheCo.size() + mCacheCg.size();
        PIC_TRY_ASSIGN(mCacheReadback,
                       Buffer::create(ctx, bytes, 0, MemoryUse::Readback, "cache readback"));
    }
    const ShTables tables = makeShTables();
    PIC_TRY_ASSIGN(mShTables, Buffer::createWith(ctx, &tables, sizeof(tables),
                                                 VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, "SH tables"));
    PIC_TRY_ASSIGN(mTimer, PassTimer::create(ctx, kTimedPasses));

    mVisibility = options.directVisibility.value_or(
        ctx.isCpuDevice() ? DirectVisibility::Rays : DirectVisibility::ShadowMaps);
    // Every pass is made through the pass table (render/passes/pass.h) from one config.
    const NodeSpread spread = nodeSpread(mBake);
    const PassConfig config{
        .scene = &mScene,
        .bake = &mBake,
        .rays = &rays,
        .spread = &spread,
        .visibility = mVisibility,
        .shadowMapSize = options.shadowMapSize,
        .shadowMap = {.levelsOfDetail = options.casterLevelsOfDetail,
                      .equalFootprint = options.shadowEqualFootprint},
        .cachePerSubgroup = options.cachePerSubgroup.value_or(!ctx.isCpuDevice()),
        .maxLinkTexelWords = options.maxLinkTexelWords,
    };
    if (mVisibility == DirectVisibility::Rays) {
        PIC_TRY_ASSIGN(mRayVisibility, createPass<RayVisibilityPass>(ctx, config));
    } else {
        PIC_TRY_ASSIGN(mShadows, createPass<ShadowMapPass>(ctx, config));
    }
    PIC_TRY_ASSIGN(mSurfels, createPass<SurfelLightingPass>(ctx, config));
    PIC_TRY_ASSIGN(mPull, createPass<PullPass>(ctx, config));
    PIC_TRY_ASSIGN(mCacheLighting, createPass<CacheLightingPass>(ctx, config));
    PIC_TRY(bindVisibility());
    PIC_TRY(mPull->bind(ctx, mNodeFlux, mNodeLight));
    PIC_TRY(mCacheLighting->bind(ctx, mNodeLight, mCacheY, mCacheCo, mCacheCg, mCacheIrradiance,
                                 mShTables));
    if (!mBake.cacheSky.empty()) {
        PIC_TRY_ASSIGN(mSkyCaches, createPass<SkyCachesPass>(ctx, config));
        PIC_TRY(mSkyCaches->bind(mCacheY, mCacheCo, mCacheCg));
    }
    mLightmapCopyOnHost = options.lightmapCopyOnHost.value_or(ctx.isCpuDevice());

    mValues = CacheValues::zeros(nC, mBake.params.bandsY, mBake.params.bandsC);
    mTextures = makeCacheTextures(mBake);
    return {};
}

Result<gpu::LightmapCopyPass*> GpuRuntime::lightmapCopyPass() {
    if (!mLightmapCopy) {
        PIC_TRY_ASSIGN(mLightmapCopy,
                       gpu::createPass<gpu::LightmapCopyPass>(*mContext, {.bake = &mBake}));
        PIC_TRY(mLightmapCopy->bind(mCacheY, mCacheCo, mCacheCg));
    }
    return mLightmapCopy.get();
}

Result<void> GpuRuntime::bindVisibility() {
    return mSurfels->bind({mShadows.get(), mRayVisibility.get(), &mNodeFlux, &mNodeLight, &mCacheY,
                           &mCacheCo, &mCacheCg, &mCacheIrradiance, &mShTables});
}

Result<void> GpuRuntime::prepareLights(const LightSet& lights) {
    PIC_TRY(checkRuntimeLights(lights, mScene));
    bool reallocated = false;
    if (mShadows)
        PIC_TRY(mShadows->prepare(lights, reallocated));
    else
        PIC_TRY(mRayVisibility->prepare(lights, reallocated));
    // A new depth image or visibility buffer invalidates the set that reads the old one.
    if (reallocated) PIC_TRY(bindVisibility());
    PIC_TRY_ASSIGN(mSkyNow, mSky.update(lights));
    PIC_TRY(mSurfels->setSky(mSkyNow ? &mSkyNow->sh : nullptr));
    if (mSkyNow && mSkyCaches) PIC_TRY(mSkyCaches->setWeights(mSkyNow->caches));
    return mSurfels->setEmissiveScales(lights);
}

Result<void> GpuRuntime::addSkyToCaches(UpdateStats& stats) {
    if (!mSkyNow || !mSkyCaches) return {};
    return submitTimed(
        [&](VkCommandBuffer cmd) {
            mTimer.begin(cmd, "sky_caches");
            mSkyCaches->record(cmd, {});
            gpu::computeBarrier(cmd);
            recordCacheReadback(cmd);
        },
        stats);
}

void GpuRuntime::recordShadowMaps(VkCommandBuffer cmd) {
    if (!mShadows) return;
    mTimer.begin(cmd, "shadow_maps");
    mShadows->record(cmd, {});
}

void GpuRuntime::addVisibilityStats(UpdateStats& stats) const {
    if (mRayVisibility) {
        stats.lightsTraced = int(mRayVisibility->tracedLights());
        stats.passMs["visibility_rays"] += mRayVisibility->traceMs();
        return;
    }
    stats.shadowMapsRendered = int(mShadows->renderedLights());
    stats.shadowTriangles = mShadows->drawnTriangles();
    stats.shadowTexels = mShadows->renderedTexels();
}

Result<void> GpuRuntime::submitTimed(const std::function<void(VkCommandBuffer)>& record,
                                     UpdateStats& stats) {
    PIC_TRY(mContext->submit(record, &mTimer));
    std::vector<std::pair<std::string, double>> ms;
    PIC_TRY(mTimer.collect(ms));
    for (const auto& [pass, t] : ms) stats.passMs[pass] += t;
    return {};
}

Result<const CacheValues*> GpuRuntime::setLights(const LightSet& lights, UpdateStats* statsOut,
                                                 const BounceObserver& observer) {
    const Clock::time_point start = Clock::now();
    UpdateStats local;
    UpdateStats& stats = statsOut ? *statsOut : local;
    stats = UpdateStats{};
    PIC_TRY(prepareLights(lights));
    mTexturesCurrent = false;

    BounceSchedule schedule(mBounces, mRatioBound);
    const uint32_t lightCount = uint32_t(lights.lights.size());
    if (schedule.maxPasses() == 0) {
        // No cache pass: the caches, and so the textures, hold no light but the sky's.
        mValues = CacheValues::zeros(mBake.caches.size(), mValues.bandsY, mValues.bandsC);
        PIC_TRY(uploadCaches(mValues));
        if (mSkyNow && mSkyCaches) {
            PIC_TRY(addSkyToCaches(stats));
            readCaches(mValues);
        }
        stats.totalMs = millisecondsSince(start);
        return &mValues;
    }

    // Each submission ends with a bounce's caches and, when another bounce follows, the
    // surfel flux that bounce pulls; the host reads the flux sums to decide whether its cache
    // pass runs (BounceSchedule). Each one also reads its caches back, since only the host's
    // look at the sums tells which bounce is the last.
    const auto cacheBounce = [&](VkCommandBuffer cmd, const BounceStep& next, uint32_t sumSlot) {
        mTimer.begin(cmd, "pull");
        mPull->record(cmd, {});
        mTimer.begin(cmd, "cache_lighting");
        mCacheLighting->record(cmd, {});
        if (next.another) {
            // The caches are written before the surfels read them.
            gpu::computeBarrier(cmd);
            mTimer.begin(cmd, "surfel_lighting");
            mSurfels->record(
                cmd,
                {.bounce = true, .lightCount = lightCount, .sumSlot = sumSlot, .tail = next.tail});
        }
        // Everything written before the next submission's first pass reads it.
        gpu::computeBarrier(cmd);
        recordCacheReadback(cmd);
    };

    // Bounce 1's plan needs no flux sums, so the direct pass and bounce 2's surfels share a
    // submission.
    BounceStep step = schedule.afterBounce(1);
    PIC_TRY(submitTimed(
        [&](VkCommandBuffer cmd) {
            recordShadowMaps(cmd);
            mTimer.begin(cmd, "surfel_lighting");
            mSurfels->record(cmd, {.lightCount = lightCount, .sumSlot = 0});
            // The leaves are written before the pull reads them.
            gpu::computeBarrier(cmd);
            cacheBounce(cmd, step, 1);
        },
        stats));
    addVisibilityStats(stats);
    // The caches each submission read back, for an observer.
    const auto observe = [&](int bounce) {
        if (!observer) return;
        readCaches(mValues);
        observer(bounce, mValues, !step.another);
    };
    observe(1);
    PIC_TRY_ASSIGN(glm::dvec3 sum, mSurfels->totalFlux(0));
    schedule.record(sum);
    stats.bounces = 1;
    stats.surfelFlux = luminance(glm::vec3(sum));

    // sumSlot of the surfel flux the latest submission computed for the next bounce.
    uint32_t slot = 1;
    for (int bounce = 2; step.another; ++bounce) {
        PIC_TRY_ASSIGN(sum, mSurfels->totalFlux(slot));
        if (!schedule.record(sum)) break;
        step = schedule.afterBounce(bounce);
        slot ^= 1u;
        PIC_TRY(submitTimed([&](VkCommandBuffer cmd) { cacheBounce(cmd, step, slot); }, stats));
        stats.bounces = bounce;
        stats.surfelFlux = luminance(glm::vec3(sum));
        observe(bounce);
    }

    // After the last bounce, the direct sky.
    PIC_TRY(addSkyToCaches(stats));
    readCaches(mValues);
    stats.totalMs = millisecondsSince(start);
    return &mValues;
}

Result<const CacheTextures*> GpuRuntime::textures() {
    if (!mTexturesCurrent) {
        if (mLightmapCopyOnHost) {
            copyCachesToTextures(mBake, mValues, mTextures);
        } else {
            // From the values setLights returned: the single-pass entry points below reuse
            // the cache buffers.
            PIC_TRY_ASSIGN(gpu::LightmapCopyPass * pass, lightmapCopyPass());
            PIC_TRY(uploadCaches(mValues));
            PIC_TRY(mContext->submit([&](VkCommandBuffer cmd) { pass->record(cmd, {}); }));
            PIC_TRY(pass->read(*mContext, mTextures));
        }
        mTexturesCurrent = true;
    }
    return &mTextures;
}

// ---------------------------------------------------------------------------------------------
// Single passes on given inputs

Result<void> GpuRuntime::uploadFlux(std::span<const glm::vec3> flux, gpu::Buffer& buffer) {
    std::vector<glm::vec4> padded(flux.size());
    for (size_t i = 0; i < flux.size(); ++i) padded[i] = glm::vec4(flux[i], 0.0f);
    return mContext->upload(buffer, padded.data(), padded.size() * sizeof(glm::vec4));
}

Result<std::vector<glm::vec3>> GpuRuntime::downloadFlux(const gpu::Buffer& buffer, size_t count) {
    std::vector<glm::vec4> padded(count);
    PIC_TRY(mContext->download(buffer, padded.data(), count * sizeof(glm::vec4)));
    std::vector<glm::vec3> flux(count);
    for (size_t i = 0; i < count; ++i) flux[i] = glm::vec3(padded[i]);
    return flux;
}

Result<void> GpuRuntime::uploadCaches(const CacheValues& values) {
    PIC_CHECK(values.bandsY == mValues.bandsY && values.bandsC == mValues.bandsC &&
              values.cacheCount() == mBake.caches.size());
    const auto put = [&](const std::vector<float>& v, gpu::Buffer& buffer) -> Result<void> {
        std::vector<uint16_t> halves(v.size());
        for (size_t i = 0; i < v.size(); ++i) halves[i] = floatToHalf(v[i]);
        if (halves.empty()) return {};
        return mContext->upload(buffer, halves.data(), halves.size() * sizeof(uint16_t));
    };
    PIC_TRY(put(values.y, mCacheY));
    PIC_TRY(put(values.co, mCacheCo));
    PIC_TRY(put(values.cg, mCacheCg));
    if (values.irradiance.empty()) return {};
    return uploadFlux(values.irradiance, mCacheIrradiance);
}

void GpuRuntime::recordCacheReadback(VkCommandBuffer cmd) {
    if (!mCacheReadback.handle()) return;
    // The cache lighting's writes are done before the copy reads them.
    gpu::computeBarrier(cmd);
    VkDeviceSize offset = 0;
    for (const gpu::Buffer* buffer : {&mCacheY, &mCacheCo, &mCacheCg}) {
        const VkBufferCopy region{0, offset, buffer->size()};
        vkCmdCopyBuffer(cmd, buffer->handle(), mCacheReadback.handle(), 1, &region);
        offset += buffer->size();
    }
}

void GpuRuntime::readCaches(CacheValues& values) const {
    const char* readback = static_cast<const char*>(mCacheReadback.mapped());
    const auto get = [&](const gpu::Buffer& buffer, std::vector<float>& v) {
        const auto* halves = static_cast<const uint16_t*>(readback ? readback : buffer.mapped());
        for (size_t i = 0; i < v.size(); ++i) v[i] = halfToFloat(halves[i]);
        if (readback) readback += buffer.size();
    };
    get(mCacheY, values.y);
    get(mCacheCo, values.co);
    get(mCacheCg, values.cg);
}

Result<std::vector<glm::vec3>> GpuRuntime::runDirect(const LightSet& lights,
                                                     UpdateStats* statsOut) {
    UpdateStats local;
    UpdateStats& stats = statsOut ? *statsOut : local;
    stats = UpdateStats{};
    PIC_TRY(prepareLights(lights));
    PIC_TRY(submitTimed(
        [&](VkCommandBuffer cmd) {
            recordShadowMaps(cmd);
            mTimer.begin(cmd, "surfel_lighting");
            mSurfels->record(cmd, {.lightCount = uint32_t(lights.lights.size()), .sumSlot = 0});
        },
        stats));
    addVisibilityStats(stats);
    return downloadFlux(mSurfels->directFlux(), mBake.surfels.size());
}

Result<std::vector<glm::vec3>> GpuRuntime::runBounce(std::span<const glm::vec3> direct,
                                                     const CacheValues& previous) {
    PIC_CHECK_EQ(direct.size(), mBake.surfels.size());
    PIC_CHECK_EQ(previous.irradiance.size(), mBake.caches.size());
    PIC_TRY(uploadFlux(direct, const_cast<gpu::Buffer&>(mSurfels->directFlux())));
    PIC_TRY(uploadCaches(previous));
    PIC_TRY(
        mContext->submit([&](VkCommandBuffer cmd) { mSurfels->record(cmd, {.bounce = true}); }));
    return downloadFlux(mNodeFlux, mBake.surfels.size());
}

Result<std::vector<glm::vec3>> GpuRuntime::runPull(std::span<const glm::vec3> leaves) {
    PIC_CHECK_EQ(leaves.size(), mBake.surfels.size());
    std::vector<glm::vec3> nodes(mBake.nodes.size(), glm::vec3(0.0f));
    std::copy(leaves.begin(), leaves.end(), nodes.begin());
    PIC_TRY(uploadFlux(nodes, mNodeFlux));
    PIC_TRY(mContext->submit([&](VkCommandBuffer cmd) { mPull->record(cmd, {}); }));
    return downloadFlux(mNodeFlux, mBake.nodes.size());
}

Result<std::vector<glm::uvec4>> GpuRuntime::nodeLight() {
    std::vector<glm::uvec4> packed(mBake.nodes.size());
    PIC_TRY(mContext->download(mNodeLight, packed.data(), packed.size() * sizeof(glm::uvec4)));
    return packed;
}

std::vector<glm::uvec4> packNodeLight(const BakeData& bake, std::span<const glm::vec3> nodeFlux) {
    PIC_CHECK_EQ(nodeFlux.size(), bake.nodes.size());
    std::vector<glm::mat3> moment(nodeFlux.size()), slopes(nodeFlux.size());
    std::vector<glm::vec3> centre(nodeFlux.size()), concentration(nodeFlux.size());
    std::vector<uint8_t> exponential(nodeFlux.size());
    pullFluxSpread(bake, nodeSpread(bake), nodeFlux, moment, centre, slopes, concentration,
                   exponential);
    std::vector<glm::uvec4> light(nodeFlux.size());
    for (size_t n = 0; n < nodeFlux.size(); ++n)
        light[n] = glm::uvec4(gpu::packNodeSpread(slopes[n], concentration[n], exponential[n] != 0),
                              packRgbe8(centre[n] * gpu::radianceScale(bake.nodes[n].area)));
    return light;
}

Result<CacheValues> GpuRuntime::runCacheLighting(std::span<const glm::vec3> nodeFlux) {
    return runCacheLighting(packNodeLight(mBake, nodeFlux));
}

Result<CacheValues> GpuRuntime::runCacheLighting(std::span<const glm::uvec4> nodeLight) {
    PIC_CHECK_EQ(nodeLight.size(), mBake.nodes.size());
    PIC_TRY(mContext->upload(mNodeLight, nodeLight.data(), nodeLight.size_bytes()));
    PIC_TRY(mContext->submit([&](VkCommandBuffer cmd) {
        mCacheLighting->record(cmd, {});
        recordCacheReadback(cmd);
    }));
    CacheValues values = CacheValues::zeros(mBake.caches.size(), mValues.bandsY, mValues.bandsC);
    readCaches(values);
    PIC_TRY_ASSIGN(values.irradiance, downloadFlux(mCacheIrradiance, mBake.caches.size()));
    return values;
}

Result<CacheTextures> GpuRuntime::runLightmapCopy(const CacheValues& values) {
    PIC_TRY_ASSIGN(gpu::LightmapCopyPass * pass, lightmapCopyPass());
    PIC_TRY(uploadCaches(values));
    PIC_TRY(mContext->submit([&](VkCommandBuffer cmd) { pass->record(cmd, {}); }));
    CacheTextures textures = makeCacheTextures(mBake);
    PIC_TRY(pass->read(*mContext, textures));
    mTexturesCurrent = false;
    return textures;
}

Result<CacheValues> GpuRuntime::runSkyCaches(const CacheValues& values,
                                             const SkyCacheWeights& weights) {
    if (!mSkyCaches)
        return fail(ErrorCode::InvalidInput,
                    "the bake has no sky transfer (baked with --sky-rays 0)");
    PIC_TRY(uploadCaches(values));
    PIC_TRY(mSkyCaches->setWeights(weights));
    PIC_TRY(mContext->submit([&](VkCommandBuffer cmd) {
        mSkyCaches->record(cmd, {});
        gpu::computeBarrier(cmd);
        recordCacheReadback(cmd);
    }));
    CacheValues out = CacheValues::zeros(mBake.caches.size(), mValues.bandsY, mValues.bandsC);
    readCaches(out);
    mTexturesCurrent = false;
    return out;
}

std::vector<std::pair<std::string, uint64_t>> GpuRuntime::memory() const {
    return {
        {"links", mCacheLighting->bytes()},
        {"sky", mSkyCaches ? mSkyCaches->bytes() : 0},
        {"surfels", mSurfels->bytes()},
        {"pull_nodes", mPull->bytes()},
        {"node_flux", mNodeFlux.size()},
        {"node_light", mNodeLight.size()},
        {"caches", mCacheY.size() + mCacheCo.size() + mCacheCg.size()},
        {"textures", mLightmapCopy ? mLightmapCopy->bytes() : 0},
        mShadows ? std::pair<std::string, uint64_t>{"shadow_maps", mShadows->bytes()}
                 : std::pair<std::string, uint64_t>{"visibility", mRayVisibility->bytes()},
    };
}

uint64_t GpuRuntime::linkBytesPerBounce() const {
    return mCacheLighting->linkBytes();
}

uint32_t GpuRuntime::linkTexelWords() const {
    return mCacheLighting->texelWords();
}

}  // namespace pic
