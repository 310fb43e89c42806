#pragma once
/// `picbench budget`: what `picserver --update-budget-ms M` buys (server/progressive.h). For
/// each budget (0: unbudgeted, the baseline of the same run) it starts picserver on a free
/// loopback port over the scene's bake and runs `picclient load`'s test in this process: an
/// editor moving the first light `updateRate` times a second while N subscribers decode every
/// frame. Per budget it prints, from the editor's call to a subscriber holding the frame, the
/// time to the first visible change (any part of the version) and to the final state (p50,
/// p99), the earlier parts per update, the server's update time and CPU per update, and how
/// far the luma SH a client shows before the final state are from it. Writes JSON and a chart.

#include <cstdint>
#include <string>
#include <vector>

namespace pic {

struct BudgetBenchmarkParams {
    std::string scenePath;
    std::string bakePath;         ///< empty: a bake at `setting` made here
    std::string setting = "moderate";
    std::string backend = "gpu";
    std::vector<double> budgets = {0, 5, 10, 20, 40, 80};
    uint32_t clients = 64;
    double duration = 10.0;       ///< seconds of light changes per budget
    double updateRate = 2.0;      ///< light changes per second
    std::string picserver;        ///< empty: picserver next to picbench in the build tree
    std::string jsonPath = "out/budget_benchmark.json";
};

int runBudgetBenchmark(const BudgetBenchmarkParams& params);

}  // namespace pic
