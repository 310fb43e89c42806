#pragma once
/// `picbench stream`: the product end to end under load (issue 5's benchmark). Bakes the
/// scene at a paper 000 Table 2 setting, starts picserver as a child process on a free
/// loopback port, and for each subscriber count runs `picclient load`'s test in this process:
/// an editor moving the first light `updateRate` times a second for `duration` seconds while
/// N subscribers decode every frame they receive. Per count it prints the latency from the
/// editor's call to each subscriber holding the frame (p50, p95, p99, max), the server's CPU
/// time per update (from /proc: it should not grow with N), bytes and bits per SH coefficient
/// of key and delta frames. Writes JSON.

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench/server_process.h"
#include "client/load_test.h"

namespace pic {

struct StreamBenchmarkParams {
    std::string scenePath;
    std::string setting = "moderate";
    std::string linkMode = "rtp";
    std::string backend = "gpu";
    int bounces = 1;
    std::vector<uint32_t> clients = {1, 16, 64, 200};
    double duration = 10.0;       ///< seconds of light changes per subscriber count
    double updateRate = 2.0;      ///< light changes per second
    std::string picserver;        ///< empty: picserver next to picbench in the build tree
    std::string jsonPath = "out/stream_benchmark.json";
};

int runStreamBenchmark(const StreamBenchmarkParams& params);

/// `picclient load`'s test through `connection` to `server`, its report with
/// `server_cpu_ms_per_update` added: the server's CPU while the editor changed lights (the
/// subscribers' first key frames and their stream setup are outside that window), per update.
Result<nlohmann::ordered_json> runLoadOn(const ServerProcess& server, PicConnection& connection,
                                         LoadOptions load);


}  // namespace pic
