// What the GPU runtime and pass tests share (tests/render/gpu_fixture.h).

#include "tests/render/gpu_fixture.h"

#include <cmath>
#include <span>

#include <gtest/gtest.h>

#include "render/cpu/pull.h"
#include "render/cpu/surfel_lighting.h"

namespace pic::test {

const BakedScene& smallBake(const std::string& name, LinkMode mode, uint32_t bandsY,
                            uint32_t bandsC) {
    BakeOptions options = smallBakeOptions(4096, 64);
    options.linkMode = mode;
    options.bandsY = bandsY;
    options.bandsC = bandsC;
    return bakedScene(name, options, 0.12f, 0.06f);
}

std::unique_ptr<GpuRuntime> gpuFor(const BakedScene& b, BounceParams bounces,
                                   const GpuRuntimeOptions& options) {
    auto runtime = GpuRuntime::create(b.scene, *b.rays, b.bake, bounces, options);
    if (!runtime) {
        ADD_FAILURE() << runtime.error().message;
        return nullptr;
    }
    return std::move(*runtime);
}

LightSet twoLights(const Scene& scene) {
    LightSet lights = defaultLightSet(scene);
    EXPECT_FALSE(lights.lights.empty()) << scene.sourcePath;
    if (lights.lights.empty()) return lights;
    Light second = lights.lights[0];
    second.id = "second";
    second.position += glm::vec3(0.1f, -0.2f, 0.05f);
    lights.lights.push_back(second);
    return lights;
}

double relativeL2(const CacheValues& a, const CacheValues& b) {
    double diff = 0.0, norm = 0.0;
    const std::vector<float>* pa[3] = {&a.y, &a.co, &a.cg};
    const std::vector<float>* pb[3] = {&b.y, &b.co, &b.cg};
    for (int ch = 0; ch < 3; ++ch) {
        EXPECT_EQ(pa[ch]->size(), pb[ch]->size());
        for (size_t i = 0; i < pb[ch]->size(); ++i) {
            const double d = double((*pa[ch])[i]) - double((*pb[ch])[i]);
            diff += d * d;
            norm += double((*pb[ch])[i]) * (*pb[ch])[i];
        }
    }
    return norm > 0.0 ? std::sqrt(diff / norm) : std::sqrt(diff);
}

std::vector<glm::vec3> cpuNodeFlux(const BakedScene& b, const LightSet& lights) {
    std::vector<glm::vec3> nodes(b.bake.nodes.size());
    directSurfelFlux(b.scene, *b.rays, b.bake, lights,
                     std::span<glm::vec3>(nodes.data(), b.bake.surfels.size()));
    pullFlux(b.bake, nodes);
    return nodes;
}

}  // namespace pic::test
