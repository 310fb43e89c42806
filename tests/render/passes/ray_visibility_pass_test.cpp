// The ray-visibility pass (shadow rays traced on the host with Embree) through the GPU runtime:
// only lights that changed are traced again, a light set that outgrows the visibility buffer
// retraces every light, and after any sequence of changes the caches equal those of a runtime
// that saw only the final light set.

#include <gtest/gtest.h>

#include "core/light_set.h"
#include "tests/render/gpu_fixture.h"

namespace pic {
namespace {

TEST(GpuRayVisibility, OnlyLightsThatChangedAreRetracedAndMoreLightsKeepTheirBits) {
    const test::BakedScene& b = test::smallBake("cornell", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    const GpuRuntimeOptions options{.directVisibility = gpu::DirectVisibility::Rays};
    auto gpu = test::gpuFor(b, BounceParams{1}, options);
    ASSERT_TRUE(gpu);
    LightSet lights = test::twoLights(b.scene);
    ASSERT_EQ(lights.lights.size(), 2u);
    const Light second = lights.lights[1];
    UpdateStats stats;
    ASSERT_TRUE(gpu->setLights(lights, &stats));
    EXPECT_EQ(stats.lightsTraced, 2);
    EXPECT_EQ(stats.shadowMapsRendered, 0);
    ASSERT_TRUE(gpu->setLights(lights, &stats));
    EXPECT_EQ(stats.lightsTraced, 0);
    // Colour and intensity do not change what a light reaches.
    lights.lights[1].intensity *= 2.0f;
    lights.lights[1].color = {1.0f, 0.5f, 0.25f};
    ASSERT_TRUE(gpu->setLights(lights, &stats));
    EXPECT_EQ(stats.lightsTraced, 0);
    // Moving one light retraces that light only; so does a new cone.
    lights.lights[1].position.x += 0.05f;
    ASSERT_TRUE(gpu->setLights(lights, &stats));
    EXPECT_EQ(stats.lightsTraced, 1);
    // A third light outgrows the visibility buffer: every light is traced into the new one.
    Light third = second;
    third.id = "third";
    third.position.z -= 0.1f;
    lights.lights.push_back(third);
    ASSERT_TRUE(gpu->setLights(lights, &stats));
    EXPECT_EQ(stats.lightsTraced, 3);
    // Dropping the first light shifts the others onto its slot: both are traced again.
    lights.lights.erase(lights.lights.begin());
    auto updated = gpu->setLights(lights, &stats);
    ASSERT_TRUE(updated) << updated.error().message;
    EXPECT_EQ(stats.lightsTraced, 2);
    // After all that, the same caches as a runtime that saw only this light set.
    auto fresh = test::gpuFor(b, BounceParams{1}, options);
    ASSERT_TRUE(fresh);
    auto expected = fresh->setLights(lights, nullptr);
    ASSERT_TRUE(expected) << expected.error().message;
    EXPECT_EQ((*updated)->y, (*expected)->y);
    EXPECT_EQ((*updated)->co, (*expected)->co);
    EXPECT_EQ(gpu->context().validationMessages(), 0u);
}

}  // namespace
}  // namespace pic
