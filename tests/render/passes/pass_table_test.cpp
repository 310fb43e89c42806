// The pass table (render/passes/pass_table.cpp): one row per pass kind, each named after its
// files, and every row makes its own pass class from one config of a small bake.

#include <gtest/gtest.h>

#include <set>
#include <string>

#include "core/cache_textures.h"
#include "render/node_spread.h"
#include "render/passes/cache_lighting_pass.h"
#include "render/passes/cache_shading_pass.h"
#include "render/passes/gbuffer_pass.h"
#include "render/passes/lightmap_copy_pass.h"
#include "render/passes/pass.h"
#include "render/passes/pull_pass.h"
#include "render/passes/ray_visibility_pass.h"
#include "render/passes/shadow_map_pass.h"
#include "render/passes/sky_caches_pass.h"
#include "render/passes/surfel_lighting_pass.h"
#include "tests/render/gpu_fixture.h"
#include "tests/render/renderer_fixture.h"

namespace pic {
namespace {

TEST(PassTable, OneRowPerKindNamedAfterItsFiles) {
    std::set<std::string> names;
    for (size_t i = 0; i < gpu::kPassKinds; ++i) {
        const gpu::PassEntry& row = gpu::passTable()[i];
        EXPECT_EQ(row.kind, gpu::PassKind(i));
        ASSERT_NE(row.create, nullptr);
        const std::string name = row.name;
        EXPECT_TRUE(names.insert(name).second) << name;
        // The base name of render/passes/<name>_pass.h and shaders/<name>.*.
        EXPECT_EQ(name.find_first_not_of("abcdefghijklmnopqrstuvwxyz_"), std::string::npos) << name;
    }
}

/// Whether `pass` is of class T.
template <class T>
bool madeAs(const Result<std::unique_ptr<gpu::Pass>>& pass) {
    return pass && dynamic_cast<const T*>(pass->get()) != nullptr;
}

TEST(PassTable, EveryRowMakesItsPass) {
    const test::BakedScene& b = test::smallBake("cornell", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    gpu::Context* context = test::sharedContext();
    ASSERT_TRUE(context);
    const NodeSpread spread = nodeSpread(b.bake);
    const ClientLayout layout = clientLayoutOf(b.bake);
    const gpu::PassConfig config{
        .scene = &b.scene,
        .bake = &b.bake,
        .rays = b.rays.get(),
        .spread = &spread,
        .shadowMapSize = 64,
        .triangleUvs = layout.triangleUvs,
        .bandsY = layout.bandsY,
        .bandsC = layout.bandsC,
        .gridDims = layout.gridDims,
        .lightmapSize = {layout.lightmapWidth, layout.lightmapHeight},
    };
    const auto make = [&](gpu::PassKind kind) {
        auto pass = gpu::createPass(kind, *context, config);
        EXPECT_TRUE(pass) << gpu::passTable()[size_t(kind)].name << ": " << pass.error().message;
        return pass;
    };
    using gpu::PassKind;
    EXPECT_TRUE(madeAs<gpu::ShadowMapPass>(make(PassKind::ShadowMap)));
    EXPECT_TRUE(madeAs<gpu::RayVisibilityPass>(make(PassKind::RayVisibility)));
    EXPECT_TRUE(madeAs<gpu::SurfelLightingPass>(make(PassKind::SurfelLighting)));
    EXPECT_TRUE(madeAs<gpu::PullPass>(make(PassKind::Pull)));
    EXPECT_TRUE(madeAs<gpu::CacheLightingPass>(make(PassKind::CacheLighting)));
    EXPECT_TRUE(madeAs<gpu::SkyCachesPass>(make(PassKind::SkyCaches)));
    EXPECT_TRUE(madeAs<gpu::LightmapCopyPass>(make(PassKind::LightmapCopy)));
    EXPECT_TRUE(madeAs<gpu::GbufferPass>(make(PassKind::Gbuffer)));
    EXPECT_TRUE(madeAs<gpu::CacheShadingPass>(make(PassKind::CacheShading)));
    EXPECT_EQ(context->validationMessages(), 0u);
}

}  // namespace
}  // namespace pic
