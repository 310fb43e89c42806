#include "render/cpu_runtime.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <span>
#include <vector>

#include "core/cache_textures.h"
#include "core/color.h"
#include "core/sh.h"
#include "render/cpu/cache_lighting.h"
#include "render/cpu/pull.h"
#include "render/cpu/sky_caches.h"
#include "render/cpu/surfel_lighting.h"
#include "render/node_spread.h"
#include "render/sky_lighting.h"
#include "render/surfel_visibility.h"

namespace pic {
namespace {

using Clock = std::chrono::steady_clock;

double millisecondsSince(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

/// The summed flux (W, RGB); summed in double so that 10⁵ small terms keep their digits, and
/// in index order so that the result does not depend on threads.
glm::dvec3 totalFlux(std::span<const glm::vec3> flux) {
    glm::dvec3 sum(0.0);
    for (const glm::vec3& f : flux) sum += glm::dvec3(f);
    return sum;
}

/// The CPU backend: every pass of paper 000 Figure 2 but shadow maps (visibility comes from
/// Embree rays). Not thread-safe: one update at a time.
class CpuRuntime final : public Runtime {
public:
    CpuRuntime(const Scene& scene, const EmbreeScene& rays, const BakeData& bake,
               const BounceParams& bounces)
        : mScene(scene),
          mRays(rays),
          mBake(bake),
          mBounces(bounces),
          mRatioBound(bounceRatioBound(bake)),
          mDirectFlux(bake.surfels.size()),
          mNodeFlux(bake.nodes.size()),
          mSpread(nodeSpread(bake)),
          mNodeMoment(bake.nodes.size()),
          mCentreFlux(bake.nodes.size()),
          mSlopes(bake.nodes.size()),
          mConcentration(bake.nodes.size()),
          mExponential(bake.nodes.size()),
          mNodeLight(bake.nodes.size()),
          mValues(CacheValues::zeros(bake.caches.size(), bake.params.bandsY, bake.params.bandsC)),
          mStencils(surfelStencils(scene, rays, bake)),
          mSky(scene, bake) {
        // Links' box points, directions and cone factors do not depend on the lights: unpacked
        // once.
        mLinks = unpackLinks(bake, mSpread);
    }

    Result<const CacheValues*> setLights(const LightSet& lights, UpdateStats* stats,
                                         const BounceObserver& observer) override;
    Result<const CacheTextures*> textures() override;
    const char* name() const override { return "cpu"; }

private:
    const Scene& mScene;
    const EmbreeScene& mRays;
    const BakeData& mBake;
    BounceParams mBounces;
    glm::vec3 mRatioBound;  ///< bounceRatioBound of the bake
    LinkTable mLinks;
    std::vector<glm::vec3> mDirectFlux;  ///< nS: flux from lights and emission, per update
    std::vector<glm::vec3> mNodeFlux;  ///< 2nS − 1: leaves hold the current bounce's surfel flux
    NodeSpread mSpread;                ///< fixed per bake
    std::vector<glm::mat3> mNodeMoment;  ///< 2nS − 1: the flux's first moments
    std::vector<glm::vec3> mCentreFlux;  ///< 2nS − 1: the spreads' centre flux
    std::vector<glm::mat3> mSlopes;      ///< 2nS − 1: and their slopes
    std::vector<glm::vec3> mConcentration;  ///< 2nS − 1: ln Z of the exponential ones
    std::vector<uint8_t> mExponential;      ///< 2nS − 1: which are exponential
    std::vector<NodeLight> mNodeLight;   ///< 2nS − 1: both as links read them
    CacheValues mValues;
    std::vector<CacheStencil> mStencils;  ///< nS: the caches each surfel's bounce reads
    SkyState mSky;
    CacheTextures mTextures;              ///< filled on demand from mValues
    bool mTexturesCurrent = false;
};

Result<const CacheValues*> CpuRuntime::setLights(const LightSet& lights, UpdateStats* stats,
                                                 const BounceObserver& observer) {
    PIC_TRY(checkRuntimeLights(lights, mScene));
    PIC_TRY_ASSIGN(const SkyLighting* sky, mSky.update(lights));
    mTexturesCurrent = false;

    const Clock::time_point start = Clock::now();
    UpdateStats local;
    UpdateStats& s = stats ? *stats : local;
    s = UpdateStats{};
    double& surfelMs = s.passMs["surfel_lighting"];
    double& pullMs = s.passMs["pull"];
    double& cacheMs = s.passMs["cache_lighting"];

    BounceSchedule schedule(mBounces, mRatioBound);
    // After the last bounce, the caches take the direct sky (render/cpu/sky_caches.h).
    auto finish = [&]() -> const CacheValues* {
        if (sky) {
            const Clock::time_point t = Clock::now();
            addSkyToCaches(mBake, sky->caches, mValues);
            s.passMs["sky_caches"] += millisecondsSince(t);
        }
        s.totalMs = millisecondsSince(start);
        return &mValues;
    };
    if (schedule.maxPasses() == 0) {
        // No cache pass: the caches hold no light but the sky's and no surfel needs lighting.
        mValues = CacheValues::zeros(mBake.caches.size(), mValues.bandsY, mValues.bandsC);
        return finish();
    }

    const std::span<glm::vec3> leaves(mNodeFlux.data(), mBake.surfels.size());
    Clock::time_point t = Clock::now();
    directSurfelFlux(mScene, mRays, mBake, lights, mDirectFlux, sky ? &sky->sh : nullptr);
    std::copy(mDirectFlux.begin(), mDirectFlux.end(), leaves.begin());
    glm::dvec3 total = totalFlux(leaves);
    schedule.record(total);
    surfelMs += millisecondsSince(t);

    for (int bounce = 1;; ++bounce) {
        t = Clock::now();
        pullFlux(mBake, mNodeFlux);
        pullFluxSpread(mBake, mSpread, mNodeFlux, mNodeMoment, mCentreFlux, mSlopes,
                       mConcentration, mExponential);
        pullMs += millisecondsSince(t);

        t = Clock::now();
        nodeLight(mCentreFlux, mSlopes, mConcentration, mExponential, mNodeLight);
        lightCaches(mBake, mNodeLight, mLinks, mValues);
        cacheMs += millisecondsSince(t);
        s.bounces = bounce;
        s.surfelFlux = luminance(glm::vec3(total));
        const BounceStep step = schedule.afterBounce(bounce);
        if (observer) observer(bounce, mValues, !step.another);
        if (!step.another) break;

        // The next bounce: direct flux plus what the surfels receive from these caches.
        t = Clock::now();
        bounceSurfelFlux(mBake, mStencils, mDirectFlux, mValues, leaves, step.tail);
        total = totalFlux(leaves);
        surfelMs += millisecondsSince(t);
        if (!schedule.record(total)) break;
    }
    return finish();
}

Result<const CacheTextures*> CpuRuntime::textures() {
    if (!mTexturesCurrent) {
        if (mTextures.bandsY == 0) mTextures = makeCacheTextures(mBake);
        copyCachesToTextures(mBake, mValues, mTextures);
        mTexturesCurrent = true;
    }
    return &mTextures;
}

}  // namespace

Result<std::unique_ptr<Runtime>> createCpuRuntime(const Scene& scene, const EmbreeScene& rays,
                                                  const BakeData& bake,
                                                  const BounceParams& bounces) {
    PIC_TRY(checkRuntimeBake(scene, bake));
    PIC_TRY(checkBounceParams(bounces));
    return std::unique_ptr<Runtime>(new CpuRuntime(scene, rays, bake, bounces));
}

}  // namespace pic
