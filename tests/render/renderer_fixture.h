#pragma once
/// What the renderer's tests and the cache-shading pass's tests share: one Vulkan context, the
/// small bake of a test scene with the caches the CPU runtime lights for it, a renderer holding
/// those caches, and the comparison of a rendered image with the CPU twin's
/// (render/cpu/cache_shading.h).

#include <memory>
#include <string>

#include "core/cache_textures.h"
#include "core/cache_values.h"
#include "core/camera.h"
#include "core/image.h"
#include "core/light_set.h"
#include "core/shade_params.h"
#include "rays/embree_scene.h"
#include "render/renderer.h"

namespace pic::test {

/// One Vulkan context for the whole test process, with the validation layer when installed;
/// null (with a test failure) when there is none.
gpu::Context* sharedContext();

/// A test scene with a small bake (2048 surfels, 32 links per cache, grid cell 0.12 and
/// light-map texel 0.04 of the scene's diagonal) and the caches the CPU runtime lights for the
/// scene's own lights.
struct LitScene {
    const Scene& scene;
    const EmbreeScene* rays;
    const BakeData& bake;
    CacheValues values;
    bool ok = false;  ///< all of it made; otherwise the failure was reported to the test
};

/// litScene for test scene `name`, made once per scene for the process.
const LitScene& litScene(const std::string& name);

/// The textures a client receives for `values` of `bake`.
CacheTextures texturesOf(const BakeData& bake, const CacheValues& values);

/// A renderer of `bake`'s layout holding the textures of `values`; null with a test failure.
std::unique_ptr<Renderer> rendererFor(const Scene& scene, const BakeData& bake,
                                      const CacheValues& values);

/// Expects every pixel finite and ≥ 0; returns how many are > 0.
int expectFiniteNonNegative(const Image& image, const char* what);

/// GPU image and CPU reference of one view, and how they compare.
struct Comparison {
    Image gpu;
    Image cpu;
    ImageError error;
    double differing = 0.0;  ///< fraction of pixels off by more than 5 % of the image mean
};

/// Renders one view with `renderer` and shades it with the CPU twin from the same inputs.
Comparison compare(Renderer& renderer, const Scene& scene, const EmbreeScene& rays,
                   const BakeData& bake, const CacheValues& values, const LightSet& lights,
                   const Camera& camera, const ShadeParams& params);

/// Reports a comparison in the test output (the figures the README quotes).
void report(const char* what, const Comparison& c);

}  // namespace pic::test
