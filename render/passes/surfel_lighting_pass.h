#pragma once
/// Surfel lighting on the GPU (paper 000 Figure 2 step 2): the direct flux of every surfel
/// from the shadow-mapped lights, the sky and its emission, then, per further bounce, that plus the
/// light the previous bounce's caches deliver to it. CPU twin: render/cpu/surfel_lighting.h.
/// The direct light's visibility comes from shadow maps or from host-traced rays.

#include <array>
#include <memory>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "core/bake_data.h"
#include "core/cache_values.h"
#include "core/light_set.h"
#include "core/scene.h"
#include "core/sky.h"
#include "gpu/device.h"
#include "gpu/kernel.h"
#include "gpu/resources.h"
#include "render/passes/pass.h"
#include "render/passes/ray_visibility_pass.h"
#include "render/passes/shadow_map_pass.h"

namespace pic::gpu {

/// Where the direct light's visibility at each surfel comes from.
enum class DirectVisibility {
    ShadowMaps,  ///< rasterised shadow maps (ShadowMapPass), sampled at the surfel
    Rays,        ///< one ray per surfel and light, traced on the host (RayVisibilityPass)
};

/// "shadow-maps" or "rays".
const char* directVisibilityName(DirectVisibility visibility);
/// Parses "shadow-maps", "rays" or "auto" (nullopt: the runtime picks); InvalidInput otherwise.
Result<std::optional<DirectVisibility>> parseDirectVisibility(std::string_view text);

/// The runtime's buffers this pass reads and writes.
struct SurfelLightingResources {
    /// The lights' records and visibility: shadows with DirectVisibility::ShadowMaps, rays
    /// with DirectVisibility::Rays.
    const ShadowMapPass* shadows = nullptr;
    const RayVisibilityPass* rays = nullptr;
    const Buffer* nodeFlux = nullptr;    ///< vec4 per node; the pass writes the leaves
    const Buffer* nodeRadiance = nullptr;  ///< RGBE8 per node; the pass writes the leaves
    /// The buffers below the lights are read as uniform texel buffers: their usage must
    /// allow it (VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT), as must the lights' and the
    /// visibility's.
    const Buffer* cacheY = nullptr;      ///< half, nC·lY²: the previous bounce
    const Buffer* cacheCo = nullptr;     ///< half, nC·lC²
    const Buffer* cacheCg = nullptr;     ///< half, nC·lC²
    const Buffer* cacheIrradiance = nullptr;  ///< vec4 per cache (CacheValues::irradiance)
    const Buffer* shTables = nullptr;    ///< ShTables
};

class SurfelLightingPass final : public Pass {
public:
    static constexpr PassKind kKind = PassKind::SurfelLighting;
    /// Uploads the surfels of config.bake and their cache stencils (render/surfel_visibility.h
    /// surfelStencils in config.rays: the CPU twin's bounce reads the same), nS of them, for
    /// direct light seen through config.visibility; shadow tests start config.rays's ray
    /// offset above the surfel.
    static Result<std::unique_ptr<Pass>> create(Context& context, const PassConfig& config);

    /// (Re)binds the pass to the runtime's buffers and the current shadow-map image or
    /// visibility buffer.
    Result<void> bind(const SurfelLightingResources& resources);
    /// Writes the per-material emission scales of `lights`.
    Result<void> setEmissiveScales(const LightSet& lights);
    /// The sky's RGB radiance SH (core/sky.h) the direct part adds through each surfel's sky
    /// transfer, uploaded with the next submission; null: no sky. A sky needs a bake with sky
    /// transfer.
    Result<void> setSky(const std::array<glm::vec3, kSkyCoefficients>* sh);
    /// Records the direct part (directFlux and the leaves) of frame.lightCount lights or, with
    /// frame.bounce, a bounce (the leaves; with a frame.tail, each leaf's new flux S' becomes
    /// S' + tail·max(S' − S, 0), as the CPU twin's bounceSurfelFlux); the pass's flux sum goes
    /// to frame.sumSlot (0 or 1).
    void record(VkCommandBuffer cmd, const FrameResources& frame) override;
    /// Σ of the leaves' flux of the last pass recorded with `sumSlot`, after it completed, in
    /// double (W, RGB).
    Result<glm::dvec3> totalFlux(uint32_t sumSlot);

    const Buffer& directFlux() const { return mDirectFlux; }
    VkDeviceSize bytes() const;

private:
    SurfelLightingPass(Context& context, const Scene& scene) : mContext(context), mScene(scene) {}
    Context& mContext;
    const Scene& mScene;
    DirectVisibility mVisibility = DirectVisibility::ShadowMaps;
    Kernel mDirect;  ///< the shader specialised to kSurfelModeDirect or kSurfelModeDirectRays
    Kernel mBounce;  ///< and to kSurfelModeBounce
    VkDescriptorSet mDirectSet = VK_NULL_HANDLE;
    VkDescriptorSet mBounceSet = VK_NULL_HANDLE;
    uint32_t mSurfelCount = 0;
    float mEpsilon = 0.0f;
    Buffer mSurfels;
    Buffer mEmissiveScale;
    Buffer mStencils;
    Buffer mDirectFlux;
    Buffer mGroupFlux;
    /// What the shader declares and the mode in use does not read: shadow-map layer records
    /// and a 16² depth layer (rays), or a visibility word (shadow maps).
    Buffer mUnusedLayers;
    DepthArray mUnusedDepth;
    Buffer mUnusedVisibility;
    /// Uniform texel views of what the shader reads by index.
    TexelView mSurfelView;
    TexelView mStencilView;
    TexelView mEmissiveView;
    TexelView mDirectFluxView;
    TexelView mLightView;
    TexelView mVisibilityView;
    std::array<TexelView, 3> mCacheViews;  ///< Y, Co, Cg
    TexelView mIrradianceView;             ///< CacheValues::irradiance, RGBA32F
    bool mHasSkyTransfer = false;  ///< the bake has BakeData::surfelSky
    bool mSky = false;             ///< the direct part adds the sky (setSky)
    Buffer mSurfelSky;             ///< float, nS·kSkyCoefficients (or 1 placeholder)
    TexelView mSurfelSkyView;
    Buffer mSkySh;                 ///< vec4 × kSkyCoefficients
};

}  // namespace pic::gpu
