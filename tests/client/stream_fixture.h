#pragma once
/// What the client tests share: the test bake, a server over it on loopback with a connection
/// to it, a frame reader, child processes of the command-line tools and the health check.

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <mutex>
#include <optional>
#include <utility>
#include <string>
#include <thread>
#include <vector>

#include <sys/types.h>

#include "client/connection.h"
#include "core/frame_codec.h"
#include "core/light_set.h"
#include "proto/wire.h"
#include "server/service.h"

namespace pic::test {

/// The Cornell box test scene.
extern const std::string kScene;

/// A small bake of the Cornell box, written once per test process into a scratch directory
/// that goes when the process exits.
const std::string& bakePath();

struct Served {
    std::unique_ptr<PicServer> server;
    std::unique_ptr<PicConnection> connection;
};

/// A server over the test bake on 127.0.0.1 (one bounce, no light-set rate limit), and a
/// connection to it.
Served serve(const std::string& backend = "cpu", uint32_t keyframeInterval = 32,
             std::chrono::milliseconds sessionIdle = std::chrono::hours(1),
             const std::string& dbPath = "");

/// The same with every server option given, and the runtime's bounce count.
Served serveWith(const ServerOptions& options, const std::string& backend = "cpu",
                 int bounces = 1);

/// Starts a server over the test bake with `options`, the backend and bounce count (−1:
/// progressive); its error when it cannot.
Result<std::unique_ptr<PicServer>> startOn(const ServerOptions& options,
                                           const std::string& backend = "cpu", int bounces = 1);

/// Starts a server over the test bake with the session database at `dbPath`.
Result<std::unique_ptr<PicServer>> startWithDatabase(const std::string& dbPath);

/// One point light inside the box at x.
LightSet pointLight(float x);

/// The header of the served bake, for the decoders.
v1::SceneHeader sceneHeaderOf(PicConnection& connection);

/// Reads frames on its own thread, decoding each, until cancelled.
class Reader {
public:
    /// With a `patience`, the stream subscribes again when sent elsewhere (FrameStream).
    Reader(PicConnection& connection, const std::string& session, const std::string& token,
           std::chrono::milliseconds patience = std::chrono::milliseconds(0))
        : mDecoder(sceneHeaderOf(connection)),
          mStream(connection.subscribe(session, token, patience)),
          mThread([this] { run(); }) {}
    ~Reader() {
        mStream->cancel();
        mThread.join();
    }

    /// Waits until a frame of version ≥ `version` was decoded.
    bool waitFor(uint64_t version, std::chrono::milliseconds timeout = std::chrono::seconds(30)) {
        const auto start = std::chrono::steady_clock::now();
        while (std::chrono::steady_clock::now() - start < timeout) {
            {
                std::lock_guard lock(mMutex);
                if (!versions.empty() && versions.back() >= version) return true;
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
        }
        return false;
    }

    std::vector<uint64_t> received() {
        std::lock_guard lock(mMutex);
        return versions;
    }
    std::vector<bool> keys() {
        std::lock_guard lock(mMutex);
        return keyFrames;
    }
    /// Whether the final state of `version` (or anything newer) was decoded.
    bool holds(uint64_t version) {
        std::lock_guard lock(mMutex);
        return mDecoder.holds(version);
    }
    HalfFrame frame() {
        std::lock_guard lock(mMutex);
        return mDecoder.frame();
    }
    /// The light set of the newest frame that carried one.
    std::optional<LightSet> lights() {
        std::lock_guard lock(mMutex);
        return mDecoder.lights() ? std::optional<LightSet>(*mDecoder.lights()) : std::nullopt;
    }
    std::vector<std::string> errors() {
        std::lock_guard lock(mMutex);
        return mErrors;
    }
    /// Waits for the stream to end by itself; its status code's name ("UNAVAILABLE", ...), or
    /// "running" when it did not end within `timeout`.
    std::string waitForEnd(std::chrono::milliseconds timeout = std::chrono::seconds(30)) {
        const auto start = std::chrono::steady_clock::now();
        while (std::chrono::steady_clock::now() - start < timeout) {
            {
                std::lock_guard lock(mMutex);
                if (mEnded) return mEndCode;
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
        }
        return "running";
    }

private:
    void run() {
        v1::Frame frame;
        while (mStream->next(frame)) {
            std::lock_guard lock(mMutex);
            keyFrames.push_back(frame.base_version() == 0);
            const uint64_t version = frame.version();
            if (auto applied = mDecoder.apply(frame); !applied)
                mErrors.push_back(applied.error().message);
            versions.push_back(version);
        }
        const grpc::Status status = mStream->status();
        std::lock_guard lock(mMutex);
        mEnded = true;
        mEndCode = wire::statusName(status.error_code());
    }

    FrameDecoder mDecoder;
    std::unique_ptr<FrameStream> mStream;
    std::mutex mMutex;
    std::vector<uint64_t> versions;
    std::vector<bool> keyFrames;
    std::vector<std::string> mErrors;
    bool mEnded = false;
    std::string mEndCode;
    std::thread mThread;
};

/// A command-line tool run with its stdout on a pipe. A child not waited for is killed
/// (SIGKILL) and reaped when the object goes, so a failing test leaves no server behind.
class Child {
public:
    Child() = default;
    explicit Child(const std::vector<std::string>& args);
    ~Child();
    Child(Child&& other) noexcept;
    Child& operator=(Child&& other) noexcept;

    pid_t pid() const { return mPid; }
    /// Standard output's read end.
    FILE* out() const { return mOut; }
    /// Sends `signal`.
    void signal(int signal) const;
    /// Waits for the exit: its code, or 128 + the signal that ended it.
    int wait();
    /// The same, waiting at most `timeout`: nothing when it is still running then.
    std::optional<int> waitFor(std::chrono::milliseconds timeout);

private:
    pid_t mPid = -1;
    FILE* mOut = nullptr;
};

/// One line of `file` without its newline; "" at the end.
std::string readLine(FILE* file);
/// Runs `command` through the shell; its stdout, its exit code in `exit`.
std::string run(const std::string& command, int& exit);

/// An HTTP reply: the status line ("error: …" when there was none), the header lines
/// ("Name: value", as sent) and the body.
struct HttpReply {
    std::string status;
    std::string body;
    std::vector<std::string> headers;

    /// The status code, 0 without a status line.
    int code() const;
    /// The value of header `name` (any case), "" without one.
    std::string header(const std::string& name) const;
};
/// An HTTP/1.1 request `method` of `path` (sent as written, unescaped) to `address`
/// ("HOST:PORT") with `body` and the extra header lines `headers` ("Name: value"), on a
/// connection of its own that the server closes.
HttpReply httpRequest(const std::string& address, const std::string& method,
                      const std::string& path, const std::string& body = "",
                      const std::vector<std::string>& headers = {});
/// An HTTP/1.1 GET of `path` from `address`.
HttpReply httpGet(const std::string& address, const std::string& path);

/// The value of the Prometheus sample `series` (name with its labels, as exposed) in `text`,
/// or −1 when it is not there.
double metricValue(const std::string& text, const std::string& series);

/// What the gRPC health check says of the whole server at `address`: "SERVING",
/// "NOT_SERVING", or what went wrong.
std::string healthStatus(const std::string& address);

}  // namespace pic::test
