#pragma once
/// The GPU backend of the runtime (paper 000 Figure 2 on Vulkan): shadow maps, surfel
/// lighting, pull, cache lighting, light-map copy and progressive bounces, each pass in
/// render/passes/ with its CPU twin in render/cpu/. Runs on any Vulkan 1.3 device; on a
/// machine without a GPU that is Mesa's lavapipe.

#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "gpu/device.h"
#include "gpu/resources.h"
#include "gpu/timers.h"
#include "rays/embree_scene.h"
#include "render/passes/surfel_lighting_pass.h"
#include "render/runtime.h"
#include "render/sky_lighting.h"

namespace pic {

/// How to run the GPU backend.
struct GpuRuntimeOptions {
    std::string deviceName;  ///< --device: substring of the Vulkan device name; empty = best
    bool validation =
        false;  ///< Vulkan validation layer when installed (PIC_VK_VALIDATION overrides)
    uint32_t shadowMapSize = 1024;  ///< texels per side of each shadow-map layer
    /// Layers with coarse texels draw simplified casters (gpu::ShadowMapOptions); off only
    /// to measure what that changes.
    bool casterLevelsOfDetail = true;
    /// Perspective layers as wide as give the orthographic texel at the median distance of
    /// the surfaces a light reaches (gpu::ShadowMapOptions::equalFootprint): the surfels are
    /// spread over those surfaces by area. Off: every layer shadowMapSize wide.
    bool shadowEqualFootprint = true;
    /// Where the direct light's visibility comes from; unset: host-traced rays on a CPU
    /// device (lavapipe, where rasterising shadow maps costs several times more than tracing
    /// a ray per surfel and light), shadow maps on a GPU. The shadow-map options above apply
    /// to DirectVisibility::ShadowMaps only.
    std::optional<gpu::DirectVisibility> directVisibility;
    /// gpu::ContextOptions::mapDeviceMemory: false runs a discrete GPU's staging and
    /// read-back paths on a device whose memory the host could map (tests).
    bool mapDeviceMemory = true;
    /// Cache lighting gives each cache a subgroup (true) or an invocation (false); unset: a
    /// subgroup on a GPU, an invocation on a CPU device (gpu::CacheLightingPass::create).
    std::optional<bool> cachePerSubgroup;
    /// Widest texel (in 32-bit words, 1 to 4) cache lighting reads its links in; of those the
    /// device supports that divide a link the pass takes 4 or 2 words before 3. 1 reads a
    /// word at a time, as on a device with no wider uint texel buffers (tests).
    uint32_t maxLinkTexelWords = 4;
    /// Where textures() gets the light-map copy (paper 000 Figure 2 step 5), on demand after
    /// each setLights (picserver streams the caches and never asks): true, on the host from
    /// the caches setLights reads back anyway (core/cache_textures.h copyCachesToTextures);
    /// false, the LightmapCopyPass on the device, then the layers read back. Unset: the host
    /// on a CPU device, whose memory is the host's, so the pass would only add a dispatch and
    /// a submission; the device on a GPU.
    std::optional<bool> lightmapCopyOnHost;
};

namespace gpu {
class ShadowMapPass;
class RayVisibilityPass;
class SurfelLightingPass;
class PullPass;
class CacheLightingPass;
class SkyCachesPass;
class LightmapCopyPass;
}  // namespace gpu

/// Each node's light from its flux (pulled): its flux spread (render/node_spread.h), the slopes
/// and ln Z packed by gpu::packNodeSpread and the radiance at the box centre as RGBE8, what
/// surfel lighting (leaves) and the pull (inner nodes) write for cache lighting
/// (shaders/shared/pull.h).
std::vector<glm::uvec4> packNodeLight(const BakeData& bake, std::span<const glm::vec3> nodeFlux);

/// The GPU backend. Besides the Runtime API it runs single passes on given inputs, so that
/// tests compare each pass with its CPU twin on identical data. Not thread-safe.
class GpuRuntime final : public Runtime {
public:
    /// `scene`, `rays` (for its ray offset) and `bake` must outlive the runtime.
    static Result<std::unique_ptr<GpuRuntime>> create(const Scene& scene, const EmbreeScene& rays,
                                                      const BakeData& bake,
                                                      const BounceParams& bounces,
                                                      const GpuRuntimeOptions& options = {});
    ~GpuRuntime() override;

    Result<const CacheValues*> setLights(const LightSet& lights, UpdateStats* stats,
                                         const BounceObserver& observer = {}) override;
    Result<const CacheTextures*> textures() override;
    const char* name() const override { return "gpu"; }

