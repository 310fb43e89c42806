// `picbench glossy`: the glossy lobe from SH caches against the same lobe path-traced.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "tests/bench/picbench_fixture.h"

namespace {

namespace fs = std::filesystem;
namespace test = pic::test;

class PicbenchGlossy : public test::PicbenchTest {
protected:
    PicbenchGlossy() : PicbenchTest("picbench_glossy") {}
};

// A small run: every exponent × band count gets an error, finite and positive, in the JSON,
// and the chart is written beside it. Wider lobes are reproduced better by more bands: at a
// low exponent 3 bands beat 1 (the constant band alone cannot follow the walls' colours).
TEST_F(PicbenchGlossy, WritesTheTableJsonAndChart) {
    const fs::path json = mDir / "glossy.json";
    std::string err;
    ASSERT_EQ(run(std::string("glossy --scene ") + PIC_TEST_SCENE_DIR +
                      "/cornell.gltf --size 24x24 --spp 64 --probe-samples 128 --surfels 2048 "
                      "--truncate-bands 1 3 --exponents 2 20 --json " + json.string(),
                  err),
              0)
        << err;
    std::ifstream in(json);
    const nlohmann::json report = nlohmann::json::parse(in);
    ASSERT_EQ(report.at("rows").size(), 2u);
    for (const nlohmann::json& row : report.at("rows")) {
        ASSERT_EQ(row.at("ideal").size(), 2u);
        for (const nlohmann::json& entry : row.at("ideal")) {
            const double error = entry.at("pixel").get<double>();
            EXPECT_TRUE(std::isfinite(error) && error > 0.0) << row.dump();
        }
        EXPECT_GT(row.at("linked").at("pixel").get<double>(), 0.0);
        EXPECT_GT(row.at("reference_noise").get<double>(), 0.0);
    }
    const nlohmann::json& wide = report.at("rows")[0].at("ideal");
    EXPECT_LT(wide[1].at("block4").get<double>(), wide[0].at("block4").get<double>());
    EXPECT_TRUE(fs::exists(mDir / "glossy.png"));
}

}  // namespace
