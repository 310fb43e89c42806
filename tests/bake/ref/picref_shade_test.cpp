// `picref shade` end to end: the real binary on a bake written in-process, its image and its
// exit codes for bad input.

#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "core/image.h"
#include "core/progress.h"
#include "tests/support/baked_scene.h"
#include "tests/support/command.h"

namespace pic {
namespace {

/// Small bakes of cornell and closed_box, and a temporary directory for the images, made once
/// for all tests.
struct ShadeFixture {
    test::ScratchDir dir{"picref_shade_test"};
    std::string cornellBake;
    std::string otherBake;
    bool ok = false;

    ShadeFixture() {
        Progress::setEnabled(false);
        const BakeOptions options = test::smallBakeOptions(2048, 48, 0.25f, 0.1f);
        cornellBake = test::bakeFile("cornell", options);
        otherBake = test::bakeFile("closed_box", options);
        ok = !cornellBake.empty() && !otherBake.empty();
    }
};

const ShadeFixture& fixture() {
    static const ShadeFixture f;
    return f;
}

/// Exit code and output of `picref shade ARGS`.
test::CommandResult runShade(const std::string& args) {
    return test::runCommand(fmt::format("'{}' shade {} --quiet", PIC_PICREF, args),
                            fixture().dir.path());
}

TEST(PicrefShade, WritesAFiniteImageOfCornell) {
    const ShadeFixture& f = fixture();
    ASSERT_TRUE(f.ok);
    const std::string out = (f.dir / "cornell.exr").string();
    const test::CommandResult run =
        runShade(fmt::format("'{}' --bake '{}' --scene-camera 0 --size 32x32 --out '{}'",
                             test::testScenePath("cornell"), f.cornellBake, out));
    ASSERT_EQ(run.exitCode, 0) << run.err;
    EXPECT_NE(run.err.find("bounces"), std::string::npos) << run.err;
    auto image = readImage(out);
    ASSERT_TRUE(image.has_value()) << image.error().message;
    ASSERT_EQ(image->width, 32u);
    ASSERT_EQ(image->height, 32u);
    double sum = 0.0;
    for (const glm::vec3& pixel : image->pixels) {
        for (int c = 0; c < 3; ++c) {
            ASSERT_TRUE(std::isfinite(pixel[c]) && pixel[c] >= 0.0f);
            sum += pixel[c];
        }
    }
    EXPECT_GT(sum, 0.0);
}

TEST(PicrefShade, RefusesABakeOfAnotherScene) {
    const ShadeFixture& f = fixture();
    ASSERT_TRUE(f.ok);
    const test::CommandResult run = runShade(
        fmt::format("'{}' --bake '{}' --scene-camera 0 --size 8x8 --out '{}'",
                    test::testScenePath("cornell"), f.otherBake, (f.dir / "other.exr").string()));
    EXPECT_EQ(run.exitCode, 2) << run.err;
    EXPECT_NE(run.err.find("different scene"), std::string::npos) << run.err;
}

TEST(PicrefShade, GpuAndCpuBackendsGiveTheSameImage) {
    // ARCHITECTURE §5: `--backend gpu|cpu` selects the runtime; the images agree to 1 %.
    const ShadeFixture& f = fixture();
    ASSERT_TRUE(f.ok);
    Image images[2];
    const char* backends[2] = {"cpu", "gpu"};
    for (int b = 0; b < 2; ++b) {
        const std::string out = (f.dir / fmt::format("{}.exr", backends[b])).string();
        const test::CommandResult run = runShade(fmt::format(
            "'{}' --bake '{}' --backend {} --scene-camera 0 --size 48x48 --component indirect "
            "--out '{}'",
            test::testScenePath("cornell"), f.cornellBake, backends[b], out));
        ASSERT_EQ(run.exitCode, 0) << run.err;
        auto image = readImage(out);
        ASSERT_TRUE(image.has_value()) << image.error().message;
        images[b] = std::move(*image);
    }
    auto error = compareImages(images[1], images[0]);
    ASSERT_TRUE(error.has_value()) << error.error().message;
    EXPECT_LE(error->relativeRmse, 0.01);
    EXPECT_NEAR(error->meanRatio, 1.0, 0.01);
}

TEST(PicrefShade, UnknownGpuDeviceIsABadInput) {
    const ShadeFixture& f = fixture();
    ASSERT_TRUE(f.ok);
    const test::CommandResult run = runShade(
        fmt::format("'{}' --bake '{}' --backend gpu --device no-such-gpu --scene-camera 0 "
                    "--size 8x8 --out '{}'",
                    test::testScenePath("cornell"), f.cornellBake, (f.dir / "gpu.exr").string()));
    EXPECT_EQ(run.exitCode, 2) << run.err;
    EXPECT_NE(run.err.find("no-such-gpu"), std::string::npos) << run.err;
}

TEST(PicrefShade, BadUsageExitsWithTwo) {
    const ShadeFixture& f = fixture();
    ASSERT_TRUE(f.ok);
    const std::string base =
        fmt::format("'{}' --bake '{}'", test::testScenePath("cornell"), f.cornellBake);
    // No --out.
    test::CommandResult run = runShade(base + " --scene-camera 0 --size 8x8");
    EXPECT_EQ(run.exitCode, 2) << run.err;
    EXPECT_NE(run.err.find("--out"), std::string::npos) << run.err;
    // A malformed size is named.
    run = runShade(
        base + fmt::format(" --scene-camera 0 --size 8by8 --out '{}'", (f.dir / "a.exr").string()));
    EXPECT_EQ(run.exitCode, 2) << run.err;
    EXPECT_NE(run.err.find("8by8"), std::string::npos) << run.err;
    // A camera the scene does not have.
    run = runShade(
        base + fmt::format(" --scene-camera 7 --size 8x8 --out '{}'", (f.dir / "b.exr").string()));
    EXPECT_EQ(run.exitCode, 2) << run.err;
    EXPECT_NE(run.err.find("7"), std::string::npos) << run.err;
    // Neither --camera nor --scene-camera.
    run = runShade(base + fmt::format(" --size 8x8 --out '{}'", (f.dir / "c.exr").string()));
    EXPECT_EQ(run.exitCode, 2) << run.err;
}

}  // namespace
}  // namespace pic
