// The picref command line as users and scripts call it (ARCHITECTURE.md §5).

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "core/bake_file.h"
#include "core/image.h"
#include "core/progress.h"
#include "tests/support/baked_scene.h"
#include "tests/support/command.h"

namespace pic {
namespace {

namespace fs = std::filesystem;

class PicrefCli : public ::testing::Test {
protected:
    test::CommandResult run(const std::string& args) {
        return test::runCommand(std::string(PIC_PICREF) + " " + args, mDir.path());
    }

    static std::string scene(const std::string& name) { return test::testScenePath(name); }

    /// A small bake of a test scene, made in-process.
    std::string bake(const std::string& name) {
        Progress::setEnabled(false);
        return test::bakeFile(name, test::smallBakeOptions(2048, 16, 0.34f, 0.2f));
    }

    test::ScratchDir mDir{"picref_cli"};
};

TEST_F(PicrefCli, RendersCornellToExr) {
    std::string out = (mDir / "cornell.exr").string();
    test::CommandResult r = run(scene("cornell") + " --scene-camera 0 --size 20x14 --spp 2 --out " +
                                out + " --quiet --threads 2");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.err.find("samples/s"), std::string::npos) << r.err;
    auto image = readImage(out);
    ASSERT_TRUE(image) << image.error().message;
    EXPECT_EQ(image->width, 20u);
    EXPECT_EQ(image->height, 14u);
    double sum = 0.0;
    for (const glm::vec3& p : image->pixels) {
        ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
        ASSERT_GE(std::min(p.x, std::min(p.y, p.z)), 0.0f);
        sum += p.x + p.y + p.z;
    }
    EXPECT_GT(sum, 0.0);
}

TEST_F(PicrefCli, CommandLineCameraComponentAndPng) {
    std::string out = (mDir / "indirect.png").string();
    test::CommandResult r = run(scene("cornell") +
                                " --camera 0,0.5,2,0,0.5,0,0,1,0,40 --size 8x8 --spp 1 "
                                "--component indirect --bounces 1 --seed 3 --exposure 2 --out " +
                                out);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_TRUE(fs::exists(out));
}

TEST_F(PicrefCli, BadSizeIsBadUsageNamingTheValue) {
    test::CommandResult r = run(scene("cornell") + " --scene-camera 0 --size 12by5 --spp 1 --out " +
                                (mDir / "x.exr").string());
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("12by5"), std::string::npos) << r.err;
}

TEST_F(PicrefCli, MissingSceneIsBadInputNamingThePath) {
    std::string missing = (mDir / "nowhere.gltf").string();
    test::CommandResult r =
        run(missing + " --scene-camera 0 --size 4x4 --spp 1 --out " + (mDir / "x.exr").string());
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("nowhere.gltf"), std::string::npos) << r.err;
}

TEST_F(PicrefCli, BadCameraIsBadUsageNamingTheValue) {
    test::CommandResult r = run(scene("cornell") + " --camera 1,2,3 --size 4x4 --spp 1 --out " +
                                (mDir / "x.exr").string());
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("1,2,3"), std::string::npos) << r.err;
    test::CommandResult index =
        run(scene("cornell") + " --scene-camera 7 --size 4x4 --spp 1 --out " +
            (mDir / "x.exr").string());
    EXPECT_EQ(index.exitCode, 2);
    EXPECT_NE(index.err.find("7"), std::string::npos) << index.err;
}

TEST_F(PicrefCli, UnknownComponentIsBadUsageNamingTheValue) {
    test::CommandResult r =
        run(scene("cornell") + " --scene-camera 0 --size 4x4 --spp 1 --component specular --out " +
            (mDir / "x.exr").string());
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("specular"), std::string::npos) << r.err;
    // The glossy component is the lobe's term: without a lobe there is nothing to trace.
    test::CommandResult noLobe =
        run(scene("cornell") + " --scene-camera 0 --size 4x4 --spp 1 --component glossy --out " +
            (mDir / "x.exr").string());
    EXPECT_EQ(noLobe.exitCode, 2);
    EXPECT_NE(noLobe.err.find("--glossy N --glossy-weight W"), std::string::npos) << noLobe.err;
    test::CommandResult lobe =
        run(scene("cornell") + " --scene-camera 0 --size 4x4 --spp 2 --component glossy "
            "--glossy 10 --glossy-weight 0.5 --out " + (mDir / "g.exr").string());
    EXPECT_EQ(lobe.exitCode, 0) << lobe.err;
}

