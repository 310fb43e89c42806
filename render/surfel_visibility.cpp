#include "render/surfel_visibility.h"

#include <algorithm>

#include "core/error.h"
#include "core/geometry.h"
#include "core/parallel.h"

namespace pic {
namespace {

/// Surfels per task: a surfel costs one shadow ray per light or per stencil entry.
constexpr size_t kSurfelGrain = 256;

/// A light-map cache lies on a surfel's own surface where their normals are within 25°: its
/// irradiance along its normal is then what the surfel receives (surfelStencils).
constexpr float kSameSurfaceCos = 0.9f;

}  // namespace

glm::vec3 visibleIrradiance(const EmbreeScene& rays, const Surfel& surfel, const Light& light) {
    glm::vec3 toLight;
    float distance = 0.0f;
    const glm::vec3 e = lightIrradiance(light, surfel.position, surfel.normal, toLight, distance);
    if (!(e.r > 0.0f || e.g > 0.0f || e.b > 0.0f)) return glm::vec3(0.0f);
    const float epsilon = rays.epsilon();
    const glm::vec3 origin = surfel.position + epsilon * surfel.normal;
    return rays.occluded(origin, toLight, 0.0f, distance - epsilon) ? glm::vec3(0.0f) : e;
}

void surfelVisibility(const EmbreeScene& rays, const BakeData& bake, const Light& light,
                      std::span<uint32_t> bits) {
    const size_t nS = bake.surfels.size();
    PIC_CHECK_EQ(bits.size(), visibilityWords(nS));
    // White and of unit strength: where E > 0 for it, E > 0 for any colour and intensity.
    Light unit = light;
    unit.color = glm::vec3(1.0f);
    unit.intensity = 1.0f;
    // A task per word, so that no two tasks write one word.
    parallelFor(
        0, bits.size(),
        [&](size_t word) {
            uint32_t mask = 0;
            const size_t end = std::min(nS, 32 * word + 32);
            for (size_t i = 32 * word; i < end; ++i) {
                const glm::vec3 e = visibleIrradiance(rays, bake.surfels[i], unit);
                if (e.r > 0.0f) mask |= 1u << (i - 32 * word);
            }
            bits[word] = mask;
        },
        kSurfelGrain / 32);
}

std::vector<CacheStencil> surfelStencils(const Scene& scene, const EmbreeScene& rays,
                                         const BakeData& bake) {
    std::vector<CacheStencil> stencils(bake.surfels.size());
    const float offset = 4.0f * rays.epsilon();
    parallelFor(0, bake.surfels.size(), [&](size_t i) {
        const Surfel& surfel = bake.surfels[i];
        PIC_DCHECK(surfel.triangle < scene.triangles.size());
        const Triangle& triangle = scene.triangles[surfel.triangle];
        const glm::vec3 b = barycentric(surfel.position, scene.vertices[triangle.v[0]].position,
                                        scene.vertices[triangle.v[1]].position,
                                        scene.vertices[triangle.v[2]].position);
        const CacheStencil all = surfaceStencil(bake, surfel.triangle, b.y, b.z, surfel.position);
        const glm::vec3 origin = surfel.position + offset * surfel.normal;
        CacheStencil seen;
        float total = 0.0f;
        for (int k = 0; k < all.count; ++k) {
            const Cache& cache = bake.caches[all.cache[k]];
            const glm::vec3 v = cache.position + offset * cache.normal - origin;
            const float d = glm::length(v);
            if (d > 2.0f * offset && rays.occluded(origin, v / d, 0.0f, d - offset)) continue;
            seen.cache[seen.count] = all.cache[k];
            seen.weight[seen.count] = all.weight[k];
            total += all.weight[k];
            ++seen.count;
        }
        CacheStencil& out = stencils[i];
        if (seen.count == all.count || seen.count == 0 || !(total > 0.0f)) {
            out = all;
        } else {
            for (int k = 0; k < seen.count; ++k) seen.weight[k] /= total;
            out = seen;
        }
        for (int k = 0; k < out.count; ++k) {
            const Cache& cache = bake.caches[out.cache[k]];
            if (cache.kind == gpu::kCacheKindLightmap &&
                glm::dot(cache.normal, surfel.normal) >= kSameSurfaceCos)
                out.alongNormal |= uint8_t(1u << k);
        }
    }, kSurfelGrain / 4);
    return stencils;
}

}  // namespace pic
