#include "server/picserver_cli.h"

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <future>
#include <iterator>
#include <utility>
#include <string>
#include <thread>
#include <vector>

#include <pthread.h>

#include <CLI/CLI.hpp>

#include "core/cli.h"
#include "render/gpu_runtime_flags.h"
#include "server/service.h"
#include "server/session_store.h"

namespace pic {

namespace {

using Clock = std::chrono::steady_clock;

int reportError(const Error& error) { return pic::reportError("picserver", error); }

Result<std::string> readTextFile(const std::string& path) {
    std::ifstream file(path, std::ios::binary);
    std::string text{std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
    if (!file && !file.eof()) return fail(ErrorCode::Io, "cannot read {}", path);
    if (text.empty()) return fail(ErrorCode::InvalidInput, "{} is empty", path);
    return text;
}

/// The update's line on stdout: version, ms per pass, encode ms, bytes, subscribers.
void logUpdate(const UpdateLog& log) {
    const Update& update = *log.update;
    std::string passes;
    for (const auto& [pass, ms] : update.stats.passMs) passes += fmt::format(" {}_ms={:.1f}", pass, ms);
    size_t bytes = 0;
    for (const v1::Plane& plane : update.broadcast->planes()) bytes += plane.data().size();
    std::string base = update.base.version == 0 ? std::string("key")
                       : update.base.part == 0 ? fmt::format("delta:{}", update.base.version)
                                               : fmt::format("delta:{}.{}", update.base.version,
                                                             update.base.part);
    if (update.part != 0) {
        std::printf("part session=%s version=%llu part=%u bounces=%d update_ms=%.1f "
                    "encode_ms=%.1f bytes=%zu frame=%s subscribers=%zu\n",
                    log.session.c_str(), (unsigned long long)update.version, update.part,
                    update.stats.bounces, update.broadcast->update_ms(), update.encodeMs, bytes,
                    base.c_str(), log.subscribers);
        std::fflush(stdout);
        return;
    }
    std::printf("update session=%s version=%llu bounces=%d%s runtime_ms=%.1f update_ms=%.1f "
                "encode_ms=%.1f "
                "bytes=%zu frame=%s subscribers=%zu\n",
                log.session.c_str(), (unsigned long long)update.version, update.stats.bounces,
                passes.c_str(), update.stats.totalMs, update.broadcast->update_ms(),
                update.encodeMs, bytes,
                base.c_str(), log.subscribers);
    std::fflush(stdout);
}

}  // namespace

int picserverMain(int argc, char** argv) {
    CLI::App app{"picserver: relights baked scenes on light changes and streams the caches to "
                 "the clients of each session over gRPC"};
    app.name("picserver");
    std::vector<std::string> bakePaths;
    std::vector<std::string> scenePaths;
    std::string listen = "127.0.0.1:50051";
    ServeOptions serve;
    ServerOptions options;
    app.add_option("--bake", bakePaths, "bake file (.pic); repeat with --scene for several bakes")
        ->required();
    app.add_option("--scene", scenePaths, "the scene each --bake was made from, in order")
        ->required();
    app.add_option("--listen", listen, "HOST:PORT to serve on; port 0 picks a free one");
    app.add_option("--backend", serve.backend, "runtime backend (cpu: the CPU twin)")
        ->check(CLI::IsMember({"cpu", "gpu"}));
    addGpuRuntimeFlags(app, serve.gpu);
    app.add_option("--bounces", serve.bounces.bounces,
                   "cache passes per update: 0 = direct light only, B = up to B reflections "
                   "(default: until a bounce adds < 0.5 % of the flux, at most 8)")
        ->check(CLI::Range(-1, 64));
    app.add_option("--keyframe-interval", options.session.keyframeInterval,
                   "every N-th version is streamed as a key frame, the others as deltas")
        ->check(CLI::Range(1u, 100000u));
    app.add_option("--zstd-level", options.session.zstdLevel, "zstd level of the frames (default 1)")
        ->check(CLI::Range(1, 19));
    app.add_option("--max-sessions", options.maxSessions, "sessions the server holds at most")
        ->check(CLI::Range(size_t(1), size_t(100000)));
    app.add_option("--db", options.dbPath,
                   "session database: an SQLite FILE (one server), or postgresql://… shared by "
                   "replicas; sessions, token digests and light sets survive a restart");
    app.add_option("--metrics-listen", options.metricsListen,
                   "HOST:PORT to serve Prometheus metrics on (GET /metrics); port 0 picks a "
                   "free one");
    app.add_option("--web-listen", options.webListen,
                   "HOST:PORT to serve browsers on: the session streams over WebSocket at "
                   "/v1/stream?session=ID&token=T, the scene, light sets and pages over HTTP; "
                   "port 0 picks a free one");
    app.add_option("--web-root", options.webRoot,
                   "folder of the pages --web-listen serves under / (index.html at /, the "
                   "scripts' libraries in its node_modules/)")
        ->capture_default_str();
    double idleMinutes = 60.0;
    app.add_option("--session-idle-minutes", idleMinutes,
                   "remove a session without subscribers after this long unused")
        ->check(CLI::PositiveNumber);
    std::string tlsCert;
    std::string tlsKey;
    auto* certOption = app.add_option("--tls-cert", tlsCert, "serve TLS with this certificate chain (PEM file)")
                           ->check(CLI::ExistingFile);
    auto* keyOption = app.add_option("--tls-key", tlsKey, "the certificate's private key (PEM file)")
                          ->check(CLI::ExistingFile);
    certOption->needs(keyOption);
    keyOption->needs(certOption);
    std::string apiKeysPath;
    app.add_option("--api-keys", apiKeysPath,
                   "operator API keys, one per line (16-256 printable characters, '#' comments): "
                   "CreateSession, ListBakes and GetScene then need one");
    app.add_flag("--allow-unauthenticated", options.allowUnauthenticated,
                 "serve a non-loopback --listen without --api-keys (anyone who reaches the port "
                 "may create sessions and download the scenes)");
    app.add_option("--set-lights-per-second", options.session.setLightsPerSecond,
                   "light sets a second one session accepts (as many at once), preset "
                   "changes counted with them; beyond, RESOURCE_EXHAUSTED with the delay "
                   "to wait (default 30)")
        ->check(CLI::Range(0.01, 1e6));
    app.add_option("--update-budget-ms", options.session.updateBudgetMs,
                   "an update expected to take longer than this (the session's last one did) "
                   "streams its caches in parts, one every M ms, most changed first, then its "
                   "exact final state; 0: never (default 0)")
        ->check(CLI::Range(0.0, 1e6));
    app.add_option("--max-sessions-per-client", options.maxSessionsPerClient,
                   "sessions one API key (without keys: one peer host) may hold; 0: only "
                   "--max-sessions (default 0)")
        ->check(CLI::Range(size_t(0), size_t(100000)));
    app.add_option("--max-streams-per-peer", options.maxStreamsPerPeer,
                   "Subscribe streams one peer host may hold open (default 1000)")
        ->check(CLI::Range(size_t(1), size_t(1000000)));
    std::vector<std::string> trustedProxies;
    app.add_option("--trusted-proxy", trustedProxies,
                   "a load balancer's ADDRESS or ADDRESS/PREFIX (repeatable): for calls through "
                   "it, per-peer quotas count the client address it appends to X-Forwarded-For");
    app.add_option("--relight-threads", options.relightThreads,
                   "threads that compute the sessions' versions, taking the sessions in turns, "
                   "whatever their number; 0: one per bake plus one (default 0)")
        ->check(CLI::Range(0u, 256u));
    double keepaliveSeconds = 30.0, connectionAgeMinutes = 60.0;
    app.add_option("--keepalive-seconds", keepaliveSeconds,
                   "ping a client after this long without traffic; one that does not answer "
                   "within as long (at most 20 s) is disconnected")
        ->check(CLI::Range(1.0, 86400.0));
    app.add_option("--max-connection-age-minutes", connectionAgeMinutes,
                   "ask connections older than this to reconnect (calls in progress finish); 0: "
                   "never")
        ->check(CLI::Range(0.0, 1e6));
    app.add_option("--audit-log", options.auditLog,
                   "append a JSON line per call here: time, peer, credential id, call, session, "
                   "outcome (never a token or key)");
    addGlobalFlags(app);
    if (auto exit = parseCommandLine(app, argc, argv)) return *exit;
    if (bakePaths.size() != scenePaths.size())
        return reportError({ErrorCode::InvalidInput,
                            fmt::format("{} --bake but {} --scene; give one scene per bake",
                                        bakePaths.size(), scenePaths.size())});
    if (!apiKeysPath.empty()) {
        auto keys = ApiKeys::load(apiKeysPath);
        if (!keys) return reportError(keys.error());
        options.apiKeys = std::move(*keys);
        std::fprintf(stderr, "picserver: %zu API key%s: %s\n", options.apiKeys.size(),
                     options.apiKeys.size() == 1 ? "" : "s",
                     fmt::format("{}", fmt::join(options.apiKeys.ids(), ", ")).c_str());
    }
    for (const std::string& proxy : trustedProxies)
        if (auto added = options.trustedProxies.add(proxy); !added) return reportError(added.error());
    // So is a server open to anyone who reaches its address.
    if (auto open = checkOpenListen(listen, !options.apiKeys.empty(), options.allowUnauthenticated); !open)
        return reportError(open.error());
    // A database file that cannot be used is refused before the bakes take seconds to load.
    if (!options.dbPath.empty() && !SessionStore::isPostgres(options.dbPath))
        if (auto usable = SessionStore::checkPath(options.dbPath); !usable)
            return reportError(usable.error());
    // SIGINT and SIGTERM go to one thread, never to whichever thread gRPC, TBB or Vulkan runs:
    // before the server is up they end the process at once, after it they shut it down.
    sigset_t stopSignals;
    sigemptyset(&stopSignals);
    sigaddset(&stopSignals, SIGINT);
    sigaddset(&stopSignals, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &stopSignals, nullptr);
    std::atomic<bool> serving{false};
    std::promise<int> stopped;
    std::thread signalThread([&] {
        int signal = 0;
        sigwait(&stopSignals, &signal);
        if (!serving) {
            std::fprintf(stderr, "picserver: interrupted while loading\n");
            std::_Exit(130);
        }
        stopped.set_value(signal);
    });
    signalThread.detach();

    std::vector<std::unique_ptr<ServedBake>> bakes;
    for (size_t i = 0; i < bakePaths.size(); ++i) {
        const auto start = Clock::now();
        auto bake = ServedBake::load(bakePaths[i], scenePaths[i], serve);
        if (!bake) return reportError(bake.error());
        const v1::BakeSummary& summary = (*bake)->summary();
        std::fprintf(stderr,
                     "picserver: bake %s: %s, %u triangles, %u surfels, %u caches × %u %s links, "
                     "%s backend%s%s%s%s, loaded in %.1f s (a first update %.0f ms of it)\n",
                     summary.bake_id().c_str(), summary.scene_name().c_str(), summary.triangles(),
                     summary.surfels(), summary.caches(), summary.links_per_cache(),
                     summary.link_mode().c_str(), serve.backend.c_str(),
                     (*bake)->device().empty() ? "" : " on ", (*bake)->device().c_str(),
                     (*bake)->directVisibility().empty() ? "" : ", direct visibility by ",
                     (*bake)->directVisibility().c_str(),
                     std::chrono::duration<double>(Clock::now() - start).count(),
                     (*bake)->warmUpMs());
        bakes.push_back(std::move(*bake));
    }

    for (const auto& [path, pem] : {std::pair{tlsCert, &options.tlsCertPem}, std::pair{tlsKey, &options.tlsKeyPem}}) {
        if (path.empty()) continue;
        auto text = readTextFile(path);
        if (!text) return reportError(text.error());
        *pem = std::move(*text);
    }
    options.sessionIdle = std::chrono::milliseconds(int64_t(idleMinutes * 60000.0));
    options.keepalive = std::chrono::milliseconds(int64_t(keepaliveSeconds * 1000.0));
    options.maxConnectionAge = std::chrono::milliseconds(int64_t(connectionAgeMinutes * 60000.0));
    options.session.log = logUpdate;
    options.onListening = [](const std::string& address) {
        std::printf("listening on %s\n", address.c_str());
        std::fflush(stdout);
    };
    auto server = PicServer::start(std::move(bakes), listen, std::move(options));
    if (!server) return reportError(server.error());
    if (!(*server)->metricsAddress().empty())
        std::fprintf(stderr, "picserver: metrics on http://%s/metrics\n",
                     (*server)->metricsAddress().c_str());
    if (!(*server)->webAddress().empty())
        std::fprintf(stderr, "picserver: browsers on http://%s/ (streams at ws://%s/v1/stream)\n",
                     (*server)->webAddress().c_str(), (*server)->webAddress().c_str());

    serving = true;
    const int signal = stopped.get_future().get();
    std::fprintf(stderr, "picserver: %s, shutting down\n", signal == SIGINT ? "SIGINT" : "SIGTERM");
    (*server)->shutdown();
    return 0;
}

}  // namespace pic
