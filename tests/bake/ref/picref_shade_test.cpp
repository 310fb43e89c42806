// `picref shade` end to end: the real binary on a bake written in-process, its image and its
// exit codes for bad input.

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "bake/bake.h"
#include "core/bake_file.h"
#include "core/gltf_loader.h"
#include "core/image.h"
#include "core/progress.h"
#include "tests/support/command.h"

namespace pic {
namespace {

namespace fs = std::filesystem;

std::string scenePath(const std::string& name) {
    return std::string(PIC_TEST_SCENE_DIR) + "/" + name + ".gltf";
}

/// Bakes `scene` with small settings into `out`; false (with a test failure) on any error.
bool bakeTo(const std::string& scene, const std::string& out) {
    auto loaded = loadScene(scenePath(scene));
    EXPECT_TRUE(loaded.has_value()) << (loaded ? "" : loaded.error().message);
    if (!loaded) return false;
    BakeOptions options;
    options.surfels = 2048;
    options.links = 48;
    options.gridCell = 0.25f;
    options.lightmapTexel = 0.1f;
    BakeReport report;
    Progress::setEnabled(false);
    auto bake = runBake(*loaded, options, report);
    EXPECT_TRUE(bake.has_value()) << (bake ? "" : bake.error().message);
    if (!bake) return false;
    auto written = writeBakeFile(out, *bake);
    EXPECT_TRUE(written.has_value()) << (written ? "" : written.error().message);
    return written.has_value();
}

/// A temporary directory with bakes of cornell and closed_box, made once for all tests.
struct ShadeFixture {
    fs::path dir;
    std::string cornellBake;
    std::string otherBake;
    bool ok = false;

    ShadeFixture() {
        dir = fs::temp_directory_path() / fmt::format("picref_shade_test_{}", ::getpid());
        fs::create_directories(dir);
        cornellBake = (dir / "cornell.pic").string();
        otherBake = (dir / "closed_box.pic").string();
        ok = bakeTo("cornell", cornellBake) && bakeTo("closed_box", otherBake);
    }
    ~ShadeFixture() {
        std::error_code ignored;
        fs::remove_all(dir, ignored);
    }
};

const ShadeFixture& fixture() {
    static const ShadeFixture f;
    return f;
}

/// Exit code and output of `picref shade ARGS`.
test::CommandResult runShade(const std::string& args) {
    return test::runCommand(fmt::format("'{}' shade {} --quiet", PIC_PICREF, args), fixture().dir);
}

TEST(PicrefShade, WritesAFiniteImageOfCornell) {
    const ShadeFixture& f = fixture();
    ASSERT_TRUE(f.ok);
    const std::string out = (f.dir / "cornell.exr").string();
    const test::CommandResult run =
        runShade(fmt::format("'{}' --bake '{}' --scene-camera 0 --size 32x32 --out '{}'",
                             scenePath("cornell"), f.cornellBake, out));
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
    const test::CommandResult run =
        runShade(fmt::format("'{}' --bake '{}' --scene-camera 0 --size 8x8 --out '{}'",
                             scenePath("cornell"), f.otherBake, (f.dir / "other.exr").string()));
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
            scenePath("cornell"), f.cornellBake, backends[b], out));
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
    const test::CommandResult run =
        runShade(fmt::format("'{}' --bake '{}' --backend gpu --device no-such-gpu --scene-camera 0 "
                             "--size 8x8 --out '{}'",
                             scenePath("cornell"), f.cornellBake, (f.dir / "gpu.exr").string()));
    EXPECT_EQ(run.exitCode, 2) << run.err;
    EXPECT_NE(run.err.find("no-such-gpu"), std::string::npos) << run.err;
}

TEST(PicrefShade, BadUsageExitsWithTwo) {
    const ShadeFixture& f = fixture();
    ASSERT_TRUE(f.ok);
    const std::string base = fmt::format("'{}' --bake '{}'", scenePath("cornell"), f.cornellBake);
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
