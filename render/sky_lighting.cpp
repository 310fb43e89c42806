#include "render/sky_lighting.h"

namespace pic {

Result<void> checkSkyLights(const LightSet& lights, const Scene& scene, const BakeData& bake) {
    if (!lights.sky) return {};
    if (bake.params.skyRays == 0 || bake.surfelSky.empty())
        return fail(ErrorCode::InvalidInput,
                    "the light set holds sky \"{}\" but the bake has no sky transfer (baked with "
                    "--sky-rays 0); bake again with --sky-rays N",
                    clipped(lights.sky->id));
    PIC_TRY(resolveSky(*lights.sky, scene.sourcePath));
    return {};
}

Result<const SkyLighting*> SkyState::update(const LightSet& lights) {
    if (!lights.sky) return nullptr;
    if (mSky != lights.sky) {
        PIC_TRY(checkSkyLights(lights, mScene, mBake));
        PIC_TRY_ASSIGN(const Sky sky, resolveSky(*lights.sky, mScene.sourcePath));
        mSky.reset();
        mLighting.sh = sky.project();
        mLighting.caches = skyCacheWeights(mLighting.sh, int(mBake.params.bandsY),
                                           int(mBake.params.bandsC));
        mSky = lights.sky;
    }
    return &mLighting;
}

}  // namespace pic
