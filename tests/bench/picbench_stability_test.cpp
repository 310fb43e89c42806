// `picbench stability` from the command line: every case on tiny bakes writes its figures,
// images and chart; bad cases and scene folders are refused with exit code 2.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "tests/bench/picbench_fixture.h"

namespace {

namespace fs = std::filesystem;
namespace test = pic::test;

class PicbenchStability : public test::PicbenchTest {
protected:
    PicbenchStability() : PicbenchTest("picbench_stability") {}
};

/// Tiny bakes and images: the command's plumbing, not its figures (stability_test has those).
const std::string kTiny = std::string(" --scene-dir ") + PIC_TEST_SCENE_DIR +
                          " --size 16x12 --spp 8 --probe-samples 16 --moving-probe-samples 16"
                          " --steps 4 --random-sets 18 --random-size 8x6 --surfels 2048"
                          " --links 16 --grid-cell 0.8 --lightmap-texel 0.4";

TEST_F(PicbenchStability, WritesEveryCaseWithItsImagesAndChart) {
    const fs::path json = mDir / "out" / "stability.json";
    std::string err;
    ASSERT_EQ(run("stability" + kTiny + " --json " + json.string(), err), 0) << err;
    std::ifstream in(json);
    const nlohmann::json report = nlohmann::json::parse(in);
    ASSERT_EQ(report.at("leak").size(), 2u);
    for (const nlohmann::json& leak : report.at("leak")) {
        EXPECT_TRUE(fs::exists(leak.at("image").get<std::string>()));
        EXPECT_GE(leak.at("dark_over_lit").at("linked").get<double>(), 0.0);
        // The partition and the slab are sealed: the path tracer finds no path through them.
        EXPECT_EQ(leak.at("dark_over_lit").at("reference").get<double>(), 0.0);
    }
    EXPECT_GT(report.at("spot").at("over_reference").at("linked").get<double>(), 0.0);
    EXPECT_TRUE(fs::exists(report.at("colors").at("image").get<std::string>()));
    const nlohmann::json& moving = report.at("moving");
    EXPECT_EQ(moving.at("frames").at("linked_mean").size(), 4u);
    EXPECT_EQ(moving.at("path").size(), 4u);
    EXPECT_GT(moving.at("ideal_flicker").get<double>(), 0.0);
    EXPECT_TRUE(fs::exists(moving.at("chart").get<std::string>()));
    const nlohmann::json& random = report.at("random");
    EXPECT_EQ(random.at("sets").get<int>(), 18);
    EXPECT_EQ(random.at("failures").get<int>(), 0);
    EXPECT_EQ(random.at("scenes").size(), 9u);
}

TEST_F(PicbenchStability, RefusesUnknownCasesAndMissingScenes) {
    std::string err;
    EXPECT_EQ(run("stability --cases glare", err), 2);
    EXPECT_NE(err.find("glare"), std::string::npos) << err;
    EXPECT_EQ(run("stability --cases spot --scene-dir " + (mDir / "none").string() + " --json " +
                      (mDir / "s.json").string(),
                  err),
              2);
    EXPECT_NE(err.find("small_spot"), std::string::npos) << err;
}

}  // namespace
