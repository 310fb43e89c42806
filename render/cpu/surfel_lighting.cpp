#include "render/cpu/surfel_lighting.h"

#include <numbers>
#include <vector>

#include "core/error.h"
#include "core/parallel.h"
#include "render/surfel_visibility.h"

namespace pic {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

/// Surfels per task: a surfel costs one shadow ray per light or one cache lookup.
constexpr size_t kSurfelGrain = 256;

}  // namespace

void directSurfelFlux(const Scene& scene, const EmbreeScene& rays, const BakeData& bake,
                      const LightSet& lights, std::span<glm::vec3> directFlux,
                      const std::array<glm::vec3, kSkyCoefficients>* skySh) {
    PIC_CHECK_EQ(directFlux.size(), bake.surfels.size());
    PIC_CHECK(!skySh || bake.surfelSky.size() == bake.surfels.size() * kSkyCoefficients);
    // The light set scales emission per material name; resolve the names once, not per surfel.
    std::vector<float> emissiveScale(scene.materials.size());
    for (size_t m = 0; m < scene.materials.size(); ++m)
        emissiveScale[m] = lights.emissiveScaleOf(scene.materials[m].name);

    parallelFor(0, bake.surfels.size(), [&](size_t i) {
        const Surfel& surfel = bake.surfels[i];
        PIC_DCHECK(surfel.material < emissiveScale.size());
        glm::vec3 irradiance(0.0f);
        for (const Light& light : lights.lights)
            irradiance += visibleIrradiance(rays, surfel, light);
        if (skySh) {
            // The sky through the surfel's transfer; SH ringing may dip below zero.
            const float* transfer = &bake.surfelSky[i * kSkyCoefficients];
            glm::vec3 sky(0.0f);
            for (int k = 0; k < kSkyCoefficients; ++k) sky += (*skySh)[k] * transfer[k];
            irradiance += glm::max(sky, glm::vec3(0.0f));
        }
        // Lambertian reflection of the direct light plus the material's own emission, both as
        // flux leaving the disc: B·A with B = ρ·E and B = π·L_e.
        glm::vec3 flux = surfel.albedo * (surfel.area * irradiance);
        flux += (kPi * surfel.area * emissiveScale[surfel.material]) * surfel.emission;
        directFlux[i] = flux;
    }, kSurfelGrain);
}

void bounceSurfelFlux(const BakeData& bake, std::span<const CacheStencil> stencils,
                      std::span<const glm::vec3> directFlux, const CacheValues& previousBounce,
                      std::span<glm::vec3> surfelFlux, glm::vec3 tail) {
    PIC_CHECK_EQ(stencils.size(), bake.surfels.size());
    PIC_CHECK_EQ(directFlux.size(), bake.surfels.size());
    PIC_CHECK_EQ(surfelFlux.size(), bake.surfels.size());
    PIC_CHECK(directFlux.data() != surfelFlux.data());

    const bool alongNormal = !previousBounce.irradiance.empty();
    PIC_CHECK(!alongNormal || previousBounce.irradiance.size() == bake.caches.size());
    parallelFor(0, bake.surfels.size(), [&](size_t i) {
        const Surfel& surfel = bake.surfels[i];
        CacheStencil sh = stencils[i];
        glm::vec3 e(0.0f);
        if (alongNormal && sh.alongNormal) {
            // Caches on the surfel's surface give their irradiance along its normal; the
            // others, if any, their SH at the surfel's normal.
            int kept = 0;
            for (int k = 0; k < sh.count; ++k) {
                if (sh.alongNormal & (1u << k)) {
                    e += sh.weight[k] * previousBounce.irradiance[sh.cache[k]];
                } else {
                    sh.cache[kept] = sh.cache[k];
                    sh.weight[kept++] = sh.weight[k];
                }
            }
            sh.count = kept;
        }
        // Truncated SH ring: the clamped-cosine convolution can dip below zero on the dark
        // side of a bright cache. Irradiance is never negative, and negative flux would carry
        // negative light into the next bounce, so it is cut at zero.
        if (sh.count > 0)
            e += glm::max(irradiance(blendCaches(previousBounce, sh), surfel.normal),
                          glm::vec3(0.0f));
        const glm::vec3 flux = directFlux[i] + surfel.albedo * (surfel.area * e);
        surfelFlux[i] = flux + tail * glm::max(flux - surfelFlux[i], glm::vec3(0.0f));
    }, kSurfelGrain);
}

void lightSurfels(const Scene& scene, const EmbreeScene& rays, const BakeData& bake,
                  const LightSet& lights, const CacheValues* previousBounce,
                  std::span<glm::vec3> surfelFlux) {
    if (!previousBounce) return directSurfelFlux(scene, rays, bake, lights, surfelFlux);
    std::vector<glm::vec3> direct(bake.surfels.size());
    directSurfelFlux(scene, rays, bake, lights, direct);
    bounceSurfelFlux(bake, surfelStencils(scene, rays, bake), direct, *previousBounce, surfelFlux);
}

}  // namespace pic
