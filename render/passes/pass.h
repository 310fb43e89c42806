#pragma once
/// The pass interface (STYLE.md rule 5): every GPU pass in render/passes/ is a Pass, made
/// through the one table in render/passes/pass_table.cpp from a PassConfig and recorded with a
/// FrameResources. A new pass is a class `<Name>Pass : Pass` with `kKind`, a static
/// `create(Context&, const PassConfig&)` and `record(VkCommandBuffer, const FrameResources&)`;
/// it enters with its kind in PassKind, its row in the table, and the fields it reads in
/// PassConfig and FrameResources. What is specific to one pass (binding its inputs, preparing a
/// light set, read-backs) stays a method of that pass.

#include <array>
#include <cstdint>
#include <memory>
#include <span>

#include <glm/glm.hpp>

#include "core/error.h"
#include "gpu/device.h"
#include "shaders/shared/cache_shading.h"
#include "shaders/shared/gbuffer.h"

namespace pic {
struct BakeData;
struct NodeSpread;
struct Scene;
class EmbreeScene;
}  // namespace pic

namespace pic::gpu {

/// Where the direct light's visibility comes from (render/passes/surfel_lighting_pass.h).
enum class DirectVisibility;

/// One row of the pass table per kind, in this order.
enum class PassKind : uint32_t {
    ShadowMap,
    RayVisibility,
    SurfelLighting,
    Pull,
    CacheLighting,
    SkyCaches,
    LightmapCopy,
    Gbuffer,
    CacheShading,
};
inline constexpr size_t kPassKinds = 9;

/// How the shadow-map pass draws the scene. The caster options are on by default; off only to
/// measure what they save and to test what they change. The first two store the same depths;
/// levels of detail move surfaces by at most kCasterErrorPerTexel texels of the layer that
/// draws them.
struct ShadowMapOptions {
    bool mergeCoplanar = true;   ///< draw mergeShadowCasters(scene) instead of the scene
    bool oneSidedSolids = true;  ///< skip the faces of solids that look away from the light
    bool levelsOfDetail = true;  ///< layers whose texels are coarse draw simplified casters
    /// Every layer `size` texels wide (false), or each perspective layer only as wide as
    /// needed for texels, at the median distance from the light of the scene's surfaces that
    /// layer holds (within the light's range and cone), as wide as an orthographic layer's
    /// over the scene (at most `size`).
    /// Off for pixels (a camera may look at the nearest surfaces); on for surfels, which are
    /// spread over the surfaces by area.
    bool equalFootprint = false;
};

/// What creating a pass reads; each pass reads its own fields (named beside them) and the
/// pointers it reads must be set and outlive the pass.
struct PassConfig {
    const Scene* scene = nullptr;  ///< shadow map, surfel lighting, G-buffer
    /// Ray visibility, surfel lighting, pull, cache lighting, sky caches, light-map copy.
    const BakeData* bake = nullptr;
    const EmbreeScene* rays = nullptr;   ///< ray visibility; surfel lighting (stencils, ray offset)
    const NodeSpread* spread = nullptr;  ///< pull, cache lighting: nodeSpread(*bake)
    /// Surfel lighting: where its direct light's visibility comes from (shadow maps: 0).
    DirectVisibility visibility{};
    uint32_t shadowMapSize = 1024;  ///< shadow map: texels per side of one layer
    ShadowMapOptions shadowMap;     ///< shadow map
    /// Cache lighting: a subgroup per cache (GPUs) or an invocation (CPU devices), and the
    /// widest uint texel (words) its links are read in (CacheLightingPass::create).
    bool cachePerSubgroup = false;
    uint32_t maxLinkTexelWords = 4;
    /// G-buffer: the light-map UVs of the scene's triangle corners (kNotLightmapped: grid).
    std::span<const glm::vec2> triangleUvs;
    /// Cache shading: lY, lC and the sizes of the cache textures it owns.
    uint32_t bandsY = 0;
    uint32_t bandsC = 0;
    glm::uvec3 gridDims{0u};      ///< grid vertices per axis
    glm::uvec2 lightmapSize{0u};  ///< light-map texels
};

/// What recording a pass reads that may change from one recording to the next; each pass reads
/// its own fields. Buffers and images are bound before (each pass's bind or prepare), when
/// they change, not per recording.
struct FrameResources {
    /// Surfel lighting: the direct part (false) or a bounce from the previous caches (true).
    bool bounce = false;
    uint32_t lightCount = 0;  ///< surfel lighting: lights of the set prepared
    uint32_t sumSlot = 0;     ///< surfel lighting: where its flux sum goes (0 or 1)
    /// Surfel lighting's bounce: each leaf's new flux S' becomes S' + tail·max(S' − S, 0).
    glm::vec3 tail{0.0f};
    GbufferPush gbuffer{};       ///< G-buffer: the camera view (gbufferPushOf)
    CacheShadingPush shading{};  ///< cache shading: size, component, camera, grid, …
};

/// A GPU pass: made by its table row, recorded into a command buffer.
class Pass {
public:
    virtual ~Pass() = default;
    /// Records the pass's work for `frame` into `cmd`.
    virtual void record(VkCommandBuffer cmd, const FrameResources& frame) = 0;
};

/// One row of the pass table: a kind, its base name (render/passes/<name>_pass.h and its
/// shaders/<name>.*, if any) and how it is made.
struct PassEntry {
    PassKind kind;
    const char* name;
    Result<std::unique_ptr<Pass>> (*create)(Context& context, const PassConfig& config);
};

/// The pass table (render/passes/pass_table.cpp), row i of kind i.
std::span<const PassEntry, kPassKinds> passTable();

/// Makes a pass of `kind` through its table row.
Result<std::unique_ptr<Pass>> createPass(PassKind kind, Context& context, const PassConfig& config);

/// Makes the pass class T through the table row of T::kKind (whose row makes a T).
template <class T>
Result<std::unique_ptr<T>> createPass(Context& context, const PassConfig& config) {
    PIC_TRY_ASSIGN(std::unique_ptr<Pass> pass, createPass(T::kKind, context, config));
    return std::unique_ptr<T>(static_cast<T*>(pass.release()));
}

}  // namespace pic::gpu
