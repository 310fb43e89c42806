// `picbench compare`: relative RMSE of an image against a reference per pixel and over blocks.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "tests/bench/picbench_fixture.h"

namespace {

namespace fs = std::filesystem;
namespace test = pic::test;

class PicbenchCompare : public test::PicbenchTest {
protected:
    PicbenchCompare() : PicbenchTest("picbench_compare") {}

    /// Writes a width × height binary PPM whose pixel (x, y) is `white` where (x + y + phase)
    /// is odd, else black (0 and 255 are 0 and 1 in linear and in sRGB alike; any other white
    /// scales the whole image).
    fs::path writeChecker(const std::string& name, int width, int height, int phase, int white = 255) {
        const fs::path path = mDir / name;
        std::ofstream out(path, std::ios::binary);
        out << "P6\n" << width << " " << height << "\n255\n";
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x)
                for (int c = 0; c < 3; ++c) out.put(char((x + y + phase) % 2 ? white : 0));
        return path;
    }
};

TEST_F(PicbenchCompare, PixelErrorOfComplementaryCheckersVanishesOverBlocks) {
    // Every pixel is off by 1 against a reference of mean ½ (relative RMSE 2); every 2 × 2
    // block of either is ½.
    const fs::path a = writeChecker("a.ppm", 8, 6, 0);
    const fs::path b = writeChecker("b.ppm", 8, 6, 1);
    const fs::path json = mDir / "compare.json";
    std::string err;
    ASSERT_EQ(
        run("compare " + a.string() + " " + b.string() + " --blocks 1 2 --json " + json.string(),
            err),
        0)
        << err;
    std::ifstream in(json);
    const nlohmann::json report = nlohmann::json::parse(in);
    ASSERT_EQ(report.at("blocks").size(), 2u);
    EXPECT_EQ(report.at("blocks")[0].at("block").get<int>(), 1);
    EXPECT_NEAR(report.at("blocks")[0].at("relative_rmse").get<double>(), 2.0, 1e-6);
    EXPECT_NEAR(report.at("blocks")[1].at("relative_rmse").get<double>(), 0.0, 1e-6);
    EXPECT_NEAR(report.at("blocks")[1].at("mean_ratio").get<double>(), 1.0, 1e-6);
    EXPECT_NEAR(report.at("blocks")[0].at("mean_matched_relative_rmse").get<double>(), 2.0, 1e-6);
}

TEST_F(PicbenchCompare, MeanMatchedErrorLeavesOutAScale) {
    // The same checker, dimmer: off in every pixel by the scale, in none once scaled to the
    // reference's mean.
    const fs::path a = writeChecker("dim.ppm", 8, 6, 0, 188);
    const fs::path b = writeChecker("bright.ppm", 8, 6, 0);
    const fs::path json = mDir / "scaled.json";
    std::string err;
    ASSERT_EQ(run("compare " + a.string() + " " + b.string() + " --blocks 1 4 --json " + json.string(), err), 0)
        << err;
    std::ifstream in(json);
    const nlohmann::json report = nlohmann::json::parse(in);
    for (const nlohmann::json& row : report.at("blocks")) {
        EXPECT_LT(row.at("mean_ratio").get<double>(), 0.9);
        EXPECT_GT(row.at("relative_rmse").get<double>(), 0.1);
        EXPECT_NEAR(row.at("mean_matched_relative_rmse").get<double>(), 0.0, 1e-5);
    }
}

TEST_F(PicbenchCompare, RefusesMismatchedSizesAndEmptyBlocks) {
    const fs::path a = writeChecker("a.ppm", 8, 6, 0);
    const fs::path small = writeChecker("small.ppm", 4, 6, 0);
    std::string err;
    EXPECT_EQ(run("compare " + a.string() + " " + small.string(), err), 2);
    EXPECT_NE(err.find("4x6"), std::string::npos) << err;
    EXPECT_EQ(run("compare " + a.string() + " " + a.string() + " --blocks 0", err), 2);
    EXPECT_NE(run("compare " + a.string() + " " + (mDir / "missing.exr").string(), err), 0);
    EXPECT_NE(err.find("missing.exr"), std::string::npos) << err;
}

}  // namespace
