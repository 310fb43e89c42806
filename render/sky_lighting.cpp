#include "render/sky_lighting.h"

namespace pic {
namespace {

/// The sky of `sky` for `bake`, resolved next to the scene: refused when the bake has no sky
/// transfer.
Result<Sky> bakeSky(const SkyLight& sky, const Scene& scene, const BakeData& bake) {
    if (bake.params.skyRays == 0 || bake.surfelSky.empty())
        return fail(ErrorCode::InvalidInput,
                    "the light set holds sky \"{}\" but the bake has no sky transfer (baked with "
                    "--sky-rays 0); bake again with --sky-rays N",
                    clipped(sky.id));
    return resolveSky(sky, scene.sourcePath);
}

}  // namespace

Result<void> checkSkyLights(const LightSet& lights, const Scene& scene, const BakeData& bake) {
    if (!lights.sky) return {};
    PIC_TRY(bakeSky(*lights.sky, scene, bake));
    return {};
}

Result<const SkyLighting*> SkyState::update(const LightSet& lights) {
    if (!lights.sky) return nullptr;
    if (mSky != lights.sky) {
        mSky.reset();
        PIC_TRY_ASSIGN(const Sky sky, bakeSky(*lights.sky, mScene, mBake));
        mLighting.sh = sky.project();
        mLighting.caches = skyCacheWeights(mLighting.sh, int(mBake.params.bandsY),
                                           int(mBake.params.bandsC));
        mSky = lights.sky;
    }
    return &mLighting;
}

}  // namespace pic
