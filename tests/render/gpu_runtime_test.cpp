// Every GPU pass on lavapipe (or whatever Vulkan device the machine has) against its CPU twin
// on identical inputs, the whole GPU runtime against the CPU runtime, shadow maps rendered
// only for lights that changed, and Vulkan failures returned as errors.

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "bake/bake.h"
#include "core/color.h"
#include "core/gltf_loader.h"
#include "core/light_set.h"
#include "rays/embree_scene.h"
#include "render/copy_probe.h"
#include "render/cpu/cache_lighting.h"
#include "render/cpu/lightmap_copy.h"
#include "render/cpu/pull.h"
#include "render/cpu/surfel_lighting.h"
#include "render/cpu_runtime.h"
#include "render/gpu_runtime.h"
#include "render/passes/cache_lighting_pass.h"
#include "render/passes/pull_pass.h"
#include "shaders/shared/pull.h"

namespace pic {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

/// A test scene, its rays and a small bake per (scene, link form, lY, lC), shared.
struct Baked {
    Scene scene;
    std::unique_ptr<EmbreeScene> rays;
    BakeData bake;
    bool ok = false;
};

const Baked& baked(const std::string& name, LinkMode mode, uint32_t bandsY = 3, uint32_t bandsC = 2) {
    static std::map<std::tuple<std::string, LinkMode, uint32_t, uint32_t>, std::unique_ptr<Baked>> cache;
    auto& slot = cache[{name, mode, bandsY, bandsC}];
    if (slot) return *slot;
    slot = std::make_unique<Baked>();
    auto scene = loadScene(std::string(PIC_TEST_SCENE_DIR) + "/" + name + ".gltf");
    EXPECT_TRUE(scene) << name;
    if (!scene) return *slot;
    slot->scene = std::move(*scene);
    auto rays = EmbreeScene::create(slot->scene);
    EXPECT_TRUE(rays);
    if (!rays) return *slot;
    slot->rays = std::move(*rays);
    BakeOptions options;
    options.surfels = 4096;
    options.links = 64;
    options.linkMode = mode;
    options.bandsY = bandsY;
    options.bandsC = bandsC;
    const float extent = slot->scene.bounds.diagonal();
    options.gridCell = 0.12f * extent;
    options.lightmapTexel = 0.06f * extent;
    BakeReport report;
    auto bake = runBake(slot->scene, options, report);
    EXPECT_TRUE(bake) << name << ": " << (bake ? "" : bake.error().message);
    if (!bake) return *slot;
    slot->bake = std::move(*bake);
    slot->ok = true;
    return *slot;
}

/// The GPU runtime, or a skip when the machine has no Vulkan device at all (CI has lavapipe,
/// so there these tests run).
std::unique_ptr<GpuRuntime> gpuFor(const Baked& b, BounceParams bounces = {},
                                   const GpuRuntimeOptions& options = {}) {
    auto runtime = GpuRuntime::create(b.scene, *b.rays, b.bake, bounces, options);
    if (!runtime) {
        ADD_FAILURE() << runtime.error().message;
        return nullptr;
    }
    return std::move(*runtime);
}

/// ‖a − b‖ / ‖b‖ over all coefficients of all channels.
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

/// Node flux of the scene's lights: CPU direct surfel flux, pulled.
std::vector<glm::vec3> cpuNodeFlux(const Baked& b, const LightSet& lights) {
    std::vector<glm::vec3> nodes(b.bake.nodes.size());
    directSurfelFlux(b.scene, *b.rays, b.bake, lights,
                     std::span<glm::vec3>(nodes.data(), b.bake.surfels.size()));
    pullFlux(b.bake, nodes);
    return nodes;
}

/// Fraction of surfels whose GPU flux differs from the CPU's by more than 1 % of the larger
/// (per channel, ignoring differences below 1e−6 of the brightest surfel).
double fractionDiffering(const std::vector<glm::vec3>& gpu, const std::vector<glm::vec3>& cpu) {
    float brightest = 0.0f;
    for (const glm::vec3& f : cpu) brightest = std::max({brightest, f.r, f.g, f.b});
    size_t differing = 0;
    for (size_t i = 0; i < cpu.size(); ++i) {
        for (int c = 0; c < 3; ++c) {
            const float d = std::abs(gpu[i][c] - cpu[i][c]);
            if (d > 0.01f * std::max(std::abs(cpu[i][c]), std::abs(gpu[i][c])) && d > 1e-6f * brightest) {
                ++differing;
                break;
            }
        }
    }
    return double(differing) / double(cpu.size());
}

TEST(GpuPull, NodeFluxIsExact) {
    const Baked& b = baked("cornell", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    // Both of the pull's modes run: large levels a dispatch each, the small upper ones as
    // the tail.
    const std::vector<uint32_t>& offsets = b.bake.levelOffsets;
    ASSERT_GT(offsets[1] - offsets[0], gpu::kPullTailNodes);
    ASSERT_LE(offsets.back() - offsets[offsets.size() - 2], gpu::kPullTailNodes);
    auto gpu = gpuFor(b);
    ASSERT_TRUE(gpu);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.0f, 2.0f);
    std::vector<glm::vec3> nodes(b.bake.nodes.size(), glm::vec3(0.0f));
    for (size_t i = 0; i < b.bake.surfels.size(); ++i) nodes[i] = {u(rng), u(rng), u(rng)};
    auto pulled = gpu->runPull(std::span<const glm::vec3>(nodes.data(), b.bake.surfels.size()));
    ASSERT_TRUE(pulled) << pulled.error().message;
    pullFlux(b.bake, nodes);
    // Each inner node is one float addition of the same two children: bit-exact.
    for (size_t n = 0; n < nodes.size(); ++n) ASSERT_EQ((*pulled)[n], nodes[n]) << "node " << n;
}

TEST(GpuPull, NodeRadianceIsFluxOverPiAreaAsRgbe8) {
    const Baked& b = baked("cornell", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    auto gpu = gpuFor(b, {}, {.directVisibility = gpu::DirectVisibility::Rays});
    ASSERT_TRUE(gpu);
    const size_t nS = b.bake.surfels.size();
    // Leaves: surfel lighting packs flux / (π·A), its division rounded by the device, so the
    // code may differ from the host's by one mantissa step (at most 2^-7 of the largest
    // channel) besides the rounding (2^-8).
    auto direct = gpu->runDirect(defaultLightSet(b.scene));
    ASSERT_TRUE(direct) << direct.error().message;
    auto leaves = gpu->nodeRadiance();
    ASSERT_TRUE(leaves) << leaves.error().message;
    size_t lit = 0;
    for (size_t i = 0; i < nS; ++i) {
        const glm::vec3 expected = (*direct)[i] / (kPi * b.bake.surfels[i].area);
        const glm::vec3 got = unpackRgbe8((*leaves)[i]);
        const float largest = std::max({expected.r, expected.g, expected.b});
        if (largest > 0.0f) ++lit;
        for (int c = 0; c < 3; ++c)
            ASSERT_LE(std::abs(got[c] - expected[c]), largest / 64.0f) << "surfel " << i;
    }
    EXPECT_GT(lit, nS / 4);

    // Inner nodes: the pull's float sum times the uploaded 1 / (π·A), packed with the same
    // exact operations as packRgbe8: bit for bit.
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0.0f, 3.0f);
    std::vector<glm::vec3> flux(nS);
    for (glm::vec3& f : flux) f = {u(rng), u(rng), u(rng)};
    auto pulled = gpu->runPull(flux);
    ASSERT_TRUE(pulled) << pulled.error().message;
    auto radiance = gpu->nodeRadiance();
    ASSERT_TRUE(radiance) << radiance.error().message;
    for (size_t n = nS; n < b.bake.nodes.size(); ++n)
        ASSERT_EQ((*radiance)[n],
                  packRgbe8((*pulled)[n] * gpu::radianceScale(b.bake.nodes[n].area)))
            << "node " << n;
}

TEST(GpuCacheLighting, RtpLinksPackIntoTwelveBytes) {
    // factor = V / (π·A) (bake/link_generation.cpp); the GPU keeps V as unorm16.
    const float area = 0.37f;
    const auto pack = [&](float visible, float oneMinusCos) {
        const gpu::RtpLink link{42, visible / (kPi * area), encodeOctahedral({0, 0, 1}),
                                oneMinusCos};
        return gpu::packRtpLink(link, area);
    };
    const auto visibleOf = [](const gpu::GpuRtpLink& l) {
        return float(l.visibleAndCone & 0xFFFFu) / 65535.0f;
    };
    const auto coneOf = [](const gpu::GpuRtpLink& l) {
        return halfToFloat(uint16_t(l.visibleAndCone >> 16));
    };
    for (const float visible : {1.0f, 0.75f, 0.3f, 1e-3f}) {
        for (const float oneMinusCos : {2.0f, 0.5f, 1e-2f, 3e-5f, 1e-7f}) {
            const gpu::GpuRtpLink l = pack(visible, oneMinusCos);
            EXPECT_EQ(l.node, 42u);
            EXPECT_EQ(l.directionOct, encodeOctahedral({0, 0, 1}));
            EXPECT_NEAR(visibleOf(l), visible, 0.5f / 65535.0f + 1e-6f * visible);
            // binary16: relative 2^-11 for normal values, 2^-25 absolute below 2^-14.
            EXPECT_NEAR(coneOf(l), oneMinusCos, std::max(oneMinusCos / 2048.0f, 3e-8f));
        }
    }
    // A link too faint for unorm16 keeps one step instead of reading as padding; padding
    // (factor 0) stays 0; rounding never takes V past 1.
    EXPECT_EQ(pack(1e-7f, 0.1f).visibleAndCone & 0xFFFFu, 1u);
    EXPECT_EQ(pack(0.0f, 0.1f).visibleAndCone & 0xFFFFu, 0u);
    EXPECT_EQ(pack(1.0001f, 0.1f).visibleAndCone & 0xFFFFu, 65535u);

    // SH links: c·π·A in binary16, saturating.
    const float c = 123.5f / (kPi * area);
    EXPECT_NEAR(halfToFloat(gpu::radianceShCoefficient(floatToHalf(c), area)), 123.5f, 0.1f);
    EXPECT_EQ(gpu::radianceShCoefficient(floatToHalf(-60000.0f), 10.0f), floatToHalf(-65504.0f));
    EXPECT_EQ(gpu::radianceShCoefficient(floatToHalf(5.0f), 0.0f), floatToHalf(0.0f));
}

/// Cache lighting for a link form and band split, each cache lit by a subgroup (as on a
/// GPU) or by an invocation (as on a CPU device), the links read in the widest texels the
/// device has or a word at a time.
class GpuCacheLighting : public testing::TestWithParam<
                             std::tuple<std::tuple<LinkMode, uint32_t, uint32_t>, bool, uint32_t>> {
};

TEST_P(GpuCacheLighting, MatchesTheCpuTwinWithinOnePercent) {
    const auto [form, perSubgroup, texelWords] = GetParam();
    const auto [mode, bandsY, bandsC] = form;
    const Baked& b = baked("cornell", mode, bandsY, bandsC);
    ASSERT_TRUE(b.ok);
    auto gpu = gpuFor(b, {}, {.cachePerSubgroup = perSubgroup, .maxLinkTexelWords = texelWords});
    ASSERT_TRUE(gpu);
    // A link is 3 words (RTP) or 1 + ⌈lY²/2⌉; every device reads single words, and lavapipe
    // texels of 2, 3 and 4 words, of which the pass takes 4 or 2 before 3.
    const uint32_t linkWords = mode == LinkMode::Rtp ? 3 : gpu::shLinkWords(bandsY * bandsY);
    EXPECT_EQ(linkWords % gpu->linkTexelWords(), 0u);
    EXPECT_LE(gpu->linkTexelWords(), texelWords);
    if (texelWords == 1) {
        EXPECT_EQ(gpu->linkTexelWords(), 1u);
    }
    if (gpu->context().isCpuDevice() && texelWords == 4) {
        const uint32_t expected = linkWords % 4 == 0   ? 4
                                  : linkWords % 2 == 0 ? 2
                                  : linkWords % 3 == 0 ? 3
                                                       : 1;
        EXPECT_EQ(gpu->linkTexelWords(), expected);
    }
    const std::vector<glm::vec3> nodes = cpuNodeFlux(b, defaultLightSet(b.scene));
    CacheValues cpu;
    lightCaches(b.bake, nodes, cpu);
    auto values = gpu->runCacheLighting(nodes);
    ASSERT_TRUE(values) << values.error().message;
    ASSERT_EQ(values->bandsY, bandsY);
    ASSERT_EQ(values->bandsC, bandsC);
    EXPECT_LE(relativeL2(*values, cpu), 0.01);
    EXPECT_GT(relativeL2(cpu, CacheValues::zeros(cpu.cacheCount(), bandsY, bandsC)), 0.0);
}

INSTANTIATE_TEST_SUITE_P(LinkFormsAndBands, GpuCacheLighting,
                         testing::Combine(testing::Values(std::make_tuple(LinkMode::Rtp, 3u, 2u),
                                                          std::make_tuple(LinkMode::Rtp, 4u, 1u),
                                                          std::make_tuple(LinkMode::Rtp, 2u, 2u),
                                                          std::make_tuple(LinkMode::Sh, 3u, 2u),
                                                          std::make_tuple(LinkMode::Sh, 4u, 2u),
                                                          std::make_tuple(LinkMode::Sh, 1u, 1u)),
                                          testing::Bool(), testing::Values(4u)));
INSTANTIATE_TEST_SUITE_P(WordTexels, GpuCacheLighting,
                         testing::Combine(testing::Values(std::make_tuple(LinkMode::Rtp, 3u, 2u),
                                                          std::make_tuple(LinkMode::Sh, 3u, 2u)),
                                          testing::Bool(), testing::Values(1u)));

/// Largest relative difference of a GPU flux from the CPU's over surfels and channels
/// (differences below 1e−6 of the brightest surfel ignored).
double largestDifference(const std::vector<glm::vec3>& gpu, const std::vector<glm::vec3>& cpu) {
    float brightest = 0.0f;
    for (const glm::vec3& f : cpu) brightest = std::max({brightest, f.r, f.g, f.b});
    double largest = 0.0;
    for (size_t i = 0; i < cpu.size(); ++i)
        for (int c = 0; c < 3; ++c) {
            const double d = std::abs(double(gpu[i][c]) - double(cpu[i][c]));
            if (d > 1e-6 * brightest)
                largest = std::max(largest, d / std::max(std::abs(double(cpu[i][c])), 1e-30));
        }
    return largest;
}

/// Direct surfel flux for a scene and light set, with the visibility of shadow maps (within
/// the bound) and of rays (the CPU twin's own rays: equal to float rounding).
void expectDirectMatches(const Baked& b, const LightSet& lights) {
    std::vector<glm::vec3> cpu(b.bake.surfels.size());
    directSurfelFlux(b.scene, *b.rays, b.bake, lights, cpu);
    auto rays = gpuFor(b, {}, {.directVisibility = gpu::DirectVisibility::Rays});
    ASSERT_TRUE(rays);
    auto traced = rays->runDirect(lights);
    ASSERT_TRUE(traced) << traced.error().message;
    EXPECT_LE(largestDifference(*traced, cpu), 1e-4);

    auto gpu = gpuFor(b, {}, {.directVisibility = gpu::DirectVisibility::ShadowMaps});
    ASSERT_TRUE(gpu);
    auto direct = gpu->runDirect(lights);
    ASSERT_TRUE(direct) << direct.error().message;
    // Shadow maps and exact rays disagree only where a shadow edge crosses a surfel.
    EXPECT_LE(fractionDiffering(*direct, cpu), 0.01);
    double gpuSum = 0.0, cpuSum = 0.0;
    for (size_t i = 0; i < cpu.size(); ++i) {
        gpuSum += (*direct)[i].g;
        cpuSum += cpu[i].g;
    }
    EXPECT_GT(cpuSum, 0.0);
    EXPECT_NEAR(gpuSum / cpuSum, 1.0, 0.01);
}

TEST(GpuSurfelLighting, DirectFluxOfPointLightMatchesRays) {
    const Baked& b = baked("cornell", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    expectDirectMatches(b, defaultLightSet(b.scene));
}

TEST(GpuSurfelLighting, DirectFluxOfSpotMatchesRays) {
    const Baked& b = baked("small_spot", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    expectDirectMatches(b, defaultLightSet(b.scene));
}

TEST(GpuSurfelLighting, SimplifiedCastersKeepTheDirectFlux) {
    // The atrium's columns are finely tessellated: its sun's orthographic layer draws the
    // coarsest level of detail (ShadowCasters.LevelsOfDetail*). That must not move shadows
    // by more than the map's texels do: against the exact casters, direct flux changes on
    // few surfels, and against the rays it is as good as the exact casters' within 0.2 % of
    // the surfels.
    const Baked& b = baked("atrium", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    const LightSet lights = defaultLightSet(b.scene);
    std::vector<glm::vec3> rays(b.bake.surfels.size());
    directSurfelFlux(b.scene, *b.rays, b.bake, lights, rays);
    std::vector<glm::vec3> direct[2];
    for (const bool levels : {false, true}) {
        auto runtime = GpuRuntime::create(b.scene, *b.rays, b.bake, {},
                                          {.casterLevelsOfDetail = levels,
                                           .directVisibility = gpu::DirectVisibility::ShadowMaps});
        ASSERT_TRUE(runtime) << runtime.error().message;
        auto flux = (*runtime)->runDirect(lights);
        ASSERT_TRUE(flux) << flux.error().message;
        direct[levels] = std::move(*flux);
    }
    EXPECT_LE(fractionDiffering(direct[true], direct[false]), 0.005);
    EXPECT_LE(fractionDiffering(direct[true], rays), fractionDiffering(direct[false], rays) + 0.002);
    double exactSum = 0.0, simplifiedSum = 0.0;
    for (size_t i = 0; i < rays.size(); ++i) {
        exactSum += direct[false][i].g;
        simplifiedSum += direct[true][i].g;
    }
    EXPECT_GT(exactSum, 0.0);
    EXPECT_NEAR(simplifiedSum / exactSum, 1.0, 0.005);
}

TEST(GpuSurfelLighting, DirectFluxOfEveryLightTypeMatchesRays) {
    // Two floors, lit by a point light, a narrow spot (one perspective layer), a wide spot
    // (cube) and a directional light (orthographic) at once.
    const Baked& b = baked("two_floors", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    LightSet lights = defaultLightSet(b.scene);
    const glm::vec3 c = b.scene.bounds.center();
    Light narrow;
    narrow.id = "narrow";
    narrow.type = LightType::Spot;
    narrow.position = c + glm::vec3(0.3f, 0.2f, 0.1f);
    narrow.direction = glm::normalize(glm::vec3(0.2f, -1.0f, 0.1f));
    narrow.outerConeAngle = 0.5f;
    narrow.innerConeAngle = 0.3f;
    narrow.intensity = 3.0f;
    Light wide = narrow;
    wide.id = "wide";
    wide.position = c + glm::vec3(-0.4f, -0.3f, -0.2f);
    wide.outerConeAngle = 1.4f;
    wide.innerConeAngle = 1.4f;
    Light sun;
    sun.id = "sun";
    sun.type = LightType::Directional;
    sun.direction = glm::normalize(glm::vec3(0.3f, -1.0f, 0.2f));
    sun.intensity = 2.0f;
    lights.lights.insert(lights.lights.end(), {narrow, wide, sun});
    expectDirectMatches(b, lights);
}

TEST(GpuSurfelLighting, BounceMatchesTheCpuTwin) {
    const Baked& b = baked("cornell", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    auto gpu = gpuFor(b);
    ASSERT_TRUE(gpu);
    const LightSet lights = defaultLightSet(b.scene);
    const std::vector<glm::vec3> nodes = cpuNodeFlux(b, lights);
    CacheValues caches;
    lightCaches(b.bake, nodes, caches);
    const std::vector<glm::vec3> direct(nodes.begin(), nodes.begin() + b.bake.surfels.size());
    std::vector<glm::vec3> cpu(direct.size());
    bounceSurfelFlux(b.scene, b.bake, direct, caches, cpu);
    auto leaves = gpu->runBounce(direct, caches);
    ASSERT_TRUE(leaves) << leaves.error().message;
    // The GPU reads the caches as half floats: agreement to ~0.1 %, well inside 1 %.
    EXPECT_LE(fractionDiffering(*leaves, cpu), 0.001);
}

TEST(GpuLightmapCopy, TexturesMatchTheCpuTwin) {
    const Baked& b = baked("cornell", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    auto gpu = gpuFor(b);
    ASSERT_TRUE(gpu);
    CacheValues caches;
    lightCaches(b.bake, cpuNodeFlux(b, defaultLightSet(b.scene)), caches);
    CacheTextures cpu = makeCacheTextures(b.bake);
    copyCachesToTextures(b.bake, caches, cpu);
    auto textures = gpu->runLightmapCopy(caches);
    ASSERT_TRUE(textures) << textures.error().message;
    for (int ch = 0; ch < 3; ++ch) {
        ASSERT_EQ(textures->grid[ch].size(), cpu.grid[ch].size());
        ASSERT_EQ(textures->lightmap[ch].size(), cpu.lightmap[ch].size());
        // Half floats: 11 significant bits.
        for (size_t i = 0; i < cpu.grid[ch].size(); ++i)
            ASSERT_NEAR(textures->grid[ch][i], cpu.grid[ch][i], 1e-3f * std::abs(cpu.grid[ch][i]) + 1e-7f);
        for (size_t i = 0; i < cpu.lightmap[ch].size(); ++i)
            ASSERT_NEAR(textures->lightmap[ch][i], cpu.lightmap[ch][i],
                        1e-3f * std::abs(cpu.lightmap[ch][i]) + 1e-7f);
    }
    EXPECT_EQ(textures->gridCoverage, cpu.gridCoverage);
    EXPECT_EQ(textures->lightmapCoverage, cpu.lightmapCoverage);
}

class GpuRuntimeForms : public testing::TestWithParam<std::tuple<LinkMode, gpu::DirectVisibility>> {
};

TEST_P(GpuRuntimeForms, ProgressiveUpdateMatchesTheCpuRuntime) {
    const auto [mode, visibility] = GetParam();
    const Baked& b = baked("cornell", mode);
    ASSERT_TRUE(b.ok);
    auto gpu = gpuFor(b, {}, {.directVisibility = visibility});
    ASSERT_TRUE(gpu);
    auto cpu = createCpuRuntime(b.scene, *b.rays, b.bake, BounceParams{});
    ASSERT_TRUE(cpu);
    const LightSet lights = defaultLightSet(b.scene);
    UpdateStats gpuStats, cpuStats;
    auto cpuValues = (*cpu)->setLights(lights, &cpuStats);
    ASSERT_TRUE(cpuValues) << cpuValues.error().message;
    auto gpuValues = gpu->setLights(lights, &gpuStats);
    ASSERT_TRUE(gpuValues) << gpuValues.error().message;
    EXPECT_EQ(gpuStats.bounces, cpuStats.bounces);
    EXPECT_NEAR(gpuStats.surfelFlux / cpuStats.surfelFlux, 1.0, 0.01);
    EXPECT_LE(relativeL2(**gpuValues, **cpuValues), 0.01);
    for (float v : (*gpuValues)->y) ASSERT_TRUE(std::isfinite(v));
    // The textures are the caches, copied.
    auto textures = gpu->textures();
    ASSERT_TRUE(textures) << textures.error().message;
    auto cpuTextures = (*cpu)->textures();
    ASSERT_TRUE(cpuTextures);
    EXPECT_EQ((*textures)->grid[0].size(), (*cpuTextures)->grid[0].size());
    EXPECT_EQ(gpu->context().validationMessages(), 0u);
}

/// "ShadowMaps" or "Rays", for test names.
std::string visibilityName(gpu::DirectVisibility visibility) {
    return visibility == gpu::DirectVisibility::Rays ? "Rays" : "ShadowMaps";
}

INSTANTIATE_TEST_SUITE_P(LinkFormsAndVisibility, GpuRuntimeForms,
                         testing::Combine(testing::Values(LinkMode::Rtp, LinkMode::Sh),
                                          testing::Values(gpu::DirectVisibility::ShadowMaps,
                                                          gpu::DirectVisibility::Rays)),
                         [](const auto& info) {
                             return std::string(std::get<0>(info.param) == LinkMode::Rtp ? "Rtp"
                                                                                         : "Sh") +
                                    visibilityName(std::get<1>(info.param));
                         });

TEST(GpuShadowMaps, OnlyLightsThatChangedAreRerendered) {
    const Baked& b = baked("cornell", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    auto gpu = gpuFor(b, BounceParams{1}, {.directVisibility = gpu::DirectVisibility::ShadowMaps});
    ASSERT_TRUE(gpu);
    LightSet lights = defaultLightSet(b.scene);
    ASSERT_FALSE(lights.lights.empty());
    Light second = lights.lights[0];
    second.id = "second";
    second.position += glm::vec3(0.1f, -0.2f, 0.05f);
    lights.lights.push_back(second);
    UpdateStats stats;
    ASSERT_TRUE(gpu->setLights(lights, &stats));
    EXPECT_EQ(stats.shadowMapsRendered, 2);
    ASSERT_TRUE(gpu->setLights(lights, &stats));
    EXPECT_EQ(stats.shadowMapsRendered, 0);
    // Colour and intensity do not change a depth map.
    lights.lights[1].intensity *= 2.0f;
    lights.lights[1].color = {1.0f, 0.5f, 0.25f};
    ASSERT_TRUE(gpu->setLights(lights, &stats));
    EXPECT_EQ(stats.shadowMapsRendered, 0);
    // Moving one light re-renders that light only.
    lights.lights[1].position.x += 0.05f;
    ASSERT_TRUE(gpu->setLights(lights, &stats));
    EXPECT_EQ(stats.shadowMapsRendered, 1);
}

TEST(GpuRayVisibility, OnlyLightsThatChangedAreRetracedAndMoreLightsKeepTheirBits) {
    const Baked& b = baked("cornell", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    const GpuRuntimeOptions options{.directVisibility = gpu::DirectVisibility::Rays};
    auto gpu = gpuFor(b, BounceParams{1}, options);
    ASSERT_TRUE(gpu);
    LightSet lights = defaultLightSet(b.scene);
    ASSERT_FALSE(lights.lights.empty());
    Light second = lights.lights[0];
    second.id = "second";
    second.position += glm::vec3(0.1f, -0.2f, 0.05f);
    lights.lights.push_back(second);
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
    auto fresh = gpuFor(b, BounceParams{1}, options);
    ASSERT_TRUE(fresh);
    auto expected = fresh->setLights(lights, nullptr);
    ASSERT_TRUE(expected) << expected.error().message;
    EXPECT_EQ((*updated)->y, (*expected)->y);
    EXPECT_EQ((*updated)->co, (*expected)->co);
    EXPECT_EQ(gpu->context().validationMessages(), 0u);
}

TEST(GpuRuntime, DirectVisibilityIsRaysOnACpuDeviceAndShadowMapsOnAGpu) {
    const Baked& b = baked("cornell", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    auto gpu = gpuFor(b);
    ASSERT_TRUE(gpu);
    EXPECT_EQ(gpu->directVisibility(), gpu->context().isCpuDevice()
                                           ? gpu::DirectVisibility::Rays
                                           : gpu::DirectVisibility::ShadowMaps);
    EXPECT_EQ(*gpu::parseDirectVisibility("rays"), gpu::DirectVisibility::Rays);
    EXPECT_EQ(*gpu::parseDirectVisibility("shadow-maps"), gpu::DirectVisibility::ShadowMaps);
    EXPECT_EQ(*gpu::parseDirectVisibility("auto"), std::nullopt);
    auto bad = gpu::parseDirectVisibility("raytraced");
    ASSERT_FALSE(bad);
    EXPECT_EQ(bad.error().code, ErrorCode::InvalidInput);
    EXPECT_NE(bad.error().message.find("raytraced"), std::string::npos);
}

TEST(GpuRuntime, ZeroBouncesLeaveCachesAndTexturesDark) {
    const Baked& b = baked("cornell", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    auto lit = gpuFor(b, BounceParams{1});
    ASSERT_TRUE(lit);
    ASSERT_TRUE(lit->setLights(defaultLightSet(b.scene), nullptr));
    auto dark = gpuFor(b, BounceParams{0});
    ASSERT_TRUE(dark);
    auto values = dark->setLights(defaultLightSet(b.scene), nullptr);
    ASSERT_TRUE(values) << values.error().message;
    for (float v : (*values)->y) ASSERT_EQ(v, 0.0f);
    auto textures = dark->textures();
    ASSERT_TRUE(textures) << textures.error().message;
    for (int ch = 0; ch < 3; ++ch)
        for (float v : (*textures)->lightmap[ch]) ASSERT_EQ(v, 0.0f);
}

// A discrete GPU's device memory is not mapped: uploads, downloads and the caches' read-back
// go through host-visible buffers. Lavapipe could map it; left unmapped, it takes those paths
// and must give the same caches and textures, bit for bit (the same shaders on the same data).
class GpuRuntimeMemory : public testing::TestWithParam<gpu::DirectVisibility> {};

TEST_P(GpuRuntimeMemory, UnmappedDeviceMemoryGivesTheSameResults) {
    const Baked& b = baked("cornell", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    auto mapped = gpuFor(b, {}, {.directVisibility = GetParam()});
    auto unmapped = gpuFor(b, {}, {.directVisibility = GetParam(), .mapDeviceMemory = false});
    ASSERT_TRUE(mapped && unmapped);
    LightSet lights = defaultLightSet(b.scene);
    for (int update = 0; update < 3; ++update) {
        auto expected = mapped->setLights(lights, nullptr);
        auto actual = unmapped->setLights(lights, nullptr);
        ASSERT_TRUE(expected && actual);
        EXPECT_EQ((*actual)->y, (*expected)->y);
        EXPECT_EQ((*actual)->co, (*expected)->co);
        EXPECT_EQ((*actual)->cg, (*expected)->cg);
        auto expectedTextures = mapped->textures();
        auto actualTextures = unmapped->textures();
        ASSERT_TRUE(expectedTextures && actualTextures);
        for (int ch = 0; ch < 3; ++ch) {
            EXPECT_EQ((*actualTextures)->grid[ch], (*expectedTextures)->grid[ch]);
            EXPECT_EQ((*actualTextures)->lightmap[ch], (*expectedTextures)->lightmap[ch]);
        }
        // A recolour, then a move.
        if (update == 0) lights.lights[0].intensity *= 0.5f;
        if (update == 1) lights.lights[0].position.y -= 0.1f;
    }
    // The single-pass path reads the caches back the same way.
    std::vector<glm::vec3> nodes(b.bake.nodes.size(), glm::vec3(0.25f, 0.5f, 1.0f));
    auto expected = mapped->runCacheLighting(nodes);
    auto actual = unmapped->runCacheLighting(nodes);
    ASSERT_TRUE(expected && actual);
    EXPECT_EQ(actual->y, expected->y);
    EXPECT_GT(*std::max_element(actual->y.begin(), actual->y.end()), 0.0f);
    EXPECT_EQ(unmapped->context().validationMessages(), 0u);
}

INSTANTIATE_TEST_SUITE_P(Visibility, GpuRuntimeMemory,
                         testing::Values(gpu::DirectVisibility::ShadowMaps,
                                         gpu::DirectVisibility::Rays),
                         [](const auto& info) { return visibilityName(info.param); });

// The light-map copy on the host (the default on a CPU device) and on the device give the
// same textures bit for bit: both copy the same half-float caches of a progressive update,
// with the device's memory mapped or not.
class GpuRuntimeLightmapCopy : public testing::TestWithParam<bool> {};

TEST_P(GpuRuntimeLightmapCopy, HostAndDeviceCopiesGiveTheSameTextures) {
    const Baked& b = baked("cornell", LinkMode::Sh);
    ASSERT_TRUE(b.ok);
    const bool mapped = GetParam();
    auto host = gpuFor(b, {}, {.mapDeviceMemory = mapped, .lightmapCopyOnHost = true});
    auto device = gpuFor(b, {}, {.mapDeviceMemory = mapped, .lightmapCopyOnHost = false});
    ASSERT_TRUE(host && device);
    EXPECT_TRUE(host->lightmapCopyOnHost());
    EXPECT_FALSE(device->lightmapCopyOnHost());
    LightSet lights = defaultLightSet(b.scene);
    for (int update = 0; update < 2; ++update) {
        UpdateStats hostStats, deviceStats;
        auto expected = device->setLights(lights, &deviceStats);
        auto actual = host->setLights(lights, &hostStats);
        ASSERT_TRUE(expected && actual);
        EXPECT_GT(hostStats.bounces, 1);
        EXPECT_EQ(hostStats.bounces, deviceStats.bounces);
        EXPECT_EQ((*actual)->y, (*expected)->y);
        // The copy runs on demand in textures(), from what setLights returned, even when a
        // single pass has reused the cache buffers in between.
        EXPECT_FALSE(hostStats.passMs.contains("lightmap_copy"));
        EXPECT_FALSE(deviceStats.passMs.contains("lightmap_copy"));
        if (update == 1)
            ASSERT_TRUE(device->runCacheLighting(std::vector<uint32_t>(b.bake.nodes.size(), 0)));
        auto expectedTextures = device->textures();
        auto actualTextures = host->textures();
        ASSERT_TRUE(expectedTextures && actualTextures);
        for (int ch = 0; ch < 3; ++ch) {
            EXPECT_EQ((*actualTextures)->grid[ch], (*expectedTextures)->grid[ch]);
            EXPECT_EQ((*actualTextures)->lightmap[ch], (*expectedTextures)->lightmap[ch]);
        }
        EXPECT_GT(*std::max_element((*actualTextures)->lightmap[0].begin(),
                                    (*actualTextures)->lightmap[0].end()),
                  0.0f);
        lights.lights[0].position.y -= 0.1f;
    }
    EXPECT_EQ(host->context().validationMessages(), 0u);
    EXPECT_EQ(device->context().validationMessages(), 0u);
}

INSTANTIATE_TEST_SUITE_P(Memory, GpuRuntimeLightmapCopy, testing::Bool(),
                         [](const auto& info) { return info.param ? "Mapped" : "Unmapped"; });

TEST(GpuRuntime, LightmapCopyIsOnTheHostOnACpuDeviceByDefault) {
    const Baked& b = baked("cornell", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    auto gpu = gpuFor(b);
    ASSERT_TRUE(gpu);
    EXPECT_EQ(gpu->lightmapCopyOnHost(), gpu->context().isCpuDevice());
}

TEST(GpuCopyProbe, CopiesEveryWordAndReportsARate) {
    auto context = gpu::Context::create({.mapDeviceMemory = false});
    ASSERT_TRUE(context) << context.error().message;
    // Fewer workgroups than the data needs: each strides over the rest, past a partial group.
    auto rate = gpu::computeCopyBandwidth(
        **context, {.bytes = 16 * 3001, .copiesPerSubmission = 2, .submissions = 3, .maxGroups = 3});
    ASSERT_TRUE(rate) << rate.error().message;
    EXPECT_GT(*rate, 0.0);
    auto bad = gpu::computeCopyBandwidth(**context, {.bytes = 20});
    ASSERT_FALSE(bad);
    EXPECT_EQ(bad.error().code, ErrorCode::InvalidInput);
    EXPECT_NE(bad.error().message.find("20"), std::string::npos) << bad.error().message;
}

TEST(GpuRuntime, RefusesInvalidLights) {
    const Baked& b = baked("cornell", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    auto gpu = gpuFor(b);
    ASSERT_TRUE(gpu);
    LightSet lights = defaultLightSet(b.scene);
    ASSERT_FALSE(lights.lights.empty());
    lights.lights[0].intensity = std::nanf("");
    auto values = gpu->setLights(lights, nullptr);
    ASSERT_FALSE(values);
    EXPECT_EQ(values.error().code, ErrorCode::InvalidInput);
}

}  // namespace
}  // namespace pic
