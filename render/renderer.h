#pragma once
/// The thin client's headless renderer (ARCHITECTURE.md §1, `picclient render`): one frame of
/// a scene shaded from cache textures (core/cache_textures.h: the client writes them from the
/// caches the server streams), on any Vulkan 1.3 device (lavapipe without a GPU). A rasterised G-buffer, direct light from shadow maps
/// (render/passes/shadow_map_pass.h), the cache term from the light map (bilinear) on
/// light-mapped surfaces and the grid (trilinear) elsewhere (paper 000 §3.2), emission; each
/// pixel holds the radiance at its centre, or with n subsamples the mean over n fixed points
/// of the pixel (supersampling: a G-buffer and a shading pass per subsample, core/camera.h
/// subsampleOffset). The CPU twin is render/cpu/cache_shading.h:
/// the cache term matches it to half-float precision of the textures; direct light differs
/// where shadow-map texels straddle a shadow edge.

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "core/bake_data.h"
#include "core/cache_textures.h"
#include "core/error.h"
#include "core/image.h"
#include "core/light_set.h"
#include "core/scene.h"
#include "core/shade_params.h"
#include "gpu/device.h"
#include "gpu/resources.h"
#include "gpu/timers.h"

namespace pic {

namespace gpu {
class ShadowMapPass;
class GbufferPass;
class CacheShadingPass;
}  // namespace gpu

/// What a thin client knows of a bake besides the scene: enough to place and sample the cache
/// textures (layout in core/cache_textures.h). Plain numbers and vectors, so that the
/// wire can carry it.
struct ClientLayout {
    uint64_t sceneHash = 0;              ///< Scene::hash of the scene the bake was made for
    uint32_t bandsY = 0;                 ///< lY
    uint32_t bandsC = 0;                 ///< lC, 1 ≤ lC ≤ lY
    glm::vec3 gridOrigin{0.0f};          ///< metres, position of grid vertex (0, 0, 0)
    float gridCellSize = 0.0f;           ///< metres; 0: no grid (its surfaces get no cache light)
    glm::uvec3 gridDims{0u};             ///< grid vertices per axis
    uint32_t lightmapWidth = 0;          ///< texels
    uint32_t lightmapHeight = 0;         ///< texels
    std::vector<glm::vec2> triangleUvs;  ///< 3 per scene triangle: light-map UVs in [0, 1]² of
                                         ///< the atlas, or kNotLightmapped (grid-shaded)
};

/// The client layout of a bake.
ClientLayout clientLayoutOf(const BakeData& bake);

/// The renderer's ray offset above surfaces and its camera's near-plane distance for `scene`,
/// metres: the CPU twin's (rays/embree_scene.h EmbreeScene::epsilon), 1e-5 of the bounds'
/// diagonal and at least 1e-6.
float rendererEpsilonOf(const Scene& scene);

/// How to build a renderer.
struct RendererOptions {
    uint32_t shadowMapSize = 1024;  ///< texels per side of each shadow-map layer, 16..16384
};

/// Where one frame's time went.
struct RenderTimings {
    std::vector<std::pair<std::string, double>> passMs;  ///< GPU time per pass (timestamps)
    double totalMs = 0.0;                                ///< wall time of render()
    uint32_t shadowMapsRendered = 0;                     ///< lights whose maps were redrawn
};

/// Renders frames of one scene from its streamed caches. Not thread-safe; the context and
/// the scene must outlive it.
class Renderer {
public:
    /// Uploads the scene (triangles, materials, textures) and allocates the cache textures
    /// for `layout`, which hold no light until setCaches. InvalidInput when the layout does
    /// not fit the scene (other scene hash, UV count, band counts, non-finite numbers);
    /// Unsupported when the scene's textures or triangles, or one channel of the cache
    /// textures, exceed one storage buffer of the device (lavapipe: 128 MiB).
    static Result<std::unique_ptr<Renderer>> create(gpu::Context& context, const Scene& scene,
                                                    const ClientLayout& layout,
                                                    const RendererOptions& options = {});
    ~Renderer();
    Renderer(const Renderer&) = delete;
    Renderer& operator=(const Renderer&) = delete;

    /// Uploads one version's cache textures (once per streamed version). InvalidInput, and
    /// the previous textures kept, when they do not match the layout (band counts, grid or
    /// light-map size, array lengths), hold a non-finite value or coverage other than 0 or 1.
    Result<void> setCaches(const CacheTextures& textures);

    /// Renders `camera`'s view lit by `lights` as `params` asks: params.component selects
    /// full (visible emission + direct + cache term), direct, indirect (the cache term, with
    /// the glossy lobe when glossyWeight and glossyExponent are > 0) or glossy (the lobe
    /// alone); the cache term takes the light set's indirect scales; misses are black.
    /// samplesPerPixel subsamples per pixel, averaged (1: the pixel centre); the frame's cost
    /// grows with them, shadow maps aside. Never NaN, infinite or negative for accepted
    /// inputs. InvalidInput for sizes outside 1..16384, sample counts outside
    /// 1..kMaxSamplesPerPixel, bad glossy parameters, an invalid camera, or lights that
    /// checkRuntimeLights refuses or that number more than kMaxLights.
    Result<Image> render(const LightSet& lights, const Camera& camera, const ShadeParams& params,
                         RenderTimings* timings = nullptr);

    /// The Vulkan context it renders with (device name, validation messages).
    const gpu::Context& context() const { return mContext; }

private:
    Renderer(gpu::Context& context, const Scene& scene, ClientLayout layout);
    Result<void> init(const RendererOptions& options);

    gpu::Context& mContext;
    const Scene& mScene;
    ClientLayout mLayout;
    float mEpsilon = 0.0f;
    std::unique_ptr<gpu::ShadowMapPass> mShadows;
    std::unique_ptr<gpu::GbufferPass> mGbuffer;
    std::unique_ptr<gpu::CacheShadingPass> mShading;
    gpu::PassTimer mTimer;
    gpu::Buffer mShTables;
    gpu::Buffer mRadiance;  ///< vec4 per pixel, host-visible
    bool mBound = false;    ///< the shading pass's set names the current targets and buffers
};

}  // namespace pic
