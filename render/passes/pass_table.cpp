/// The pass table (render/passes/pass.h): every GPU pass, one row each, in PassKind order. The
/// runtime and the renderer make their passes through it; a new pass adds its row here.

#include "render/passes/pass.h"

#include "render/passes/cache_lighting_pass.h"
#include "render/passes/cache_shading_pass.h"
#include "render/passes/gbuffer_pass.h"
#include "render/passes/lightmap_copy_pass.h"
#include "render/passes/pull_pass.h"
#include "render/passes/ray_visibility_pass.h"
#include "render/passes/shadow_map_pass.h"
#include "render/passes/sky_caches_pass.h"
#include "render/passes/surfel_lighting_pass.h"

namespace pic::gpu {
namespace {

/// The row of pass class T: its kind and create function, so that a row never pairs one
/// class's kind with another's create (createPass<T> relies on it).
template <class T>
constexpr PassEntry row(const char* name) {
    return {T::kKind, name, &T::create};
}

constexpr std::array<PassEntry, kPassKinds> kPassTable = {
    row<ShadowMapPass>("shadow_map"),
    row<RayVisibilityPass>("ray_visibility"),
    row<SurfelLightingPass>("surfel_lighting"),
    row<PullPass>("pull"),
    row<CacheLightingPass>("cache_lighting"),
    row<SkyCachesPass>("sky_caches"),
    row<LightmapCopyPass>("lightmap_copy"),
    row<GbufferPass>("gbuffer"),
    row<CacheShadingPass>("cache_shading"),
};

constexpr bool inKindOrder() {
    for (size_t i = 0; i < kPassTable.size(); ++i)
        if (kPassTable[i].kind != PassKind(i)) return false;
    return true;
}
static_assert(inKindOrder(), "row i of the pass table is of PassKind i");

}  // namespace

std::span<const PassEntry, kPassKinds> passTable() {
    return kPassTable;
}

Result<std::unique_ptr<Pass>> createPass(PassKind kind, Context& context,
                                         const PassConfig& config) {
    PIC_CHECK_LT(size_t(kind), kPassTable.size());
    return kPassTable[size_t(kind)].create(context, config);
}

}  // namespace pic::gpu
