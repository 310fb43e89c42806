// `picbench soak` as CI runs it: 30 seconds of the 10-minute soak (docs/performance.md has the
// long run's figures), on a small bake of the Cornell box.

#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "tests/bench/picbench_fixture.h"

namespace pic::test {
namespace {

namespace fs = std::filesystem;

class PicbenchSoak : public PicbenchTest {
protected:
    PicbenchSoak() : PicbenchTest("picbench_soak") {}
};

TEST_F(PicbenchSoak, TwoHundredSubscribersForThirtySecondsLoseNoFinalState) {
    const std::string scene = cornellScene();
    const std::string bake = smallCornellBake();
    ASSERT_FALSE(bake.empty());
    const fs::path json = mDir / "soak.json";
    std::string err;
    const int exit = run("soak --scene " + scene + " --bake " + bake +
                             " --backend cpu --clients 200 --update-rate 10 --duration 30 --json " +
                             json.string(),
                         err);
    ASSERT_TRUE(exit == 0 || exit == 1) << err;
    std::ifstream in(json);
    const nlohmann::json report = nlohmann::json::parse(in);
    EXPECT_EQ(report.at("lost_final_states"), 0) << report.dump(2);
    EXPECT_EQ(report.at("load").at("errors"), 0) << report.at("load").dump(2);
    EXPECT_GE(report.at("load").at("updates").get<int>(), 250);
    EXPECT_GT(report.at("load").at("latency_ms").at("p99").get<double>(), 0.0);
    EXPECT_GE(report.at("rss_samples").size(), 25u);
    EXPECT_GT(report.at("rss_mib").at("end").get<double>(), 1.0);
    EXPECT_EQ(exit, report.at("passed").get<bool>() ? 0 : 1) << "the exit code is the verdict";
    EXPECT_TRUE(fs::exists(mDir / "soak.png"));
}

}  // namespace
}  // namespace pic::test
