#pragma once
/// A bake as the server serves it (ARCHITECTURE §1): the scene, the bake data, the one
/// runtime that relights it for every session on it, and what thin clients and browsers
/// download.

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "core/bake_data.h"
#include "core/error.h"
#include "core/frame_codec.h"
#include "core/scene.h"
#include "proto/pic.pb.h"
#include "rays/embree_scene.h"
#include "render/gpu_runtime.h"
#include "render/runtime.h"

namespace pic {

/// How the server relights its bakes.
struct ServeOptions {
    std::string backend = "gpu";  ///< "gpu" or "cpu" (the CPU twin)
    GpuRuntimeOptions gpu;        ///< the gpu backend's device, shadow maps and visibility
    BounceParams bounces;         ///< progressive by default, as everywhere
};

/// Bytes of one SceneChunk data message.
inline constexpr size_t kSceneChunkBytes = 1u << 20;

class ServedBake {
public:
    /// Loads the scene and its bake (refusing a bake of another scene), builds the runtime and
    /// the client assets. Errors name the file and the problem.
    static Result<std::unique_ptr<ServedBake>> load(const std::string& bakePath,
                                                    const std::string& scenePath,
                                                    const ServeOptions& options);

    /// 16 hex digits: a hash of the bake file's bytes.
    const std::string& id() const { return mId; }
    const Scene& scene() const { return mScene; }
    const BakeData& bake() const { return mBake; }
    /// The summary ListBakes returns.
    const v1::BakeSummary& summary() const { return mSummary; }
    /// The header GetScene sends first; the assets' bytes follow in its order.
    const v1::SceneHeader& header() const { return mHeader; }
    const std::vector<std::string>& assetBytes() const { return mAssetBytes; }
    /// The browsers' scene (server/web_scene.h), built on the first call from any thread and
    /// kept; every call gives what the first built, its size logged then.
    const Result<std::string>& webScene() const;
    /// The Vulkan device of the GPU backend, empty for the CPU twin.
    const std::string& device() const { return mDevice; }
    /// Where the GPU backend's direct visibility comes from ("shadow-maps", "rays"), empty
    /// for the CPU twin (which traces rays).
    const std::string& directVisibility() const { return mDirectVisibility; }

    /// Whether a session of this bake takes `lights`: they fit the scene (checkRuntimeLights)
    /// and a sky has the bake's sky transfer and a readable environment (checkSkyLights).
    /// InvalidInput (or the environment's error) naming the problem.
    Result<void> checkLights(const LightSet& lights) const;

    /// Milliseconds of the update run at load (see warmUp).
    double warmUpMs() const { return mWarmUpMs; }

    /// Relights the scene with `lights` and gives the resulting caches as a frame's half
    /// planes (core/frame_codec.h), one call at a time (the runtime keeps per-light state such
    /// as shadow maps). The server's relight pool calls it for one session of the bake at a
    /// time already, taking them in turns (server/relight_pool.h).
    /// `observer` sees every bounce's caches (Runtime::setLights).
    Result<void> relight(const LightSet& lights, UpdateStats& stats, HalfFrame& frame,
                         const BounceObserver& observer = {});

private:
    ServedBake() = default;
    Result<void> buildAssets(const std::string& scenePath);
    /// One update with the scene's own lights at load: a runtime that cannot relight fails
    /// the load, not a session, and what a process pays once (first touches of the runtime's
    /// memory, driver work at first dispatch, the lights' visibility) is not paid by the first
    /// session's first version (atrium on lavapipe: 62–74 ms without, 50–51 ms with).
    Result<void> warmUp();

    std::string mId;
    Scene mScene;
    BakeData mBake;
    std::unique_ptr<EmbreeScene> mRays;
    std::unique_ptr<Runtime> mRuntime;
    std::mutex mRuntimeMutex;  ///< one relight at a time
    std::string mDevice;
    std::string mDirectVisibility;
    double mWarmUpMs = 0.0;
    v1::BakeSummary mSummary;
    v1::SceneHeader mHeader;
    std::vector<std::string> mAssetBytes;
    mutable std::once_flag mWebSceneBuilt;
    mutable Result<std::string> mWebScene;  ///< set once, under mWebSceneBuilt
};

}  // namespace pic
