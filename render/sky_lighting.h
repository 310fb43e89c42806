#pragma once
/// The sky of a light set as both runtime backends relight with it (core/sky.h): its radiance
/// SH, which surfel lighting multiplies with each surfel's sky transfer, and the same folded
/// for the caches (SkyCacheWeights), which the sky_caches pass multiplies with each cache's
/// sky visibility after the last bounce.

#include <array>
#include <optional>

#include <glm/glm.hpp>

#include "core/bake_data.h"
#include "core/error.h"
#include "core/light_set.h"
#include "core/scene.h"
#include "core/sky.h"

namespace pic {

struct SkyLighting {
    std::array<glm::vec3, kSkyCoefficients> sh{};  ///< RGB radiance SH, W/(m²·sr)
    SkyCacheWeights caches;
};

/// InvalidInput when `lights` holds a sky and `bake` has no sky transfer (baked with
/// --sky-rays 0); the environment's errors (core/sky.h loadEnvironment) when it cannot be read.
Result<void> checkSkyLights(const LightSet& lights, const Scene& scene, const BakeData& bake);

/// The sky lighting of successive light sets, recomputed only when the sky changes (an
/// environment's projection reads every texel).
class SkyState {
public:
    SkyState(const Scene& scene, const BakeData& bake) : mScene(scene), mBake(bake) {}
    /// The sky of `lights`, or null when it holds none.
    Result<const SkyLighting*> update(const LightSet& lights);

private:
    const Scene& mScene;
    const BakeData& mBake;
    std::optional<SkyLight> mSky;  ///< the sky mLighting was made for
    SkyLighting mLighting;
};

}  // namespace pic
