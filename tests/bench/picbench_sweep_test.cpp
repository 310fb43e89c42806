// `picbench sweep` on cornell at a tiny size: every point carries every figure, the CSV and
// the charts are written, a second run resumes from the finished points, and a folder of
// other inputs is refused.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include <nlohmann/json.hpp>

#include "tests/bench/picbench_fixture.h"

namespace {

namespace fs = std::filesystem;
namespace test = pic::test;

class PicbenchSweep : public test::PicbenchTest {
protected:
    PicbenchSweep() : PicbenchTest("picbench_sweep") {}

    /// A sweep small enough for a test: three settings, every baseline, 32x24 pixels.
    std::string sweepArgs(const fs::path& dir, const std::string& extra = "--max-points 3") const {
        return std::string("sweep --scene ") + PIC_TEST_SCENE_DIR + "/cornell.gltf --size 32x24 "
               "--spp 8 --probe-samples 16 --shade-spp 1 --repeat 1 --surfels 2048 --links 32 --out-dir " +
               dir.string() + " " +
               extra;
    }
};

TEST_F(PicbenchSweep, MeasuresEveryPointAndResumes) {
    const fs::path dir = mDir / "sweep";
    std::string err;
    ASSERT_EQ(run(sweepArgs(dir), err), 0) << err;
    std::ifstream in(dir / "sweep.json");
    const nlohmann::json sweep = nlohmann::json::parse(in);
    const nlohmann::json& points = sweep.at("points");
    // Three settings of pic, two ideal sample counts, four traced-probe and three LPV points.
    std::set<std::string> methods, keys;
    for (const nlohmann::json& p : points) {
        SCOPED_TRACE(p.at("name").get<std::string>());
        methods.insert(p.at("method").get<std::string>());
        EXPECT_TRUE(keys.insert(p.at("key").get<std::string>()).second) << "keys are unique";
        const nlohmann::json& a = p.at("accuracy");
        for (const char* figure : {"indirect_rmse", "indirect_mean_ratio", "full_rmse", "full_mean_ratio"}) {
            const double value = a.at(figure).get<double>();
            EXPECT_TRUE(std::isfinite(value)) << figure;
            EXPECT_GT(value, 0.0) << figure;
        }
        // The blotch index holds each point against the ideal caches at --probe-samples: zero
        // for those caches themselves, positive for every other method.
        const double blotch = a.at("blotch_index").get<double>();
        if (p.at("key") == "ideal_s16")
            EXPECT_EQ(blotch, 0.0);
        else
            EXPECT_GT(blotch, 0.0);
        EXPECT_GT(p.at("settle_ms").get<double>(), 0.0);
        EXPECT_GE(p.at("settle_ms").get<double>(), p.at("cpu_update_ms").get<double>());
        EXPECT_GT(p.at("runtime_memory_bytes").get<uint64_t>(), 0u);
        EXPECT_GT(p.at("stream_key_bytes").get<uint64_t>(), 0u);
        EXPECT_GT(p.at("stream_delta_bytes").get<uint64_t>(), 0u);
        EXPECT_GT(p.at("params").at("caches").get<uint64_t>(), 0u);
        if (p.at("method") == "pic") {
            EXPECT_GT(p.at("bake_seconds").get<double>(), 0.0);
            EXPECT_GT(p.at("bake_peak_memory_bytes").get<uint64_t>(), 0u);
            EXPECT_GT(p.at("bake_file_bytes").get<uint64_t>(), 0u);
        }
    }
    EXPECT_EQ(methods, (std::set<std::string>{"pic", "ideal", "traced_probes", "lpv"}));
    EXPECT_EQ(std::count_if(points.begin(), points.end(), [](const auto& p) { return p.at("method") == "pic"; }), 3);
    // The default's bake is kept for the baselines; the others' are removed.
    EXPECT_TRUE(fs::exists(dir / "bakes" / "default.pic"));
    size_t bakes = 0;
    for (const auto& entry : fs::directory_iterator(dir / "bakes")) bakes += entry.path().extension() == ".pic";
    EXPECT_EQ(bakes, 1u);
    // The reference's own noise is stated, from its two halves.
    const double noise = sweep.at("reference_noise").at(0).at("indirect").get<double>();
    EXPECT_GT(noise, 0.0);
    EXPECT_LT(noise, 1.0);
    // One CSV row per point, and the charts.
    std::ifstream csv(dir / "sweep.csv");
    size_t rows = 0;
    for (std::string line; std::getline(csv, line);) ++rows;
    EXPECT_EQ(rows, points.size() + 1);
    EXPECT_GT(fs::file_size(dir / "sweep.png"), 1000u);

    // A second run finds every point measured and reproduces the same figures.
    ASSERT_EQ(run(sweepArgs(dir), err), 0) << err;
    EXPECT_NE(err.find("measured already"), std::string::npos);
    EXPECT_EQ(err.find("path tracing"), std::string::npos) << "the references are kept";
    std::ifstream again(dir / "sweep.json");
    EXPECT_EQ(nlohmann::json::parse(again).at("points"), points);
}

TEST_F(PicbenchSweep, RefusesAFolderOfOtherInputs) {
    const fs::path dir = mDir / "sweep";
    std::string err;
    ASSERT_EQ(run(sweepArgs(dir, "--baselines ideal --max-points 1"), err), 0) << err;
    // Another image size makes every figure incomparable: refused, nothing overwritten.
    EXPECT_EQ(run(std::string("sweep --scene ") + PIC_TEST_SCENE_DIR +
                      "/cornell.gltf --size 16x12 --spp 8 --probe-samples 16 --max-points 1 "
                      "--baselines ideal --out-dir " + dir.string(),
                  err),
              2);
    EXPECT_NE(err.find("other inputs"), std::string::npos) << err;
    EXPECT_NE(err.find(dir.string()), std::string::npos) << err;
}

TEST_F(PicbenchSweep, AutotuneChecksEachTargetAgainstTheGrid) {
    const fs::path dir = mDir / "autotune";
    std::string err;
    ASSERT_EQ(run("autotune" + sweepArgs(dir, "--baselines ideal --max-points 2 --target-errors 0.9 --grid-cell 0.125 --lightmap-texel 0.06").substr(5), err), 0)
        << err;
    std::ifstream in(dir / "sweep.json");
    const nlohmann::json sweep = nlohmann::json::parse(in);
    ASSERT_EQ(sweep.at("autotune").size(), 1u);
    const nlohmann::json& check = sweep.at("autotune")[0];
    EXPECT_EQ(check.at("target_error").get<double>(), 0.9);
    // A target this loose: a bake cheaper than the base, within it, and some grid point meets it.
    EXPECT_NE(check.at("chosen"), "base");
    EXPECT_LE(check.at("predicted_error").get<double>(), 0.95 * 0.9);
    EXPECT_TRUE(std::isfinite(check.at("error").get<double>()));
    EXPECT_EQ(check.at("meets").get<bool>(), check.at("error").get<double>() <= 0.9);
    ASSERT_FALSE(check.at("cheapest_swept").is_null());
    EXPECT_GT(check.at("cost_ratio").get<double>(), 0.0);
    // The choice reads fewer links per update than the grid's default point.
    EXPECT_LT(check.at("link_reads_ratio").get<double>(), 1.0);
    size_t targets = 0;
    for (const nlohmann::json& p : sweep.at("points")) targets += p.at("method") == "target";
    EXPECT_EQ(targets, 1u);
    // The pilot kept its measurements in the sweep's folder.
    EXPECT_TRUE(fs::exists(dir / "pilot" / "pilot"));
    // autotune without a target is bad usage.
    EXPECT_EQ(run("autotune --scene " + std::string(PIC_TEST_SCENE_DIR) + "/cornell.gltf", err), 2);
}

TEST_F(PicbenchSweep, RejectsAnUnknownGrid) {
    std::string err;
    EXPECT_EQ(run(std::string("sweep --scene ") + PIC_TEST_SCENE_DIR + "/cornell.gltf --grid huge", err), 2);
    EXPECT_NE(err.find("huge"), std::string::npos) << err;
}

}  // namespace
