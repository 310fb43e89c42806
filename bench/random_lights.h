#pragma once
/// Seeded random light sets for a scene: what the stability suite relights scenes with to
/// check that no light set produces NaN, infinite or negative radiance, and what accuracy can
/// be checked under, with lights nobody tuned the bake for.

#include <cstdint>

#include "core/error.h"
#include "core/light_set.h"
#include "core/scene.h"

namespace pic {

/// The ranges randomLightSet draws from (the scene's bounding box sets the lengths).
struct RandomLightRanges {
    uint32_t minLights = 1;
    uint32_t maxLights = 4;
    /// Point and spot intensity I [W/sr] is log-uniform in [minIntensity, maxIntensity] × (d/5 m)²
    /// for the scene's diagonal d: a lamp in a 5 m room gives 0.1–100 W/sr.
    float minIntensity = 0.1f;
    float maxIntensity = 100.0f;
    /// Directional irradiance E [W/m²], log-uniform.
    float minIrradiance = 0.1f;
    float maxIrradiance = 10.0f;
    /// Spot outer half-angles, uniform in degrees; the inner one is uniform in [0, outer].
    float minOuterConeDegrees = 2.0f;
    float maxOuterConeDegrees = 80.0f;
    /// Share of lights with a finite range (uniform in [0.1, 1] × d), and of saturated colours
    /// (one or two channels exactly 0).
    float rangedShare = 0.2f;
    float saturatedShare = 0.25f;
    /// Emissive materials' scales: 0 with probability zeroEmissionShare, else log-uniform in
    /// [minEmissiveScale, maxEmissiveScale].
    float zeroEmissionShare = 0.1f;
    float minEmissiveScale = 0.01f;
    float maxEmissiveScale = 10.0f;
};

/// A light set drawn from `seed` alone (the same seed gives the same set on every machine):
/// minLights to maxLights lights (uniform), each point, spot or directional with probability
/// 1/3; point and spot positions uniform in the scene's bounding box shrunk by 2 % per side
/// (inside furniture or outside a room is allowed: lights go there too), directions uniform on
/// the sphere, colours uniform per channel in [0.05, 1] (or saturated), intensities, cone
/// angles and ranges as `ranges` says; every material with emission gets a random emissive
/// scale. Ids are "random_0", "random_1", …. The set passes checkLightSet for `scene`.
/// InvalidInput when the scene has no extent or the ranges are empty, reversed or negative.
Result<LightSet> randomLightSet(const Scene& scene, uint64_t seed,
                                const RandomLightRanges& ranges = {});

}  // namespace pic
