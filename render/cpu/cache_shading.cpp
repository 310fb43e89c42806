#include "render/cpu/cache_shading.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <vector>

#include "core/camera.h"
#include "core/parallel.h"
#include "core/sh.h"

namespace pic {
namespace {

constexpr float kInvPi = std::numbers::inv_pi_v<float>;

/// Checks that `indices` only name caches below `caches` (or kNoCache).
Result<void> checkCacheIndices(const std::vector<uint32_t>& indices, size_t caches,
                               const char* what) {
    for (size_t i = 0; i < indices.size(); ++i)
        if (indices[i] != kNoCache && indices[i] >= caches)
            return fail(ErrorCode::InvalidInput,
                        "{} entry {} names cache {}, but the cache values hold {} caches", what, i,
                        indices[i], caches);
    return {};
}

/// Rejects parameters, bakes and cache values that shading cannot index safely.
Result<void> validate(const Scene& scene, const BakeData& bake, const CacheValues& values,
                      const ShadeParams& params) {
    PIC_TRY(checkShadeParams(params));
    if (bake.sceneHash != scene.hash)
        return fail(ErrorCode::InvalidInput,
                    "the bake was made for a different scene (hash {:016x}, scene {:016x})",
                    bake.sceneHash, scene.hash);

    const size_t caches = bake.caches.size();
    const size_t countY = size_t{values.bandsY} * values.bandsY;
    const size_t countC = size_t{values.bandsC} * values.bandsC;
    if (values.bandsY < 1 || values.bandsY > uint32_t(kMaxShBands) || values.bandsC > values.bandsY)
        return fail(ErrorCode::InvalidInput,
                    "cache values have bands y {} c {} (need 1 ≤ c ≤ y ≤ {})", values.bandsY,
                    values.bandsC, kMaxShBands);
    if (values.y.size() != caches * countY || values.co.size() != caches * countC ||
        values.cg.size() != caches * countC)
        return fail(ErrorCode::InvalidInput,
                    "cache values hold {} Y, {} Co, {} Cg coefficients; the bake's {} caches with "
                    "bands y {} c {} need {}, {}, {}",
                    values.y.size(), values.co.size(), values.cg.size(), caches, values.bandsY,
                    values.bandsC, caches * countY, caches * countC, caches * countC);

    const LightmapLayout& map = bake.lightmap;
    if (map.triangleUvs.size() != 3 * scene.triangles.size())
        return fail(ErrorCode::InvalidInput,
                    "the bake has light-map UVs for {} triangles, the scene has {} triangles",
                    map.triangleUvs.size() / 3, scene.triangles.size());
    if (map.cacheIndex.size() != size_t{map.width} * map.height)
        return fail(ErrorCode::InvalidInput, "light map {}x{} has {} texel entries", map.width,
                    map.height, map.cacheIndex.size());
    const GridLayout& grid = bake.grid;
    if (grid.cacheIndex.size() != size_t{grid.dims.x} * grid.dims.y * grid.dims.z)
        return fail(ErrorCode::InvalidInput, "grid {}x{}x{} has {} vertex entries", grid.dims.x,
                    grid.dims.y, grid.dims.z, grid.cacheIndex.size());
    if (auto ok = checkCacheIndices(map.cacheIndex, caches, "light-map texel"); !ok) return ok;
    return checkCacheIndices(grid.cacheIndex, caches, "grid vertex");
}

/// Everything one pixel's shading reads, resolved once per image.
struct ShadingContext {
    const Scene& scene;
    const EmbreeScene& rays;
    const BakeData& bake;
    const CacheValues& values;
    const LightSet& lights;
    const ShadeParams& params;
    const CameraRays& cameraRays;
    /// Texture footprints are a subsample's share of the pixel: 1/√n of its sides for n
    /// subsamples, so that the filter and the subsample average do not both blur by a pixel.
    float footprintScale;
    std::vector<float> emissiveScale;  // per material: the light set's scale
};

/// Radiance arriving at the camera along one primary ray.
glm::vec3 shadeRay(const ShadingContext& context, const glm::vec3& origin,
                   const glm::vec3& direction) {
    const std::optional<RayHit> hit =
        context.rays.intersect(origin, direction, 0.0f, std::numeric_limits<float>::infinity());
    if (!hit) return glm::vec3(0.0f);

    const ShadeParams& params = context.params;
    const glm::vec3 position = origin + hit->t * direction;
    // Both faces reflect: shade the side the camera sees.
    const glm::vec3 normal = hit->backFace ? -hit->geometricNormal : hit->geometricNormal;
    // Base-colour textures averaged over the subsample's footprint on the hit's plane, as the
    // G-buffer pass averages them over its pixel's (shaders/gbuffer.frag).
    const PixelFootprint footprint =
        context.cameraRays.footprintOnPlane(position, hit->geometricNormal);
    const glm::vec3 albedo = context.scene.albedoOverFootprint(
        hit->triangle, hit->b1, hit->b2, context.footprintScale * footprint.dPdx,
        context.footprintScale * footprint.dPdy);
    glm::vec3 radiance(0.0f);

    if (params.component == ShadeComponent::Full && !hit->backFace) {
        const uint32_t material = context.scene.triangles[hit->triangle].material;
        radiance += context.emissiveScale[material] *
                    context.scene.emissionAt(hit->triangle, hit->b1, hit->b2);
    }

    if (params.component == ShadeComponent::Full || params.component == ShadeComponent::Direct) {
        const float epsilon = context.rays.epsilon();
        // Shadow rays start just above the surface so that they do not hit its own triangle.
        const glm::vec3 shadowOrigin = position + epsilon * normal;
        glm::vec3 irradianceDirect(0.0f);
        for (const Light& light : context.lights.lights) {
            glm::vec3 toLight;
            float distance = 0.0f;
            const glm::vec3 e = lightIrradiance(light, position, normal, toLight, distance);
            // Points facing away from the light or outside its cone or range cast no ray.
            if (!(e.r > 0.0f || e.g > 0.0f || e.b > 0.0f)) continue;
            if (context.rays.occluded(shadowOrigin, toLight, 0.0f, distance - epsilon)) continue;
            irradianceDirect += e;
        }
        radiance += albedo * kInvPi * irradianceDirect;
    }

    if (params.component != ShadeComponent::Direct) {
        RadianceSh incident = lookupSurfaceRadiance(context.bake, context.values, hit->triangle,
                                                    hit->b1, hit->b2, position);
        const IndirectScale& scale = context.lights.indirectScale;
        if (scale != IndirectScale{}) scaleLumaChroma(incident, scale.y, scale.cocg);
        // A truncated SH expansion rings: on the dark side of a bright cache its clamped-cosine
        // convolution can dip below zero. Irradiance never does, so each channel is cut at 0.
        if (params.component != ShadeComponent::Glossy) {
            const glm::vec3 e = glm::max(irradiance(incident, normal), glm::vec3(0.0f));
            radiance += albedo * kInvPi * e;
        }
        if (params.glossyExponent > 0.0f && params.glossyWeight > 0.0f) {
            // The lobe is centred on the mirror direction of the view ray; its average incident
            // radiance is clamped like the irradiance, for the same ringing.
            const glm::vec3 mirror = glm::reflect(direction, normal);
            for (int c = 0; c < 3; ++c)
                radiance[c] += params.glossyWeight *
                               std::max(0.0f, shGlossy(int(incident.bands), incident.rgb[c], mirror,
                                                       params.glossyExponent));
        }
    }
    return radiance;
}

}  // namespace

Result<Image> shadeFromCaches(const Scene& scene, const EmbreeScene& rays, const BakeData& bake,
                              const CacheValues& values, const LightSet& lights,
                              const Camera& camera, const ShadeParams& params) {
    if (auto ok = validate(scene, bake, values, params); !ok) return std::unexpected(ok.error());

    const CameraRays cameraRays(camera, params.width, params.height);
    const uint32_t n = params.samplesPerPixel;
    ShadingContext context{
        scene, rays, bake, values, lights, params, cameraRays, 1.0f / std::sqrt(float(n)), {}};
    // The light set scales emission per material name; resolve the names once, not per pixel.
    context.emissiveScale.resize(scene.materials.size());
    for (size_t m = 0; m < scene.materials.size(); ++m)
        context.emissiveScale[m] = lights.emissiveScaleOf(scene.materials[m].name);

    std::vector<glm::vec2> offsets(n);
    for (uint32_t s = 0; s < n; ++s) offsets[s] = subsampleOffset(s, n);

    Image image(params.width, params.height);
    // One row per task: each writes only its own pixels, so the image is the same on any
    // number of threads.
    parallelFor(
        0, params.height,
        [&](size_t row) {
            const uint32_t y = uint32_t(row);
            for (uint32_t x = 0; x < params.width; ++x) {
                glm::vec3 sum(0.0f);
                for (const glm::vec2& offset : offsets) {
                    const glm::vec3 direction =
                        cameraRays.direction(float(x) + offset.x, float(y) + offset.y);
                    sum += shadeRay(context, cameraRays.origin(), direction);
                }
                image.at(x, y) = sum / float(n);
            }
        },
        1);
    return image;
}

}  // namespace pic
