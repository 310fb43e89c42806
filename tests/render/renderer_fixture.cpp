// What the renderer and cache-shading tests share (tests/render/renderer_fixture.h).

#include "tests/render/renderer_fixture.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include <gtest/gtest.h>

#include "core/cache_textures.h"
#include "render/cpu/cache_shading.h"
#include "render/cpu_runtime.h"
#include "tests/support/baked_scene.h"

namespace pic::test {

gpu::Context* sharedContext() {
    static std::unique_ptr<gpu::Context> shared = [] {
        auto created = gpu::Context::create();
        EXPECT_TRUE(created) << created.error().message;
        return created ? std::move(*created) : nullptr;
    }();
    return shared.get();
}

const LitScene& litScene(const std::string& name) {
    static std::map<std::string, std::unique_ptr<LitScene>> cache;
    auto& slot = cache[name];
    if (slot) return *slot;
    const BakedScene& b = bakedScene(name, smallBakeOptions(2048, 32), 0.12f, 0.04f);
    slot.reset(new LitScene{b.scene, b.rays.get(), b.bake, {}, false});
    if (!b.ok) return *slot;
    auto runtime = createCpuRuntime(b.scene, *b.rays, b.bake, BounceParams{});
    EXPECT_TRUE(runtime);
    if (!runtime) return *slot;
    auto values = (*runtime)->setLights(defaultLightSet(b.scene), nullptr);
    EXPECT_TRUE(values) << (values ? "" : values.error().message);
    if (!values) return *slot;
    slot->values = **values;
    slot->ok = true;
    return *slot;
}

CacheTextures texturesOf(const BakeData& bake, const CacheValues& values) {
    CacheTextures textures = makeCacheTextures(bake);
    copyCachesToTextures(bake, values, textures);
    return textures;
}

std::unique_ptr<Renderer> rendererFor(const Scene& scene, const BakeData& bake,
                                      const CacheValues& values) {
    gpu::Context* gpu = sharedContext();
    if (!gpu) return nullptr;
    auto renderer = Renderer::create(*gpu, scene, clientLayoutOf(bake));
    if (!renderer) {
        ADD_FAILURE() << renderer.error().message;
        return nullptr;
    }
    if (auto ok = (*renderer)->setCaches(texturesOf(bake, values)); !ok) {
        ADD_FAILURE() << ok.error().message;
        return nullptr;
    }
    return std::move(*renderer);
}

int expectFiniteNonNegative(const Image& image, const char* what) {
    int positive = 0;
    for (size_t i = 0; i < image.pixels.size(); ++i) {
        const glm::vec3& p = image.pixels[i];
        for (int c = 0; c < 3; ++c)
            EXPECT_TRUE(std::isfinite(p[c]) && p[c] >= 0.0f)
                << what << ": pixel " << i << " channel " << c << " is " << p[c];
        positive += (p.r > 0.0f || p.g > 0.0f || p.b > 0.0f) ? 1 : 0;
    }
    return positive;
}

Comparison compare(Renderer& renderer, const Scene& scene, const EmbreeScene& rays,
                   const BakeData& bake, const CacheValues& values, const LightSet& lights,
                   const Camera& camera, const ShadeParams& params) {
    Comparison out;
    auto gpu = renderer.render(lights, camera, params);
    EXPECT_TRUE(gpu) << (gpu ? "" : gpu.error().message);
    auto cpu = shadeFromCaches(scene, rays, bake, values, lights, camera, params);
    EXPECT_TRUE(cpu) << (cpu ? "" : cpu.error().message);
    if (!gpu || !cpu) return out;
    out.gpu = std::move(*gpu);
    out.cpu = std::move(*cpu);
    auto error = compareImages(out.gpu, out.cpu);
    EXPECT_TRUE(error);
    if (error) out.error = *error;
    double mean = 0.0;
    for (const glm::vec3& p : out.cpu.pixels) mean += (p.r + p.g + p.b) / 3.0;
    mean /= double(out.cpu.pixels.size());
    size_t differing = 0;
    for (size_t i = 0; i < out.cpu.pixels.size(); ++i) {
        const glm::vec3 d = glm::abs(out.gpu.pixels[i] - out.cpu.pixels[i]);
        differing += std::max({d.r, d.g, d.b}) > 0.05 * mean ? 1 : 0;
    }
    out.differing = double(differing) / double(out.cpu.pixels.size());
    return out;
}

void report(const char* what, const Comparison& c) {
    std::printf("[ measured ] %s: relative RMSE %.5f, mean ratio %.5f, pixels off > 5 %%: %.4f\n",
                what, c.error.relativeRmse, c.error.meanRatio, c.differing);
}

}  // namespace pic::test
