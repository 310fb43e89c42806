#pragma once
/// The thin client's side of the wire (proto/pic.proto): a connection to a picserver, the
/// scene download, the frame stream and the decoder that turns frames back into the cache
/// textures the server computed.

#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "core/cache_textures.h"
#include "core/error.h"
#include "core/frame_codec.h"
#include "core/light_set.h"
#include "core/scene.h"
#include "proto/pic.grpc.pb.h"
#include "render/renderer.h"

namespace pic {

/// A bake's scene as a thin client holds it: the scene loaded from the downloaded files and
/// what it needs to place and sample the cache textures.
struct ClientScene {
    v1::SceneHeader header;
    std::string folder;                     ///< where the assets were written
    Scene scene;
    std::vector<glm::vec2> triangleUvs;     ///< 3 light-map UVs per triangle (kNotLightmapped: grid)
    std::vector<uint32_t> gridCaches;       ///< per grid vertex its cache, kNoCache for none
    std::vector<uint32_t> lightmapCaches;   ///< per light-map texel its cache, kNoCache for none

    /// Where a frame's caches go in the textures (views into this scene).
    CacheIndexMaps indexMaps() const;
};

/// A Subscribe stream: frames as they arrive, until the stream ends or is cancelled.
///
/// With a `patience`, a stream the server ends UNAVAILABLE (it is draining, or the session
/// moved to another replica) or that breaks (INTERNAL, UNKNOWN: a proxy lost its upstream) is
/// subscribed again, with backoff from 50 ms to 2 s, until a frame arrives or `patience`
/// passes without one. The first frame after a resubscription is a key frame of the latest
/// version, which a FrameDecoder takes whatever it held.
class FrameStream {
public:
    FrameStream(v1::Pic::Stub& stub, v1::SubscribeRequest request,
                std::chrono::milliseconds patience = std::chrono::milliseconds(0));
    ~FrameStream();

    /// Blocks for the next frame into `frame`; false when the stream has ended (status() says
    /// why).
    bool next(v1::Frame& frame);
    /// Ends the stream from any thread; next() then returns false.
    void cancel();
    /// The stream's final status, once next() returned false.
    grpc::Status status();
    /// How many times the stream was subscribed again.
    uint32_t resubscriptions() const { return mResubscriptions; }

private:
    /// Starts a call (under mMutex).
    void start();
    /// Ends the current call: cancels and drains it, and returns its status.
    grpc::Status finishCall();

    v1::Pic::Stub& mStub;
    const v1::SubscribeRequest mRequest;
    const std::chrono::milliseconds mPatience;
    std::mutex mMutex;  ///< guards the context against cancel() from another thread
    std::condition_variable mWake;  ///< cancel() ends a backoff wait
    bool mCancelled = false;
    std::unique_ptr<grpc::ClientContext> mContext;
    std::unique_ptr<grpc::ClientReader<v1::Frame>> mReader;
    bool mFinished = false;
    grpc::Status mStatus;
    std::atomic<uint32_t> mResubscriptions{0};
};

/// How a PicConnection reaches its server.
struct ConnectOptions {
    /// How long to wait for the server to accept the connection.
    std::chrono::milliseconds timeout = std::chrono::seconds(10);
    /// TLS, trusting these certificates (PEM); empty: plaintext.
    std::string rootCertsPem;
    /// Sent with every call as `authorization: Bearer KEY`: the operator credential of a
    /// server with --api-keys; empty: none.
    std::string apiKey;
    /// A ping after this long without traffic, and the connection counted as dead when the
    /// answer takes as long again (at most 10 s): a stream from a server that stopped
    /// answering (frozen, or its network gone) fails UNAVAILABLE instead of waiting forever.
    std::chrono::milliseconds keepalive = std::chrono::seconds(20);
};

/// A channel to one picserver and its calls, each returning the server's refusal as an Error
/// that names the call and the status (INVALID_ARGUMENT → InvalidInput, ...).
class PicConnection {
public:
    /// Connects to `address` ("HOST:PORT"), waiting up to `options.timeout` for the server; Io
    /// when it cannot be reached. InvalidInput for an API key that no header can carry.
    static Result<std::unique_ptr<PicConnection>> connect(const std::string& address,
                                                          const ConnectOptions& options = {});

    const std::string& address() const { return mAddress; }
    /// How long session calls (create, join, stats, set lights) go on trying while the
    /// server answers UNAVAILABLE (it drains, the session moved to another replica, a replica
    /// behind the load balancer went away) or RESOURCE_EXHAUSTED with a delay to wait (too
    /// many light sets a second). 0 (the default): one try. A retried SetLights that
    /// had been applied before its reply was lost is applied again as a newer version of the
    /// same set.
    void setPatience(std::chrono::milliseconds patience) { mPatience = patience; }
    std::chrono::milliseconds patience() const { return mPatience; }
    v1::Pic::Stub& stub() { return *mStub; }

