// `picbench runtime` and `picbench shadows` on cornell: they run, and what they report holds
// together (kinds of light change, triangles drawn, shadow-map error falling with size).

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "tests/bench/picbench_fixture.h"

namespace {

namespace fs = std::filesystem;
namespace test = pic::test;

class PicbenchRuntime : public test::PicbenchTest {
protected:
    PicbenchRuntime() : PicbenchTest("picbench_runtime") {}
};

TEST_F(PicbenchRuntime, ReportsEveryKindOfLightChange) {
    const fs::path json = mDir / "runtime.json";
    std::string err;
    ASSERT_EQ(run(std::string("runtime --scene ") + PIC_TEST_SCENE_DIR + "/cornell.gltf "
                  "--settings moderate --link-modes rtp --bounces 1 --repeat 1 --shadow-map-size 256 "
                  "--visibility shadow-maps rays --json " + json.string(), err), 0) << err;
    std::ifstream in(json);
    const nlohmann::json report = nlohmann::json::parse(in);
    ASSERT_EQ(report.at("runs").size(), 6u);
    for (size_t r = 0; r < 6; ++r) {
        const nlohmann::json& run = report.at("runs")[r];
        const std::string change = run.at("change");
        const std::string visibility = run.at("direct_visibility");
        SCOPED_TRACE(change + ", " + visibility);
        EXPECT_EQ(visibility, r < 3 ? "shadow-maps" : "rays");
        EXPECT_GT(run.at("cpu").at("update_ms_median").get<double>(), 0.0);
        EXPECT_GT(run.at("gpu").at("update_ms_median").get<double>(), 0.0);
        EXPECT_GT(run.at("bandwidth_ratio").get<double>(), 0.0);
        const uint64_t drawn = run.at("gpu").at("shadow_triangles").get<uint64_t>();
        const int traced = run.at("gpu").at("lights_traced").get<int>();
        if (visibility == "rays") {
            // Cornell's one point light is traced whenever it moves, never for a recolour.
            EXPECT_FALSE(run.contains("shadow_map_size"));
            EXPECT_EQ(drawn, 0u);
            EXPECT_EQ(traced, change == "recolour" ? 0 : 1);
            EXPECT_TRUE(run.at("gpu").at("pass_ms_median").contains("visibility_rays"));
            continue;
        }
        EXPECT_EQ(run.at("shadow_map_size").get<int>(), 256);
        EXPECT_EQ(traced, 0);
        // Cornell's one point light: a cube, every triangle in some face, none drawn when only
        // the intensity changes.
        if (change == "recolour")
            EXPECT_EQ(drawn, 0u);
        else
            EXPECT_GE(drawn, report.at("triangles").get<uint64_t>());
    }
    // The ratio chart beside the JSON: a PNG.
    std::ifstream png(mDir / "runtime.png", std::ios::binary);
    std::string signature(8, '\0');
    ASSERT_TRUE(png.read(signature.data(), 8)) << "no runtime.png beside the JSON";
    EXPECT_EQ(signature, std::string("\x89PNG\r\n\x1a\n", 8));
}

TEST_F(PicbenchRuntime, ShadowErrorFallsWithSize) {
    const fs::path json = mDir / "shadows.json";
    std::string err;
    ASSERT_EQ(run(std::string("shadows --scene ") + PIC_TEST_SCENE_DIR + "/cornell.gltf "
                  "--sizes 64 512 --sides uniform footprint --repeat 1 --json " + json.string(), err), 0)
        << err;
    std::ifstream in(json);
    const nlohmann::json report = nlohmann::json::parse(in);
    const nlohmann::json& runs = report.at("runs");
    ASSERT_EQ(runs.size(), 5u);
    for (const nlohmann::json& row : runs) {
        EXPECT_GE(row.at("relative_l1").get<double>(), 0.0);
        EXPECT_LE(row.at("fraction_surfels_differing").get<double>(), 1.0);
        EXPECT_GT(row.at("gpu_direct_ms_median").get<double>(), 0.0);
    }
    for (size_t first : {0, 2}) {
        SCOPED_TRACE(runs[first].at("sides").get<std::string>());
        EXPECT_EQ(runs[first].at("size").get<int>(), 64);
        EXPECT_EQ(runs[first + 1].at("size").get<int>(), 512);
        // Eight times the resolution: the edges of cornell's box shadow get sharper.
        EXPECT_LT(runs[first + 1].at("relative_l1").get<double>(),
                  runs[first].at("relative_l1").get<double>());
    }
    // Cornell's one point light: six uniform layers; footprint sides are never wider.
    EXPECT_EQ(runs[1].at("texels").get<uint64_t>(), 6u * 512u * 512u);
    EXPECT_LE(runs[3].at("texels").get<uint64_t>(), runs[1].at("texels").get<uint64_t>());
    // Last, the host rays: the CPU twin's own visibility, so no error but float rounding.
    EXPECT_EQ(runs[4].at("direct_visibility").get<std::string>(), "rays");
    EXPECT_EQ(runs[4].at("texels").get<uint64_t>(), 0u);
    EXPECT_LT(runs[4].at("relative_l1").get<double>(), 1e-5);
    EXPECT_EQ(runs[4].at("fraction_surfels_differing").get<double>(), 0.0);
}

TEST_F(PicbenchRuntime, CodecFramesDecodeExactlyAndDeltasAreSmaller) {
    // picbench codec exits 1 if a decoded frame differs from the encoder's input.
    const fs::path json = mDir / "codec.json";
    std::string err;
    ASSERT_EQ(run(std::string("codec --scene ") + PIC_TEST_SCENE_DIR +
                      "/cornell.gltf --updates 3 "
                      "--zstd-levels 1 19 --json " +
                      json.string(),
                  err),
              0)
        << err;
    std::ifstream in(json);
    const nlohmann::json report = nlohmann::json::parse(in);
    const nlohmann::json& levels = report.at("levels");
    ASSERT_EQ(levels.size(), 2u);
    for (const nlohmann::json& level : levels) {
        const double key = level.at("key_bits_per_coefficient_median").get<double>();
        const double delta = level.at("delta_bits_per_coefficient_median").get<double>();
        EXPECT_GT(key, 0.0);
        EXPECT_LT(key, 16.0);  // below raw halves
        EXPECT_GT(delta, 0.0);
        EXPECT_LT(delta, key);
    }
    // zstd's strongest level codes the same frames smaller than its fastest.
    EXPECT_LT(levels[1].at("key_bits_per_coefficient_median").get<double>(),
              levels[0].at("key_bits_per_coefficient_median").get<double>());
    EXPECT_EQ(report.at("frames").size(), 4u);
    EXPECT_EQ(report.at("frames")[3].at("levels").size(), 2u);
    EXPECT_TRUE(fs::exists(mDir / "codec.png"));
}

TEST_F(PicbenchRuntime, CodecTakesTheChromaBandsAndRefusesMoreThanLuma) {
    // --chroma-bands 3 at the moderate setting (lY 3): every coefficient has its chroma, 27 per
    // cache; 4 exceeds lY and is refused with the value named.
    const fs::path json = mDir / "codec3.json";
    std::string err;
    ASSERT_EQ(run(std::string("codec --scene ") + PIC_TEST_SCENE_DIR +
                      "/cornell.gltf --updates 1 --zstd-levels 3 --chroma-bands 3 --json " +
                      json.string(),
                  err),
              0)
        << err;
    std::ifstream in(json);
    const nlohmann::json report = nlohmann::json::parse(in);
    EXPECT_EQ(report.at("bands").at("c").get<int>(), 3);
    EXPECT_EQ(report.at("coefficients_per_frame").get<uint64_t>(),
              27u * report.at("caches").get<uint64_t>());
    EXPECT_EQ(run(std::string("codec --scene ") + PIC_TEST_SCENE_DIR +
                      "/cornell.gltf --updates 1 --chroma-bands 4 --json " + json.string(),
                  err),
              2);
    EXPECT_NE(err.find("got 4"), std::string::npos) << err;
}

TEST_F(PicbenchRuntime, RefusesAnUnknownChange) {
    std::string err;
    EXPECT_EQ(run(std::string("runtime --scene ") + PIC_TEST_SCENE_DIR + "/cornell.gltf --changes teleport", err), 2);
    EXPECT_NE(err.find("teleport"), std::string::npos) << err;
}

}  // namespace
