#include "render/passes/ray_visibility_pass.h"

#include <algorithm>
#include <chrono>
#include <span>

#include "render/passes/shadow_map_pass.h"
#include "render/surfel_visibility.h"

namespace pic::gpu {

namespace {
/// Surfel lighting reads the lights and the visibility bits as uniform texel buffers.
constexpr VkBufferUsageFlags kVisibilityUsage = VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT;
}  // namespace

Result<std::unique_ptr<Pass>> RayVisibilityPass::create(Context& context,
                                                        const PassConfig& config) {
    PIC_CHECK(config.rays != nullptr && config.bake != nullptr);
    const EmbreeScene& rays = *config.rays;
    const BakeData& bake = *config.bake;
    std::unique_ptr<RayVisibilityPass> pass(new RayVisibilityPass(context, rays, bake));
    pass->mWords = uint32_t(visibilityWords(bake.surfels.size()));
    PIC_TRY_ASSIGN(pass->mLights,
                   Buffer::create(context, kMaxLights * sizeof(GpuLight), kVisibilityUsage,
                                  MemoryUse::Device, "light records"));
    // Room for one light until a light set asks for more.
    PIC_TRY_ASSIGN(pass->mVisibility,
                   Buffer::create(context, std::max<size_t>(pass->mWords, 1) * sizeof(uint32_t),
                                  kVisibilityUsage, MemoryUse::Device, "surfel visibility"));
    return pass;
}

Result<void> RayVisibilityPass::prepare(const LightSet& lights, bool& reallocated) {
    using Clock = std::chrono::steady_clock;
    reallocated = false;
    const size_t count = lights.lights.size();
    const size_t bytes = std::max<size_t>(count * mWords, 1) * sizeof(uint32_t);
    if (bytes > mVisibility.size()) {
        // A new buffer holds none of the bits traced before: every light is traced again (the
        // buffer grows only when a light set has more lights than any before it).
        mKeys.clear();
        PIC_TRY_ASSIGN(mVisibility, Buffer::create(mContext, bytes, kVisibilityUsage,
                                                   MemoryUse::Device, "surfel visibility"));
        reallocated = true;
    }
    mBits.resize(count * mWords);
    mKeys.resize(std::min(mKeys.size(), count));

    const Clock::time_point start = Clock::now();
    mTracedLights = 0;
    std::vector<GpuLight> records(count);
    for (size_t l = 0; l < count; ++l) {
        const Light& light = lights.lights[l];
        records[l] = gpuLightRecord(light);
        const LightKey key{light.id,           light.type,           light.position,
                           light.direction,    light.innerConeAngle, light.outerConeAngle,
                           light.range};
        if (l < mKeys.size() && mKeys[l] == key) continue;
        const std::span<uint32_t> bits(mBits.data() + l * mWords, mWords);
        surfelVisibility(mRays, mBake, light, bits);
        ++mTracedLights;
        if (Result<void> uploaded = mContext.uploadWithNextSubmit(
                mVisibility, bits.data(), bits.size_bytes(), l * mWords * sizeof(uint32_t));
            !uploaded) {
            mKeys.clear();  // nothing is known to be on the device: trace every light next time
            return uploaded;
        }
        if (l < mKeys.size())
            mKeys[l] = key;
        else
            mKeys.push_back(key);
    }
    mTraceMs = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    if (records.empty()) return {};
    return mContext.uploadWithNextSubmit(mLights, records.data(), records.size() * sizeof(GpuLight));
}

}  // namespace pic::gpu
