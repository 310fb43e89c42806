// The browsers' transport (server/web_server.h) read as a browser reads it, with civetweb's
// WebSocket client on 127.0.0.1: the gRPC stream's frames byte for byte, decoded to the
// server's caches, a key frame first on every connection, and refusals and the server's stop
// said in the close frame. Every server a test starts is stopped by it.
#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <civetweb.h>
#include <google/protobuf/util/message_differencer.h>

#include "tests/client/stream_fixture.h"

namespace pic {
namespace {

using namespace std::chrono_literals;
using namespace test;

/// One browser's socket: every binary message parsed as a v1::Frame (and decoded, given the
/// scene's header), and the close frame's code and reason.
class WebReader {
public:
    WebReader(const std::string& address, const std::string& session, const std::string& token,
              const v1::SceneHeader* header = nullptr) {
        if (header) mDecoder.emplace(*header);
        static std::once_flag initialised;
        std::call_once(initialised, [] { mg_init_library(MG_FEATURES_WEBSOCKET); });
        const size_t colon = address.rfind(':');
        const std::string host = address.substr(0, colon);
        const int port = std::stoi(address.substr(colon + 1));
        const std::string path = "/v1/stream?session=" + session + "&token=" + token;
        char error[256] = {};
        mConnection = mg_connect_websocket_client(host.c_str(), port, 0, error, sizeof error,
                                                  path.c_str(), nullptr, onData, onClose, this);
        EXPECT_TRUE(mConnection) << error;
    }
    ~WebReader() {
        if (mConnection) mg_close_connection(mConnection);
    }

    /// Waits until `count` frames came (or the socket closed).
    bool waitForFrames(size_t count, std::chrono::milliseconds timeout = 30s) {
        std::unique_lock lock(mMutex);
        return mChanged.wait_for(lock, timeout, [&] { return mFrames.size() >= count || mClosed; }) &&
               mFrames.size() >= count;
    }
    /// Waits until the decoder holds `version`'s final state.
    bool waitForVersion(uint64_t version, std::chrono::milliseconds timeout = 30s) {
        std::unique_lock lock(mMutex);
        return mChanged.wait_for(lock, timeout, [&] { return (mDecoder && mDecoder->holds(version)) || mClosed; }) &&
               mDecoder && mDecoder->holds(version);
    }
    /// Waits for the close frame: its code, 0 when none came in time.
    int waitForClose(std::chrono::milliseconds timeout = 30s) {
        std::unique_lock lock(mMutex);
        mChanged.wait_for(lock, timeout, [&] { return mCloseCode != 0; });
        return mCloseCode;
    }
    std::vector<v1::Frame> frames() {
        std::lock_guard lock(mMutex);
        return mFrames;
    }
    HalfFrame decoded() {
        std::lock_guard lock(mMutex);
        return mDecoder ? mDecoder->frame() : HalfFrame{};
    }
    /// Stops reading (the next message waits in the data handler until release()): a browser
    /// tab that falls behind.
    void stall() {
        std::lock_guard lock(mMutex);
        mStalled = true;
    }
    void release() {
        {
            std::lock_guard lock(mMutex);
            mStalled = false;
        }
        mChanged.notify_all();
    }
    std::string reason() {
        std::lock_guard lock(mMutex);
        return mReason;
    }
    std::vector<std::string> errors() {
        std::lock_guard lock(mMutex);
        return mErrors;
    }

private:
    static int onData(mg_connection*, int bits, char* data, size_t length, void* self) {
        auto* reader = static_cast<WebReader*>(self);
        const int opcode = bits & 0x0f;
        {
            std::unique_lock lock(reader->mMutex);
            reader->mChanged.wait(lock, [&] { return !reader->mStalled; });
            if (opcode == MG_WEBSOCKET_OPCODE_BINARY) {
                v1::Frame frame;
                if (!frame.ParseFromArray(data, int(length))) {
                    reader->mErrors.push_back("a message that is not a v1::Frame");
                } else {
                    reader->mFrames.push_back(frame);
                    if (reader->mDecoder)
                        if (auto applied = reader->mDecoder->apply(frame); !applied)
                            reader->mErrors.push_back(applied.error().message);
                }
            } else if (opcode == MG_WEBSOCKET_OPCODE_CONNECTION_CLOSE && length >= 2) {
                reader->mCloseCode = (uint8_t(data[0]) << 8) | uint8_t(data[1]);
                reader->mReason.assign(data + 2, length - 2);
            }
        }
        reader->mChanged.notify_all();
        return opcode == MG_WEBSOCKET_OPCODE_CONNECTION_CLOSE ? 0 : 1;
    }
    static void onClose(const mg_connection*, void* self) {
        auto* reader = static_cast<WebReader*>(self);
        {
            std::lock_guard lock(reader->mMutex);
            reader->mClosed = true;
        }
        reader->mChanged.notify_all();
    }

