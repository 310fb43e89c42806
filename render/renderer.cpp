#include "render/renderer.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "core/camera.h"
#include "core/sh.h"
#include "render/passes/cache_shading_pass.h"
#include "render/passes/gbuffer_pass.h"
#include "render/passes/pass.h"
#include "render/passes/shadow_map_pass.h"
#include "render/runtime.h"
#include "render/sh_tables.h"

namespace pic {
namespace {

using Clock = std::chrono::steady_clock;

/// Timestamp pairs one frame may hold: shadow maps, G-buffer, shading, further subsamples.
constexpr uint32_t kTimedPasses = 4;

bool finite(const glm::vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// The layout fits the scene and the shaders (band counts they are built for, finite numbers).
Result<void> checkLayout(const ClientLayout& layout, const Scene& scene) {
    if (layout.sceneHash != scene.hash)
        return fail(ErrorCode::InvalidInput,
                    "the caches were baked for a different scene (hash {:016x}, scene {:016x})",
                    layout.sceneHash, scene.hash);
    if (layout.bandsY < 1 || layout.bandsY > uint32_t(kMaxShBands) || layout.bandsC < 1 ||
        layout.bandsC > layout.bandsY)
        return fail(ErrorCode::InvalidInput, "cache bands y {} c {} (need 1 ≤ c ≤ y ≤ {})",
                    layout.bandsY, layout.bandsC, kMaxShBands);
    if (layout.triangleUvs.size() != 3 * scene.triangles.size())
        return fail(ErrorCode::InvalidInput,
                    "the layout has light-map UVs for {} triangle corners, the scene has {} "
                    "triangles ({} corners)",
                    layout.triangleUvs.size(), scene.triangles.size(), 3 * scene.triangles.size());
    for (size_t i = 0; i < layout.triangleUvs.size(); ++i) {
        const glm::vec2 uv = layout.triangleUvs[i];
        if (!std::isfinite(uv.x) || !std::isfinite(uv.y))
            return fail(ErrorCode::InvalidInput, "light-map UV {} of triangle {} is not finite",
                        i % 3, i / 3);
    }
    if (!finite(layout.gridOrigin) || !std::isfinite(layout.gridCellSize) ||
        layout.gridCellSize < 0.0f)
        return fail(ErrorCode::InvalidInput,
                    "grid origin or cell size {} is not finite, or the cell size is negative",
                    layout.gridCellSize);
    // Texel indices are 32-bit in the shaders.
    const uint64_t gridVertices =
        uint64_t{layout.gridDims.x} * layout.gridDims.y * layout.gridDims.z;
    const uint64_t texels = uint64_t{layout.lightmapWidth} * layout.lightmapHeight;
    if (gridVertices > UINT32_MAX || texels > UINT32_MAX)
        return fail(ErrorCode::InvalidInput, "grid {}x{}x{} or light map {}x{} is too large",
                    layout.gridDims.x, layout.gridDims.y, layout.gridDims.z, layout.lightmapWidth,
                    layout.lightmapHeight);
    return {};
}

/// Cache textures that have the layout's band counts, sizes and array lengths, finite values
/// and 0/1 coverage.
Result<void> checkTextures(const CacheTextures& t, const ClientLayout& layout) {
    if (t.bandsY != layout.bandsY || t.bandsC != layout.bandsC)
        return fail(ErrorCode::InvalidInput,
                    "cache textures have bands y {} c {}, the layout has y {} c {}", t.bandsY,
                    t.bandsC, layout.bandsY, layout.bandsC);
    if (t.gridDims != layout.gridDims || t.lightmapWidth != layout.lightmapWidth ||
        t.lightmapHeight != layout.lightmapHeight)
        return fail(ErrorCode::InvalidInput,
                    "cache textures hold a {}x{}x{} grid and a {}x{} light map, the layout has "
                    "{}x{}x{} and {}x{}",
                    t.gridDims.x, t.gridDims.y, t.gridDims.z, t.lightmapWidth, t.lightmapHeight,
                    layout.gridDims.x, layout.gridDims.y, layout.gridDims.z, layout.lightmapWidth,
                    layout.lightmapHeight);
    const size_t vertices = size_t{t.gridDims.x} * t.gridDims.y * t.gridDims.z;
    const size_t texels = size_t{t.lightmapWidth} * t.lightmapHeight;
    const char* channel[3] = {"Y", "Co", "Cg"};
    const auto check = [](const std::vector<float>& values, size_t expected, const char* what,
                          const char* ch, bool coverage) -> Result<void> {
        if (values.size() != expected)
            return fail(ErrorCode::InvalidInput, "{} {} hold {} values, the layout needs {}", what,
                        ch, values.size(), expected);
        for (size_t i = 0; i < values.size(); ++i) {
            const float v = values[i];
            if (coverage ? !(v == 0.0f || v == 1.0f) : !std::isfinite(v))
                return fail(ErrorCode::InvalidInput, "{} {} value {} is {}{}", what, ch, i, v,
                            coverage ? " (coverage is 0 or 1)" : "");
        }
        return {};
    };
    for (int ch = 0; ch < 3; ++ch) {
        PIC_TRY(
            check(t.grid[ch], size_t{t.layers(ch)} * vertices, "grid layers", channel[ch], false));
        PIC_TRY(check(t.lightmap[ch], size_t{t.layers(ch)} * texels, "light-map layers",
                      channel[ch], false));
    }
    PIC_TRY(check(t.gridCoverage, vertices, "grid", "coverage", true));
    return check(t.lightmapCoverage, texels, "light-map", "coverage", true);
}

}  // namespace

ClientLayout clientLayoutOf(const BakeData& bake) {
    ClientLayout layout;
    layout.sceneHash = bake.sceneHash;
    layout.bandsY = bake.params.bandsY;
    layout.bandsC = bake.params.bandsC;
    layout.gridOrigin = bake.grid.origin;
    layout.gridCellSize = bake.grid.cellSize;
    layout.gridDims = bake.grid.dims;
    layout.lightmapWidth = bake.lightmap.width;
    layout.lightmapHeight = bake.lightmap.height;
    layout.triangleUvs = bake.lightmap.triangleUvs;
    return layout;
}

float rendererEpsilonOf(const Scene& scene) {
    return std::max(1e-6f, 1e-5f * scene.bounds.diagonal());
}

Renderer::Renderer(gpu::Context& context, const Scene& scene, ClientLayout layout)
    : mContext(context), mScene(scene), mLayout(std::move(layout)) {}

Renderer::~Renderer() = default;

Result<std::unique_ptr<Renderer>> Renderer::create(gpu::Context& context, const Scene& scene,
                                                   const ClientLayout& layout,
                                                   const RendererOptions& options) {
    PIC_TRY(checkLayout(layout, scene));
    std::unique_ptr<Renderer> renderer(new Renderer(context, scene, layout));
    PIC_TRY(renderer->init(options));
    return renderer;
}

Result<void> Renderer::init(const RendererOptions& options) {
    using namespace gpu;
    // The CPU twin's ray offset (rays/embree_scene.h EmbreeScene::epsilon), so that shadow
    // tests start from the same height above the surface.
    mEpsilon = rendererEpsilonOf(mScene);
    // Every pass is made through the pass table (render/passes/pass.h) from one config.
    const PassConfig config{
        .scene = &mScene,
        .shadowMapSize = options.shadowMapSize,
        .triangleUvs = mLayout.triangleUvs,
        .bandsY = mLayout.bandsY,
        .bandsC = mLayout.bandsC,
        .gridDims = mLayout.gridDims,
        .lightmapSize = {mLayout.lightmapWidth, mLayout.lightmapHeight},
    };
    PIC_TRY_ASSIGN(mShadows, createPass<ShadowMapPass>(mContext, config));
    PIC_TRY_ASSIGN(mGbuffer, createPass<GbufferPass>(mContext, config));
    PIC_TRY_ASSIGN(mShading, createPass<CacheShadingPass>(mContext, config));
    const ShTables tables = makeShTables();
    PIC_TRY_ASSIGN(mShTables, Buffer::createWith(mContext, &tables, sizeof(tables),
                                                 VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, "SH tables"));
    PIC_TRY_ASSIGN(mTimer, PassTimer::create(mContext, kTimedPasses));
    return {};
}

Result<void> Renderer::setCaches(const CacheTextures& textures) {
    PIC_TRY(checkTextures(textures, mLayout));
    return mShading->setCaches(textures);
}

Result<Image> Renderer::render(const LightSet& lights, const Camera& camera,
                               const ShadeParams& params, RenderTimings* timings) {
    const Clock::time_point start = Clock::now();
    PIC_TRY(checkShadeParams(params));
    PIC_TRY(checkCamera(camera));
    if (lights.lights.size() > kMaxLights)
        return fail(ErrorCode::InvalidInput, "{} lights, at most {} are supported",
                    lights.lights.size(), kMaxLights);
    PIC_TRY(checkRuntimeLights(lights, mScene));

    // Direct light needs the lights' shadow maps; the cache term alone needs none.
    const bool direct =
        params.component == ShadeComponent::Full || params.component == ShadeComponent::Direct;
    bool reallocated = false;
    if (direct) PIC_TRY(mShadows->prepare(lights, reallocated));
    bool resized = false;
    PIC_TRY(mGbuffer->prepare(params.width, params.height, lights, resized));
    const VkDeviceSize radianceBytes =
        VkDeviceSize{params.width} * params.height * sizeof(glm::vec4);
    if (mRadiance.size() != radianceBytes) {
        PIC_TRY_ASSIGN(mRadiance,
                       gpu::Buffer::create(mContext, radianceBytes, 0, gpu::MemoryUse::Readback,
                                           "rendered radiance"));
        resized = true;
    }
    // New images or buffers invalidate the set that names the old ones.
    if (reallocated || resized || !mBound) {
        mBound = false;
        PIC_TRY(mShading->bind({mGbuffer.get(), mShadows.get(), &mShTables, &mRadiance}));
        mBound = true;
    }

    const float near = rendererEpsilonOf(mScene);

    // What the G-buffer and shading passes record with: the shading's push here, the
    // G-buffer's per subsample.
    gpu::FrameResources frame{};
    gpu::CacheShadingPush& push = frame.shading;
    push.eye = camera.eye;
    push.component = params.component == ShadeComponent::Full       ? gpu::kShadeFull
                     : params.component == ShadeComponent::Direct   ? gpu::kShadeDirect
                     : params.component == ShadeComponent::Indirect ? gpu::kShadeIndirect
                                                                    : gpu::kShadeGlossy;
    push.gridOrigin = mLayout.gridOrigin;
    push.gridCellSize = mLayout.gridCellSize;
    push.gridDims = mLayout.gridDims;
    push.lightCount = direct ? uint32_t(lights.lights.size()) : 0u;
    push.width = params.width;
    push.height = params.height;
    push.lightmapWidth = mLayout.lightmapWidth;
    push.lightmapHeight = mLayout.lightmapHeight;
    push.epsilon = mEpsilon;
    // The CPU twin adds the lobe only when both its exponent and weight are positive.
    const bool glossy = params.glossyExponent > 0.0f && params.glossyWeight > 0.0f;
    push.glossyWeight = glossy ? params.glossyWeight : 0.0f;
    push.yScale = lights.indirectScale.y;
    push.cocgScale = lights.indirectScale.cocg;
    for (int l = 0; l < kMaxShBands; ++l)
        push.glossyLobe[l / 4][l % 4] = glossy ? cosineLobeFactor(l, params.glossyExponent) : 0.0f;

    PIC_TRY(mContext.submit(
        [&](VkCommandBuffer cmd) {
            if (direct) {
                mTimer.begin(cmd, "shadow_maps");
                mShadows->record(cmd, {});
            }
            // One G-buffer and one shading pass per subsample (the CPU twin's offsets and
            // footprints, render/cpu/cache_shading.h), each adding to the pixel's sum.
            const uint32_t n = params.samplesPerPixel;
            for (uint32_t s = 0; s < n; ++s) {
                if (s == 1) mTimer.begin(cmd, "subsamples");
                if (s == 0) mTimer.begin(cmd, "gbuffer");
                frame.gbuffer =
                    gpu::gbufferPushOf(camera, params.width, params.height, near,
                                       subsampleOffset(s, n), 1.0f / std::sqrt(float(n)));
                mGbuffer->record(cmd, frame);
                if (s == 0) mTimer.begin(cmd, "cache_shading");
                if (s > 0) {
                    // The previous subsample's sums are written before this one adds to them.
                    VkMemoryBarrier sums{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
                    sums.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
                    sums.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT;
                    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                                         VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 1, &sums, 0,
                                         nullptr, 0, nullptr);
                }
                push.accumulate = s > 0 ? 1u : 0u;
                mShading->record(cmd, frame);
            }
            // The shader's writes are visible to the host's read of the radiance.
            VkMemoryBarrier toHost{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
            toHost.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
            toHost.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
            vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                                 VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &toHost, 0, nullptr, 0, nullptr);
        },
        &mTimer));

    std::vector<glm::vec4> radiance(size_t{params.width} * params.height);
    PIC_TRY(mContext.download(mRadiance, radiance.data(), radianceBytes));
    Image image(params.width, params.height);
    // The CPU twin's average: the sum over subsamples divided by their number.
    const float n = float(params.samplesPerPixel);
    for (size_t i = 0; i < radiance.size(); ++i) image.pixels[i] = glm::vec3(radiance[i]) / n;

    if (timings) {
        timings->passMs.clear();
        PIC_TRY(mTimer.collect(timings->passMs));
        timings->shadowMapsRendered = direct ? mShadows->renderedLights() : 0u;
        timings->totalMs = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    } else {
        std::vector<std::pair<std::string, double>> unused;
        PIC_TRY(mTimer.collect(unused));
    }
    return image;
}

}  // namespace pic
