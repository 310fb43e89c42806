#pragma once
/// Direct-light visibility by rays, traced on the host with Embree: the alternative to shadow
/// maps (DirectVisibility::Rays). One ray per surfel and light, as the CPU twin casts them
/// (render/surfel_visibility.h surfelVisibility), so the direct light is exact; the
/// surfel-lighting pass reads one bit per surfel and light. On a CPU device (lavapipe) this is
/// several times faster than rasterising shadow maps: llvmpipe pays for every caster triangle
/// of every layer, whereas the server needs visibility at the nS surfels only.

#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "core/bake_data.h"
#include "core/light_set.h"
#include "gpu/device.h"
#include "gpu/resources.h"
#include "rays/embree_scene.h"
#include "render/passes/pass.h"

namespace pic::gpu {

class RayVisibilityPass final : public Pass {
public:
    static constexpr PassKind kKind = PassKind::RayVisibility;
    /// For the surfels of config.bake, traced in config.rays; both must outlive the pass.
    static Result<std::unique_ptr<Pass>> create(Context& context, const PassConfig& config);

    /// Writes the GpuLight records of `lights` and traces the rays of every light that is new
    /// on its slot or whose type, position, direction, cone or range changed; colour and
    /// intensity do not change what a light reaches. Both uploads land with the next submit.
    /// `reallocated` tells whether the visibility buffer was replaced (descriptor sets that
    /// read it must be rebuilt): it grows with the number of lights, never shrinks.
    Result<void> prepare(const LightSet& lights, bool& reallocated);
    /// Records nothing: prepare() traced the rays on the host and its uploads land with the
    /// next submit.
    void record(VkCommandBuffer, const FrameResources&) override {}

    /// Lights whose rays the last prepare() traced, and its wall-clock ms doing so.
    uint32_t tracedLights() const { return mTracedLights; }
    double traceMs() const { return mTraceMs; }
    /// Words per light in visibilityBuffer(): bit i % 32 of word i / 32 is surfel i.
    uint32_t wordsPerLight() const { return mWords; }
    const Buffer& lightBuffer() const { return mLights; }          ///< GpuLight[kMaxLights]
    const Buffer& visibilityBuffer() const { return mVisibility; }  ///< uint per 32 surfels, light by light
    VkDeviceSize bytes() const { return mLights.size() + mVisibility.size(); }

private:
    /// What a light's rays depend on.
    struct LightKey {
        std::string id;
        LightType type = LightType::Point;
        glm::vec3 position{0.0f};
        glm::vec3 direction{0.0f};
        float innerConeAngle = 0.0f;
        float outerConeAngle = 0.0f;
        float range = 0.0f;
        bool operator==(const LightKey&) const = default;
    };

    RayVisibilityPass(Context& context, const EmbreeScene& rays, const BakeData& bake)
        : mContext(context), mRays(rays), mBake(bake) {}

    Context& mContext;
    const EmbreeScene& mRays;
    const BakeData& mBake;
    uint32_t mWords = 0;
    std::vector<LightKey> mKeys;   ///< of the lights the bits were traced for, slot by slot
    std::vector<uint32_t> mBits;   ///< mWords per slot
    Buffer mLights;
    Buffer mVisibility;
    uint32_t mTracedLights = 0;
    double mTraceMs = 0.0;
};

}  // namespace pic::gpu