TEST_F(PicrefCli, ProbesWriteEveryCacheWithTheBakesBands) {
    std::string bakePath = bake("cornell");
    auto info = inspectBakeFile(bakePath);
    ASSERT_TRUE(info) << info.error().message;
    std::string json = (mDir / "probes.json").string(), binary = (mDir / "probes.bin").string();
    test::CommandResult r = run("--quiet probes " + bakePath + " --scene " + scene("cornell") +
                                " --samples 8 --bounces 1 --out " + json + " --binary " + binary);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    auto probes = nlohmann::json::parse(test::readFile(json));
    const uint32_t bandsY = info->params.bandsY, bandsC = info->params.bandsC;
    EXPECT_EQ(probes["bands"]["y"], bandsY);
    EXPECT_EQ(probes["bands"]["c"], bandsC);
    ASSERT_EQ(probes["caches"].size(), info->caches);
    double luma = 0.0;
    for (const auto& cache : probes["caches"]) {
        ASSERT_EQ(cache["position"].size(), 3u);
        ASSERT_TRUE(cache["kind"] == "grid" || cache["kind"] == "lightmap");
        ASSERT_EQ(cache["y"].size(), bandsY * bandsY);
        ASSERT_EQ(cache["co"].size(), bandsC * bandsC);
        ASSERT_EQ(cache["cg"].size(), bandsC * bandsC);
        luma += cache["y"][0].get<double>();
    }
    EXPECT_GT(luma, 0.0);
    EXPECT_EQ(fs::file_size(binary),
              info->caches * (bandsY * bandsY + 2 * bandsC * bandsC) * sizeof(float));
}

TEST_F(PicrefCli, ProbesRefuseABakeOfAnotherScene) {
    std::string bakePath = bake("cornell");
    test::CommandResult r = run("probes " + bakePath + " --scene " + scene("cornell_area") +
                                " --samples 4 --out " + (mDir / "p.json").string());
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("cornell_area"), std::string::npos) << r.err;
}

TEST_F(PicrefCli, ImageFlagsDoNotApplyToProbes) {
    test::CommandResult r = run("probes x.pic --scene " + scene("cornell") + " --size 4x4 --out " +
                                (mDir / "p.json").string());
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("--size"), std::string::npos) << r.err;
}

TEST_F(PicrefCli, SkyLightSetLightsTheOpenBox) {
    // The Cornell box is open at z = +0.5: a light set holding only a sky lights it through the
    // opening, where without any light it is black. A missing environment names the file.
    auto write = [&](const std::string& name, const std::string& json) {
        std::ofstream(mDir / name) << json;
        return (mDir / name).string();
    };
    const std::string dark = write("dark.json", R"({"lights": []})");
    const std::string sky =
        write("sky.json", R"({"lights": [{"id": "sky", "type": "sky", "intensity": 2.0}]})");
    const std::string missing = write(
        "missing.json",
        R"({"lights": [{"id": "sky", "type": "sky", "environment": "no_such_sky.exr"}]})");
    auto sum = [&](const std::string& lights) {
        const std::string out = (mDir / "sky.exr").string();
        test::CommandResult r = run(scene("cornell") + " --scene-camera 0 --size 12x8 --spp 4 "
                                    "--quiet --lights " + lights + " --out " + out);
        EXPECT_EQ(r.exitCode, 0) << r.err;
        auto image = readImage(out);
        EXPECT_TRUE(image) << image.error().message;
        double total = 0.0;
        if (image)
            for (const glm::vec3& p : image->pixels) total += p.x + p.y + p.z;
        return total;
    };
    EXPECT_EQ(sum(dark), 0.0);
    EXPECT_GT(sum(sky), 0.0);
    test::CommandResult r = run(scene("cornell") + " --scene-camera 0 --size 4x4 --spp 1 " +
                                "--lights " + missing + " --out " + (mDir / "x.exr").string());
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("no_such_sky.exr"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace pic
