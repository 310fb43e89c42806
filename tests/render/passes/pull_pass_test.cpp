// The pull pass on lavapipe (or the machine's GPU) against its CPU twin (render/cpu/pull.h):
// node flux bit for bit in both of its modes, and node radiance as RGBE8 of flux over π·A.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <span>
#include <string_view>
#include <vector>

#include "core/color.h"
#include "core/light_set.h"
#include "render/cpu/pull.h"
#include "render/node_spread.h"
#include "render/passes/pull_pass.h"
#include "shaders/shared/pull.h"
#include "tests/render/gpu_fixture.h"

namespace pic {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

TEST(GpuPull, NodeFluxIsExact) {
    const test::BakedScene& b = test::smallBake("cornell", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    // Both of the pull's modes run: large levels a dispatch each, the small upper ones as
    // the tail.
    const std::vector<uint32_t>& offsets = b.bake.levelOffsets;
    ASSERT_GT(offsets[1] - offsets[0], gpu::kPullTailNodes);
    ASSERT_LE(offsets.back() - offsets[offsets.size() - 2], gpu::kPullTailNodes);
    auto gpu = test::gpuFor(b);
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

TEST(GpuPull, SurfelRadianceIsFluxOverPiAreaAsRgbe8) {
    const test::BakedScene& b = test::smallBake("cornell", LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    auto gpu = test::gpuFor(b, {}, {.directVisibility = gpu::DirectVisibility::Rays});
    ASSERT_TRUE(gpu);
    const size_t nS = b.bake.surfels.size();
    // Leaves: surfel lighting packs flux / (π·A), its division rounded by the device, so the
    // code may differ from the host's by one mantissa step (at most 2^-7 of the largest
    // channel) besides the rounding (2^-8).
    auto direct = gpu->runDirect(defaultLightSet(b.scene));
    ASSERT_TRUE(direct) << direct.error().message;
    auto leaves = gpu->nodeLight();
    ASSERT_TRUE(leaves) << leaves.error().message;
    size_t lit = 0;
    for (size_t i = 0; i < nS; ++i) {
        const glm::vec3 expected = (*direct)[i] / (kPi * b.bake.surfels[i].area);
        const glm::vec3 got = unpackRgbe8((*leaves)[i][gpu::kNodeLightRadianceWord]);
        ASSERT_EQ(glm::uvec3((*leaves)[i]), glm::uvec3(0u)) << "surfel " << i << " has a gradient";
        const float largest = std::max({expected.r, expected.g, expected.b});
        if (largest > 0.0f) ++lit;
        for (int c = 0; c < 3; ++c)
            ASSERT_LE(std::abs(got[c] - expected[c]), largest / 64.0f) << "surfel " << i;
    }
    EXPECT_GT(lit, nS / 4);
    // Inner nodes write their flux spread's radiance at the box centre: FluxSpreadsMatchTheCpuTwin.
}

/// The GPU pull's spreads against the CPU twin's on a small bake of `name`.
void expectSpreadsMatch(const char* name) {
    SCOPED_TRACE(name);
    const test::BakedScene& b = test::smallBake(name, LinkMode::Rtp);
    ASSERT_TRUE(b.ok);
    auto gpu = test::gpuFor(b);
    ASSERT_TRUE(gpu);
    // Flux that grows along x, with a different slope per channel, plus noise, and one surfel
    // in six 20 times as bright: every inner node has a spread to find, and the nodes where a
    // bright surfel limits the line spread exponentially.
    const size_t nS = b.bake.surfels.size();
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(0.0f, 0.5f);
    std::vector<glm::vec3> nodes(b.bake.nodes.size(), glm::vec3(0.0f));
    for (size_t i = 0; i < nS; ++i) {
        const float x = b.bake.surfels[i].position.x;
        nodes[i] = glm::vec3(2.0f + x, 2.0f - x, 1.0f) + glm::vec3(u(rng), u(rng), u(rng));
        if (i % 6 == 0) nodes[i] *= 20.0f;
    }
    auto pulled = gpu->runPull(std::span<const glm::vec3>(nodes.data(), nS));
    ASSERT_TRUE(pulled) << pulled.error().message;
    auto light = gpu->nodeLight();
    ASSERT_TRUE(light) << light.error().message;
    pullFlux(b.bake, nodes);
    std::vector<glm::mat3> moment(nodes.size()), slopes(nodes.size());
    std::vector<glm::vec3> centre(nodes.size()), concentration(nodes.size());
    std::vector<uint8_t> exponential(nodes.size());
    const NodeSpread spread = nodeSpread(b.bake);
    pullFluxSpread(b.bake, spread, nodes, moment, centre, slopes, concentration, exponential);
    size_t sloped = 0, exponentials = 0, unfit = 0;
    for (size_t n = nS; n < nodes.size(); ++n) {
        // Flat nodes whose flux centroid leaves their box model keep the line (fitsBoxModel).
        if (isFlat(spread, n) && !fitsBoxModel(spread, n, nodes[n], moment[n])) ++unfit;
        glm::mat3 got;
        glm::vec3 gotConcentration;
        const bool gotExponential =
            gpu::unpackNodeSpread(glm::uvec3((*light)[n]), got, gotConcentration);
        ASSERT_EQ(gotExponential, exponential[n] != 0) << "node " << n;
        exponentials += exponential[n];
        float largest = 0.0f;
        for (int c = 0; c < 3; ++c) {
            for (int k = 0; k < 3; ++k) {
                largest = std::max(largest, std::abs(slopes[n][c][k]));
                if (gotExponential) {
                    // snorm8 of slope / 3 to nearest: within half a step, and float rounding.
                    ASSERT_NEAR(got[c][k], slopes[n][c][k],
                                0.5f * gpu::kExponentialSpreadCap / 127.0f + 1e-4f)
                        << "node " << n << " channel " << c << " axis " << k;
                    continue;
                }
                // snorm8 towards zero: less than a step of 1/127 smaller in magnitude.
                ASSERT_LE(std::abs(got[c][k]), std::abs(slopes[n][c][k]) + 1e-5f);
                ASSERT_NEAR(got[c][k], slopes[n][c][k], 1.0f / 127.0f + 1e-5f)
                    << "node " << n << " channel " << c << " axis " << k;
            }
            const float sum = std::abs(got[c].x) + std::abs(got[c].y) + std::abs(got[c].z);
            if (gotExponential) {
                ASSERT_LE(sum, gpu::kExponentialSpreadCap + 0.05f);
                // unorm7 over [0, 4]: within half a step.
                ASSERT_NEAR(gotConcentration[c], concentration[n][c],
                            0.5f * gpu::kConcentrationRange / 127.0f + 1e-4f);
            } else {
                ASSERT_LE(sum, 1.0f + 1e-6f);
            }
        }
        if (largest > 0.1f) ++sloped;
        // RGBE8: within 2^-8 of the largest channel, and float rounding besides.
        const glm::vec3 radiance = centre[n] * gpu::radianceScale(b.bake.nodes[n].area);
        const glm::vec3 gotRadiance = unpackRgbe8((*light)[n][gpu::kNodeLightRadianceWord]);
        const float top = std::max({radiance.r, radiance.g, radiance.b});
        for (int c = 0; c < 3; ++c)
            ASSERT_NEAR(gotRadiance[c], radiance[c], top * (1.0f / 256.0f + 1e-4f))
                << "node " << n << " channel " << c;
    }
    // Slopes of 0.1 and more in a good share of the nodes (about half with the bake's flux
    // weights today; the limiter cuts the rest): the comparison above is not of zeros.
    EXPECT_GT(sloped, (nodes.size() - nS) / 4);
    // The bright surfels limit some flat nodes' lines: exponential nodes are compared too.
    EXPECT_GT(exponentials, 0u);
    if (std::string_view(name) == "small_spot") {
        EXPECT_GT(unfit, 0u);
    }
}

TEST(GpuPull, FluxSpreadsMatchTheCpuTwin) {
    expectSpreadsMatch("cornell");
    // small_spot's flat nodes include ones whose flux centroid, with this flux, lies beyond
    // their box model: the GPU's test of it is compared too.
    expectSpreadsMatch("small_spot");
}

}  // namespace
}  // namespace pic
