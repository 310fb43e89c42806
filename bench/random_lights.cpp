#include "bench/random_lights.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "core/sampling.h"

namespace pic {

namespace {

/// Log-uniform number in [lo, hi] (lo > 0).
float logUniform(Rng& rng, float lo, float hi) {
    return lo * std::pow(hi / lo, rng.uniform());
}

/// Uniform direction on the sphere.
glm::vec3 randomDirection(Rng& rng) {
    const float u1 = rng.uniform();
    return sampleUniformSphere(u1, rng.uniform());
}

/// A colour with channels in [0.05, 1], or with probability `saturatedShare` one whose
/// channels are each 0 or 1 with at least one 1 (pure red, green, blue and their mixtures).
glm::vec3 randomColor(Rng& rng, float saturatedShare) {
    if (rng.uniform() < saturatedShare) {
        // 1..6 as a 3-bit mask: never black, never white.
        const uint32_t mask = 1u + std::min(5u, uint32_t(rng.uniform() * 6.0f));
        return {float(mask & 1u), float((mask >> 1) & 1u), float((mask >> 2) & 1u)};
    }
    glm::vec3 color;
    for (int c = 0; c < 3; ++c) color[c] = 0.05f + 0.95f * rng.uniform();
    return color;
}

Result<void> checkRanges(const RandomLightRanges& r) {
    if (r.minLights < 1 || r.minLights > r.maxLights || r.maxLights > kMaxLights)
        return fail(ErrorCode::InvalidInput,
                    "random lights: need 1 ≤ minLights ≤ maxLights ≤ {}, got {} and {}", kMaxLights,
                    r.minLights, r.maxLights);
    const auto positiveRange = [](const char* name, float lo, float hi) -> Result<void> {
        if (!(lo > 0.0f) || !(hi >= lo) || !std::isfinite(hi))
            return fail(ErrorCode::InvalidInput,
                        "random lights: {} needs 0 < min ≤ max < ∞, got {} and {}", name, lo, hi);
        return {};
    };
    PIC_TRY(positiveRange("intensity", r.minIntensity, r.maxIntensity));
    PIC_TRY(positiveRange("irradiance", r.minIrradiance, r.maxIrradiance));
    PIC_TRY(positiveRange("emissive scale", r.minEmissiveScale, r.maxEmissiveScale));
    if (!(r.minOuterConeDegrees > 0.0f) || !(r.maxOuterConeDegrees >= r.minOuterConeDegrees) ||
        !(r.maxOuterConeDegrees <= 90.0f))
        return fail(
            ErrorCode::InvalidInput,
            "random lights: outer cone angles need 0 < min ≤ max ≤ 90 degrees, got {} and {}",
            r.minOuterConeDegrees, r.maxOuterConeDegrees);
    for (const auto& [name, share] :
         {std::pair{"rangedShare", r.rangedShare}, std::pair{"saturatedShare", r.saturatedShare},
          std::pair{"zeroEmissionShare", r.zeroEmissionShare}})
        if (!(share >= 0.0f && share <= 1.0f))
            return fail(ErrorCode::InvalidInput, "random lights: {} must be in [0, 1], got {}",
                        name, share);
    return {};
}

}  // namespace

Result<LightSet> randomLightSet(const Scene& scene, uint64_t seed,
                                const RandomLightRanges& ranges) {
    PIC_TRY(checkRanges(ranges));
    const float diagonal = scene.bounds.diagonal();
    if (!(diagonal > 0.0f) || !std::isfinite(diagonal))
        return fail(ErrorCode::InvalidInput,
                    "random lights: scene '{}' has no extent (diagonal {} m)", scene.sourcePath,
                    diagonal);
    // One stream per seed; the draws below happen in a fixed order.
    Rng rng(seed, 0x6c69676874736574ull);
    const glm::vec3 margin = 0.02f * scene.bounds.extent();
    const glm::vec3 lo = scene.bounds.min + margin;
    const glm::vec3 size = scene.bounds.extent() - 2.0f * margin;
    const float areaScale = (diagonal / 5.0f) * (diagonal / 5.0f);
    const float degrees = std::numbers::pi_v<float> / 180.0f;

    LightSet set;
    const uint32_t span = ranges.maxLights - ranges.minLights + 1;
    const uint32_t count =
        ranges.minLights + std::min(span - 1, uint32_t(rng.uniform() * float(span)));
    for (uint32_t k = 0; k < count; ++k) {
        Light light;
        light.id = "random_" + std::to_string(k);
        const float kind = rng.uniform();
        light.type = kind < 1.0f / 3.0f   ? LightType::Point
                     : kind < 2.0f / 3.0f ? LightType::Spot
                                          : LightType::Directional;
        const glm::vec3 at(rng.uniform(), rng.uniform(), rng.uniform());
        light.position = lo + at * size;
        light.direction = randomDirection(rng);
        light.color = randomColor(rng, ranges.saturatedShare);
        const float intensity =
            logUniform(rng, ranges.minIntensity, ranges.maxIntensity) * areaScale;
        const float irradiance = logUniform(rng, ranges.minIrradiance, ranges.maxIrradiance);
        light.intensity = light.type == LightType::Directional ? irradiance : intensity;
        const float outer =
            ranges.minOuterConeDegrees +
            (ranges.maxOuterConeDegrees - ranges.minOuterConeDegrees) * rng.uniform();
        const float inner = outer * rng.uniform();
        if (light.type == LightType::Spot) {
            light.outerConeAngle = outer * degrees;
            light.innerConeAngle = std::min(inner * degrees, light.outerConeAngle);
        }
        const bool ranged = rng.uniform() < ranges.rangedShare;
        const float range = (0.1f + 0.9f * rng.uniform()) * diagonal;
        if (ranged && light.type != LightType::Directional) light.range = range;
        if (light.type == LightType::Directional) light.position = glm::vec3(0.0f);
        set.lights.push_back(std::move(light));
    }
    // Every emissive material, in material order, gets a scale (names can repeat: the first
    // one drawn for a name stays).
    for (const Material& material : scene.materials) {
        if (material.emission == glm::vec3(0.0f)) continue;
        const bool dark = rng.uniform() < ranges.zeroEmissionShare;
        const float scale = logUniform(rng, ranges.minEmissiveScale, ranges.maxEmissiveScale);
        set.emissiveScale.emplace(material.name, dark ? 0.0f : scale);
    }
    PIC_TRY(checkLightSet(set, scene));
    return set;
}

}  // namespace pic