    mg_connection* mConnection = nullptr;
    std::mutex mMutex;
    std::condition_variable mChanged;
    std::vector<v1::Frame> mFrames;
    std::optional<FrameDecoder> mDecoder;
    std::vector<std::string> mErrors;
    int mCloseCode = 0;
    std::string mReason;
    bool mClosed = false;
    bool mStalled = false;
};

ServerOptions withWeb() {
    ServerOptions options;
    options.session.setLightsPerSecond = 1e6;
    options.webListen = "127.0.0.1:0";
    return options;
}

TEST(WebStream, ABrowserGetsTheGrpcStreamsFramesAndDecodesTheServersCaches) {
    Served served = serveWith(withWeb());
    ASSERT_TRUE(served.connection);
    ASSERT_FALSE(served.server->webAddress().empty());
    auto session = served.connection->createSession();
    ASSERT_TRUE(session);
    auto live = served.server->session(session->session());
    ASSERT_TRUE(live->waitForVersion(1, 30s));

    const v1::SceneHeader header = sceneHeaderOf(*served.connection);
    WebReader browser(served.server->webAddress(), session->session(), session->viewer_token(),
                      &header);
    ASSERT_TRUE(browser.waitForVersion(1));
    Reader native(*served.connection, session->session(), session->viewer_token());
    ASSERT_TRUE(native.waitFor(1));
    for (int i = 0; i < 3; ++i) {
        auto version = served.connection->setLights(session->session(), session->editor_token(),
                                                    pointLight(-0.2f + 0.2f * float(i)));
        ASSERT_TRUE(version);
        ASSERT_TRUE(live->waitForVersion(*version, 30s));
        ASSERT_TRUE(browser.waitForVersion(*version)) << "version " << *version;
        ASSERT_TRUE(native.waitFor(*version));
        // The frame a browser holding the previous version gets is the one broadcast (a
        // message equal field by field: the order of a map's entries on the wire is not fixed).
        const auto update = live->latestUpdate();
        EXPECT_TRUE(google::protobuf::util::MessageDifferencer::Equals(browser.frames().back(),
                                                                       *update->broadcast));
    }
    EXPECT_TRUE(browser.errors().empty()) << browser.errors().front();
    EXPECT_TRUE(browser.decoded() == *live->latestUpdate()->frame);
    EXPECT_TRUE(browser.decoded() == native.frame());
    const auto frames = browser.frames();
    ASSERT_FALSE(frames.empty());
    EXPECT_EQ(frames.front().base_version(), 0u) << "a key frame first";
    // The WebSocket thread counts a frame once its write returns, which may be after the
    // browser has read it.
    const size_t sent = frames.size() + 4;
    for (auto end = std::chrono::steady_clock::now() + 10s;
         live->stats().frames_sent() < sent && std::chrono::steady_clock::now() < end;)
        std::this_thread::sleep_for(10ms);
    EXPECT_GE(live->stats().frames_sent(), sent);

    // A browser that connects later starts on the newest version's key frame.
    WebReader late(served.server->webAddress(), session->session(), session->editor_token());
    ASSERT_TRUE(late.waitForFrames(1));
    EXPECT_EQ(late.frames().front().base_version(), 0u);
    EXPECT_EQ(late.frames().front().version(), live->latestVersion());
}

// Latest wins on the WebSocket too: a browser that stops reading holds up nobody, and once it
// reads again it gets what the sockets had buffered, then the newest state (a key frame where
// it skipped), never every version.
TEST(WebStream, AStalledBrowserDelaysNobodyAndSkipsToTheLast) {
    Served served = serveWith(withWeb());
    ASSERT_TRUE(served.connection);
    auto session = served.connection->createSession();
    ASSERT_TRUE(session);
    auto live = served.server->session(session->session());
    ASSERT_TRUE(live->waitForVersion(1, 30s));
    const v1::SceneHeader header = sceneHeaderOf(*served.connection);
    WebReader stalled(served.server->webAddress(), session->session(), session->viewer_token(),
                      &header);
    ASSERT_TRUE(stalled.waitForVersion(1));
    stalled.stall();
    WebReader fast(served.server->webAddress(), session->session(), session->viewer_token(),
                   &header);
    ASSERT_TRUE(fast.waitForVersion(1));

    constexpr int kUpdates = 200;
    uint64_t last = 0;
    for (int i = 0; i < kUpdates; ++i) {
        auto version = served.connection->setLights(session->session(), session->editor_token(),
                                                    pointLight(0.01f * float(i % 20)));
        ASSERT_TRUE(version);
        last = *version;
        ASSERT_TRUE(fast.waitForVersion(last)) << "the fast browser waited on the stalled one";
    }
    stalled.release();
    ASSERT_TRUE(stalled.waitForVersion(last));
    EXPECT_TRUE(stalled.errors().empty()) << stalled.errors().front();
    EXPECT_TRUE(stalled.decoded() == *live->latestUpdate()->frame);
    const size_t frames = stalled.frames().size();
    std::printf("the stalled browser received %zu frames for %llu versions\n", frames,
                (unsigned long long)last);
    EXPECT_LT(frames, size_t(last));
}

TEST(WebStream, ARefusalSaysWhyInTheCloseFrame) {
    Served served = serveWith(withWeb());
    ASSERT_TRUE(served.connection);
    auto session = served.connection->createSession();
    ASSERT_TRUE(session);

    WebReader stranger(served.server->webAddress(), session->session(), "not-a-token");
    EXPECT_EQ(stranger.waitForClose(), 4000 + int(grpc::StatusCode::UNAUTHENTICATED));
    EXPECT_NE(stranger.reason().find("not one of session"), std::string::npos) << stranger.reason();
    EXPECT_TRUE(stranger.frames().empty());

    WebReader lost(served.server->webAddress(), "0123456789abcdef", session->viewer_token());
    EXPECT_EQ(lost.waitForClose(), 4000 + int(grpc::StatusCode::NOT_FOUND));
    EXPECT_NE(lost.reason().find("0123456789abcdef"), std::string::npos) << lost.reason();
}

TEST(WebStream, AServerThatStopsEndsTheStreamSayingSubscribeAgain) {
    Served served = serveWith(withWeb());
    ASSERT_TRUE(served.connection);
    auto session = served.connection->createSession();
    ASSERT_TRUE(session);
    WebReader browser(served.server->webAddress(), session->session(), session->viewer_token());
    ASSERT_TRUE(browser.waitForFrames(1));
    std::thread stopping([&] { served.server->shutdown(); });
    EXPECT_EQ(browser.waitForClose(), 4000 + int(grpc::StatusCode::UNAVAILABLE));
    EXPECT_NE(browser.reason().find("subscribe again"), std::string::npos) << browser.reason();
    stopping.join();
}

TEST(WebStream, AnAddressThatCannotBeServedIsRefusedNamingIt) {
    ServerOptions options = withWeb();
    options.webListen = "no-port";
    auto server = startOn(options);
    ASSERT_FALSE(server);
    EXPECT_EQ(server.error().code, ErrorCode::InvalidInput);
    EXPECT_NE(server.error().message.find("no-port"), std::string::npos) << server.error().message;
}

}  // namespace
}  // namespace pic