    /// The direct light's visibility in use (GpuRuntimeOptions::directVisibility resolved).
    gpu::DirectVisibility directVisibility() const { return mVisibility; }
    /// Visibility (shadow maps or rays) and the direct part of surfel lighting for `lights`:
    /// nS direct fluxes.
    Result<std::vector<glm::vec3>> runDirect(const LightSet& lights, UpdateStats* stats = nullptr);
    /// One bounce of surfel lighting from `direct` (nS) and the caches `previous` (with their
    /// irradiance along the light-map caches' normals, as lightCaches fills it): the leaves.
    Result<std::vector<glm::vec3>> runBounce(std::span<const glm::vec3> direct,
                                             const CacheValues& previous);
    /// Pull from the leaves `leaves` (nS): all 2nS − 1 node fluxes.
    Result<std::vector<glm::vec3>> runPull(std::span<const glm::vec3> leaves);
    /// Cache lighting from `nodeFlux` (2nS − 1 nodes, pulled), uploaded as the node light that
    /// surfel lighting and the pull write (packNodeLight); the values with their irradiance
    /// along the light-map caches' normals.
    Result<CacheValues> runCacheLighting(std::span<const glm::vec3> nodeFlux);
    /// Cache lighting from node light packed already, so that a benchmark times the pass alone.
    Result<CacheValues> runCacheLighting(std::span<const glm::uvec4> nodeLight);
    /// Every node's light (shaders/shared/pull.h) as the last update's surfel lighting
    /// (leaves) and pull (inner nodes) wrote it.
    Result<std::vector<glm::uvec4>> nodeLight();
    /// Light-map copy of `values` into the textures.
    Result<CacheTextures> runLightmapCopy(const CacheValues& values);
    /// The sky of `weights` (made for the bake's lY, lC) added to `values`; InvalidInput for a
    /// bake without sky transfer.
    Result<CacheValues> runSkyCaches(const CacheValues& values, const SkyCacheWeights& weights);

    /// Device memory per buffer group, bytes, for the benchmark (paper 000 Table 4).
    std::vector<std::pair<std::string, uint64_t>> memory() const;
    /// Link bytes cache lighting reads per bounce.
    uint64_t linkBytesPerBounce() const;
    /// 32-bit words per texel cache lighting reads its links in.
    uint32_t linkTexelWords() const;
    /// Whether textures() copies the caches on the host (GpuRuntimeOptions::lightmapCopyOnHost
    /// resolved).
    bool lightmapCopyOnHost() const { return mLightmapCopyOnHost; }
    const gpu::Context& context() const { return *mContext; }

private:
    GpuRuntime(const Scene& scene, const BakeData& bake, const BounceParams& bounces);
    Result<void> init(const EmbreeScene& rays, const GpuRuntimeOptions& options);
    /// (Re)binds surfel lighting to the current shadow-map image or visibility buffer.
    Result<void> bindVisibility();
    /// Records the shadow maps of the lights that changed (nothing with rays).
    void recordShadowMaps(VkCommandBuffer cmd);
    /// The counts and host time of the visibility the latest update prepared and recorded.
    void addVisibilityStats(UpdateStats& stats) const;
    Result<void> prepareLights(const LightSet& lights);
    Result<void> submitTimed(const std::function<void(VkCommandBuffer)>& record,
                             UpdateStats& stats);
    Result<void> uploadFlux(std::span<const glm::vec3> flux, gpu::Buffer& buffer);
    Result<std::vector<glm::vec3>> downloadFlux(const gpu::Buffer& buffer, size_t count);
    Result<void> uploadCaches(const CacheValues& values);
    /// Records the copy of the caches into mCacheReadback when the host cannot map them.
    void recordCacheReadback(VkCommandBuffer cmd);
    /// The light-map copy pass, made on first use (textures() on the device, runLightmapCopy).
    Result<gpu::LightmapCopyPass*> lightmapCopyPass();
    /// The caches as the latest submission that recorded recordCacheReadback left them.
    void readCaches(CacheValues& values) const;
    /// Adds the sky to the caches the last bounce left (SkyCachesPass) and reads them back.
    Result<void> addSkyToCaches(UpdateStats& stats);

    const Scene& mScene;
    const BakeData& mBake;
    BounceParams mBounces;
    glm::vec3 mRatioBound;  ///< bounceRatioBound of the bake
    std::unique_ptr<gpu::Context> mContext;
    gpu::DirectVisibility mVisibility = gpu::DirectVisibility::ShadowMaps;
    std::unique_ptr<gpu::ShadowMapPass> mShadows;            ///< DirectVisibility::ShadowMaps
    std::unique_ptr<gpu::RayVisibilityPass> mRayVisibility;  ///< DirectVisibility::Rays
    std::unique_ptr<gpu::SurfelLightingPass> mSurfels;
    std::unique_ptr<gpu::PullPass> mPull;
    std::unique_ptr<gpu::CacheLightingPass> mCacheLighting;
    std::unique_ptr<gpu::SkyCachesPass> mSkyCaches;  ///< bakes with sky transfer only
    SkyState mSky;
    const SkyLighting* mSkyNow = nullptr;  ///< the sky of the light set prepared, or null
    std::unique_ptr<gpu::LightmapCopyPass> mLightmapCopy;  ///< see lightmapCopyPass()
    bool mLightmapCopyOnHost = false;
    gpu::PassTimer mTimer;
    gpu::Buffer mNodeFlux;   ///< vec4 per node, W RGB
    gpu::Buffer mNodeLight;  ///< 4 words per node (shaders/shared/pull.h), cache lighting's input
    gpu::Buffer mCacheY;     ///< half, nC·lY²
    gpu::Buffer mCacheCo;    ///< half, nC·lC²
    gpu::Buffer mCacheCg;    ///< half, nC·lC²
    gpu::Buffer mCacheIrradiance;  ///< vec4 per cache: CacheValues::irradiance, for the bounce
    gpu::Buffer mShTables;   ///< ShTables
    /// Host-visible Y, Co, Cg after one another, only when the cache buffers are not mapped
    /// (a discrete GPU): filled by the submission that wrote them, not by another one.
    gpu::Buffer mCacheReadback;
    CacheValues mValues;
    CacheTextures mTextures;
    bool mTexturesCurrent = false;
};

}  // namespace pic
