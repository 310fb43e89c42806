// `picbench budget` as CI runs it: two seconds of light changes per budget on a small bake of
// the Cornell box (docs/server-and-client.md#budgeted-updates has the atrium's figures).

#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "tests/bench/picbench_fixture.h"

namespace pic::test {
namespace {

namespace fs = std::filesystem;

class PicbenchBudget : public PicbenchTest {
protected:
    PicbenchBudget() : PicbenchTest("picbench_budget") {}
};

TEST_F(PicbenchBudget, ABudgetBelowTheUpdateStreamsPartsAndTheBaselineNone) {
    const std::string scene = cornellScene();
    const std::string bake = smallCornellBake();
    ASSERT_FALSE(bake.empty());
    const fs::path json = mDir / "budget.json";
    std::string err;
    // Any update takes longer than a microsecond: every one after the first comes in parts.
    const int exit = run("budget --scene " + scene + " --bake " + bake +
                             " --backend cpu --budgets 0 0.001 --clients 4 --duration 2 "
                             "--update-rate 4 --json " + json.string(),
                         err);
    ASSERT_EQ(exit, 0) << err;
    std::ifstream in(json);
    const nlohmann::json report = nlohmann::json::parse(in);
    const auto& runs = report.at("runs");
    ASSERT_EQ(runs.size(), 2u);
    for (const auto& row : runs) {
        const auto& load = row.at("load");
        EXPECT_EQ(load.at("errors"), 0) << load.dump(2);
        EXPECT_EQ(load.at("subscribers_without_last"), 0);
        EXPECT_GE(load.at("updates").get<int>(), 4);
        EXPECT_LE(load.at("first_change_ms").at("p50").get<double>(),
                  load.at("latency_ms").at("p50").get<double>());
    }
    EXPECT_EQ(runs[0].at("parts_per_update").get<double>(), 0.0);
    EXPECT_EQ(runs[0].at("load").at("partial_frames"), 0);
    EXPECT_GT(runs[1].at("parts_per_update").get<double>(), 0.0);
    // What a client showed before each final state: the first part is nearer to it than the
    // previous version.
    const auto& error = runs[1].at("luma_error");
    EXPECT_GT(error.at("with_parts").get<int>(), 0);
    EXPECT_LT(error.at("first_part").get<double>(), error.at("previous_final").get<double>());
    EXPECT_TRUE(fs::exists(mDir / "budget.png"));
}

}  // namespace
}  // namespace pic::test
