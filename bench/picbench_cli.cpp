#include "bench/picbench_cli.h"

#include <CLI/CLI.hpp>

#include "bake/bake_options_cli.h"
#include "bench/bake_benchmark.h"
#include "core/parallel.h"
#include "core/progress.h"

namespace pic {

int picbenchMain(int argc, char** argv) {
    CLI::App app{"picbench: pic benchmarks (timings, memory, bytes) printed and written as JSON"};
    app.require_subcommand(1);
    app.fallthrough();  // global flags may follow the subcommand
    int threads = 0;
    bool quiet = false;
    app.add_option("--threads", threads, "worker threads (0 = all cores)")->check(CLI::NonNegativeNumber);
    app.add_flag("--quiet", quiet, "no progress bars");

    CLI::App* bake = app.add_subcommand("bake", "time every bake stage on one scene");
    BakeBenchmarkParams params;
    BakeOptionFlags flags;
    bake->add_option("--scene", params.scenePath, "scene file (.gltf or .glb)")->required();
    bake->add_option("--repeat", params.repeat, "bakes to run; stage times are medians (default 1)")
        ->check(CLI::PositiveNumber);
    bake->add_option("--json", params.jsonPath, "write the figures to this JSON file");
    flags.addTo(*bake);

    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        app.exit(e);
        return 2;
    }
    setWorkerCount(threads);
    Progress::setEnabled(!quiet);
    params.options = flags.toOptions();
    return runBakeBenchmark(params);
}

}  // namespace pic
