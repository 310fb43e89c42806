#pragma once
/// What the GPU runtime's tests and its passes' tests share: the small bake of a test scene that
/// they light, the GPU runtime over it, the CPU twin's node flux and the relative distance
/// between two sets of cache values.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "core/cache_values.h"
#include "core/light_set.h"
#include "render/gpu_runtime.h"
#include "tests/support/baked_scene.h"

namespace pic::test {

/// Test scene `name` with a small bake of `mode` links and lY = bandsY, lC = bandsC: 4096
/// surfels, 64 links per cache, grid cell 0.12 and light-map texel 0.06 of the scene's diagonal;
/// made once per (scene, link form, lY, lC) for the process.
const BakedScene& smallBake(const std::string& name, LinkMode mode, uint32_t bandsY = 3,
                            uint32_t bandsC = 2);

/// The GPU runtime over `b`, or null with a test failure. (A machine without any Vulkan
/// device fails here: CI has lavapipe, so there these tests run.)
std::unique_ptr<GpuRuntime> gpuFor(const BakedScene& b, BounceParams bounces = {},
                                   const GpuRuntimeOptions& options = {});

/// The scene's own lights and a copy of the first, named "second", moved by (0.1, −0.2,
/// 0.05) m: what the tests of per-light visibility reuse change, one light at a time.
LightSet twoLights(const Scene& scene);

/// ‖a − b‖ / ‖b‖ over all coefficients of all channels.
double relativeL2(const CacheValues& a, const CacheValues& b);

/// Node flux of `lights` by the CPU twin: direct surfel flux, pulled.
std::vector<glm::vec3> cpuNodeFlux(const BakedScene& b, const LightSet& lights);

}  // namespace pic::test