    Result<v1::ListBakesResponse> listBakes();
    Result<v1::CreateSessionResponse> createSession(const std::string& bakeId = "");
    Result<v1::JoinSessionResponse> joinSession(const std::string& session, const std::string& token);
    /// Pushes a light set; the version it will produce.
    Result<uint64_t> setLights(const std::string& session, const std::string& token,
                               const LightSet& lights);
    /// The assets of bake `bakeId` (empty: the server's first), kept in `cacheDir`/<bake id>:
    /// reused when that folder holds exactly the server's header, else downloaded into a
    /// fresh folder that replaces it atomically. Loads them; Corrupt when the loaded scene's
    /// hash is not the one the server announced. `downloaded` (optional) says which it was.
    Result<ClientScene> fetchScene(const std::string& bakeId, const std::string& cacheDir,
                                   bool* downloaded = nullptr);
    /// The header of bake `bakeId`'s scene (GetScene, header only): what a client needs to
    /// check the frames of a session on that bake (FrameDecoder).
    Result<v1::SceneHeader> sceneHeader(const std::string& bakeId);
    /// The session's counters (GetStats).
    Result<v1::SessionStats> stats(const std::string& session, const std::string& token);
    /// Starts a Subscribe stream; with a `patience`, one that subscribes again when the server
    /// sends it elsewhere (FrameStream).
    std::unique_ptr<FrameStream> subscribe(const std::string& session, const std::string& token,
                                           std::chrono::milliseconds patience = std::chrono::milliseconds(0));

private:
    /// GetScene: the header, and the assets written under `folder` unless `headerOnly`.
    Result<v1::SceneHeader> getScene(const std::string& bakeId, bool headerOnly,
                                     const std::string& folder);

    std::string mAddress;
    std::chrono::milliseconds mPatience{0};
    std::shared_ptr<grpc::Channel> mChannel;
    std::unique_ptr<v1::Pic::Stub> mStub;
};

/// Turns a session's frames back into the textures, exactly: key frames replace the held
/// version, delta frames apply to the version they were made from.
class FrameDecoder {
public:
    /// A decoder for the frames of a session on `header`'s bake: a frame whose planes do not
    /// hold that bake's caches is refused before anything is allocated for it.
    explicit FrameDecoder(const v1::SceneHeader& header);
    /// Decodes `frame` (its bytes are moved out). Corrupt when it is a delta against a state
    /// other than the one held, does not decode or carries a light set that does not parse;
    /// the held state is then unchanged.
    Result<void> apply(v1::Frame& frame);
    /// The version held, 0 before the first key frame.
    uint64_t version() const { return mVersion; }
    /// The part of it held: 0, its final state; k ≥ 1, the k-th earlier part of a budgeted
    /// update (v1::Frame::part).
    uint32_t part() const { return mPart; }
    /// Whether what is held is at least `version`'s final state (or any part of a newer one).
    bool holds(uint64_t version) const {
        return mVersion > version || (mVersion == version && mPart == 0);
    }
    const HalfFrame& frame() const { return mFrame; }
    /// The light set of the newest frame that carried one (null before): the direct light and
    /// indirect scales to shade the held caches with.
    const LightSet* lights() const { return mLights ? &*mLights : nullptr; }

private:
    HalfFrame mFrame;
    uint64_t mVersion = 0;
    uint32_t mPart = 0;
    std::optional<LightSet> mLights;
    std::array<size_t, kFramePlanes> mExpected{};  ///< values per plane
};

/// The textures of `frame` for `scene`: its caches, halves widened to floats, written into
/// every grid vertex and light-map texel that holds them (core/cache_textures.h), with
/// coverage from the index maps. InvalidInput when the frame's planes do not hold the
/// scene's caches and band counts.
Result<CacheTextures> cacheTexturesOf(const ClientScene& scene, const HalfFrame& frame);

/// The caches a frame holds, widened to floats (InvalidInput as cacheTexturesOf).
Result<CacheValues> cacheValuesOf(const ClientScene& scene, const HalfFrame& frame);

/// The textures of `values` for `scene` (the same layout as cacheTexturesOf's).
CacheTextures cacheTexturesOf(const ClientScene& scene, const CacheValues& values);

/// The renderer's layout (render/renderer.h) of a downloaded scene.
ClientLayout clientLayoutOf(const ClientScene& scene);

}  // namespace pic
