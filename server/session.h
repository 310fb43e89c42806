#pragma once
/// A design-review session (ARCHITECTURE §1): one light set at a time on one bake, versions
/// computed once and encoded once, handed to every subscriber through a latest-wins slot.
///
/// Versions. Every accepted light set gets the next version number. The server's relight pool
/// (server/relight_pool.h) computes a session's versions one at a time, taking the sessions in
/// turns: while an update waits or computes, newer sets replace the pending one (coalescing),
/// so only the newest pending version is computed and the ones it replaced are never produced.
///
/// Frames. Each computed version is encoded once as the frame every subscriber holding the
/// previous version receives: a delta against it, or a key frame every keyframeInterval
/// versions. A subscriber that holds any other version (it joined late or skipped versions)
/// gets the version's key frame instead, encoded at most once per version on first demand.
/// So compute and encode cost per update do not grow with the number of subscribers.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/error.h"
#include "core/frame_codec.h"
#include "core/light_set.h"
#include "proto/pic.pb.h"
#include "render/runtime.h"
#include "server/limits.h"
#include "server/relight_pool.h"

namespace pic {

class ServedBake;

/// A state subscribers hold: a version's final state (part 0) or one of its earlier parts
/// (server/progressive.h).
struct StateId {
    uint64_t version = 0;  ///< 0: nothing
    uint32_t part = 0;
    bool operator==(const StateId&) const = default;
};

/// One computed version, or an earlier part of one: its caches as halves and its frames on
/// the wire.
class Update {
public:
    uint64_t version = 0;
    uint32_t part = 0;                      ///< 0: the version's final state
    StateId base;                           ///< what `broadcast` applies to; version 0: a key frame
    std::shared_ptr<const HalfFrame> frame;  ///< the caches, kept while anyone may need a key frame
    std::shared_ptr<const v1::Frame> broadcast;
    UpdateStats stats;
    double encodeMs = 0.0;
    int zstdLevel = kDefaultZstdLevel;     ///< for the key frame encoded on demand
    std::shared_ptr<std::atomic<uint64_t>> keysOnDemand;  ///< counts it, when set

    StateId id() const { return {version, part}; }
    /// The frame for a subscriber that holds `held` (version 0: nothing): `broadcast` when it
    /// applies to `held`, else this state's key frame.
    std::shared_ptr<const v1::Frame> frameFor(StateId held) const;
    /// Whether a key frame besides `broadcast` was encoded for this state.
    bool keyEncoded() const { return mKeyEncoded.load(); }

private:
    mutable std::atomic<bool> mKeyEncoded{false};
    mutable std::once_flag mKeyOnce;
    mutable std::shared_ptr<const v1::Frame> mKey;
};

/// A subscriber's mailbox: only the newest update not yet taken (latest wins), so a slow
/// subscriber costs one update of memory and never holds the others up.
class SubscriberSlot {
public:
    /// `wake` runs (outside the slot's lock) whenever an update is put; the slot starts with
    /// `initial` pending, without a wake.
    explicit SubscriberSlot(std::function<void()> wake,
                            std::shared_ptr<const Update> initial = nullptr)
        : mWake(std::move(wake)), mPending(std::move(initial)) {}

    void put(std::shared_ptr<const Update> update);
    /// The pending update, or null.
    std::shared_ptr<const Update> take();
    /// Updates replaced before they were taken.
    uint64_t skipped() const;
    /// Ends the subscription (its session is closing): wakes the subscriber, which sees
    /// closed() and ends its stream.
    void close();
    bool closed() const;

private:
    std::function<void()> mWake;
    mutable std::mutex mMutex;
    std::shared_ptr<const Update> mPending;
    uint64_t mSkipped = 0;
    bool mClosed = false;
};

/// One update's (or part's) line for the log: version, ms per pass, encode ms, bytes,
/// subscribers.
struct UpdateLog {
    std::string session;
    const Update* update = nullptr;
    size_t subscribers = 0;
};

struct SessionOptions {
    uint32_t keyframeInterval = 32;   ///< every N-th version is broadcast as a key frame
    int zstdLevel = kDefaultZstdLevel;
    std::function<void(const UpdateLog&)> log;  ///< called once per computed update
    /// Writes a second the session accepts, light sets and preset changes together (each one
    /// a database transaction; burst: as many); beyond, they are refused with the time until
    /// the next one would be accepted.
    double setLightsPerSecond = 30.0;
    /// Milliseconds an update may take before its caches are streamed in parts (0: never;
    /// server/progressive.h).
    double updateBudgetMs = 0.0;
};

/// Where a session starts: version 1 with the scene's own lights, or, for a session restored
/// from the server's database, the version after the one it had reached, with its last set
/// and its presets.
struct SessionStart {
    uint64_t version = 1;
    std::optional<LightSet> lights;
    LightPresets presets;
    /// Who created it, for quotas (an API key's id or a peer's host); empty for a session
    /// restored or taken over from the database, which counts against nobody.
    std::string creator;
};

class Session : private RelightPool::Job {
public:
    /// Queues the session's first version on `pool`, with the session's bake as its group.
    /// The tokens come as their digests (tokenDigest): the session never holds a token.
    Session(std::string id, std::string editorDigest, std::string viewerDigest, ServedBake& bake,
            RelightPool& pool, SessionOptions options, SessionStart start = SessionStart());
    /// Leaves the pool (an update in progress finishes first; a pending one is dropped).
    ~Session() override;
    Session(const Session&) = delete;
    Session& operator=(const Session&) = delete;

    const std::string& id() const { return mId; }
    /// tokenDigest of the editor's and the viewers' tokens.
    const std::string& editorDigest() const { return mEditorDigest; }
    const std::string& viewerDigest() const { return mViewerDigest; }
    ServedBake& bake() const { return mBake; }
    /// SessionStart::creator.
    const std::string& creator() const { return mCreator; }
    /// A write's turn (a light set or a preset change) under
    /// SessionOptions::setLightsPerSecond: zero when it may go on, else how long until one may.
    std::chrono::milliseconds takeWriteTurn() { return mWriteRate.take(); }

    /// What makes an accepted light set durable before the session queues it (the server's
    /// database): called with the version the set will produce; its error refuses the set.
    using Commit = std::function<Result<void>(uint64_t version, const LightSet& lights)>;

    /// Queues a light set, checked against the scene (InvalidInput naming the problem), and
    /// returns the version it will produce. With `commit`, the set is queued only once
    /// `commit` succeeded (its error is returned, and the session stays as it was); light
    /// sets of one session are committed one at a time, in version order. Io once the
    /// session is closed.
    Result<uint64_t> setLights(LightSet lights, const Commit& commit = {});

    /// What makes a change of the presets durable before the session keeps it (the server's
    /// database): called with the session's newest version and light set and the presets as
    /// they will be; its error refuses the change.
    using PresetsCommit = std::function<Result<void>(uint64_t version, const LightSet& lights,
                                                     const LightPresets& presets)>;
    /// What a change of the presets did: whether it was made, and the names after it.
    struct PresetsChange {
        bool done = false;
        std::vector<std::string> names;  ///< in name order
    };

    /// Creates or replaces preset `name` (checkPresetName's InvalidInput), a set checked
    /// against the scene as setLights checks (InvalidInput naming the problem); not done when
    /// `name` is new and the session holds kMaxPresets already. With `commit`, the change is
    /// kept only once `commit` succeeded (its error is returned); changes are committed one
    /// at a time, together with setLights' commits. Io once the session is closed.
    Result<PresetsChange> setPreset(const std::string& name, LightSet lights,
                                    const PresetsCommit& commit = {});
    /// Deletes preset `name`, committed as setPreset's changes; not done when there is none.
    Result<PresetsChange> removePreset(const std::string& name, const PresetsCommit& commit = {});
    /// The presets as they are now.
    LightPresets presets() const;

    /// Closes the session for good (it is removed from this server): its subscribers' slots
    /// close, the pending version is dropped and a computation not yet started is abandoned.
    /// Does not wait; the destructor waits for a computation in progress.
    void close();
    /// The newest accepted version and light set.
    uint64_t latestVersion() const;
    LightSet latestLights() const;
    /// Both, read together.
    std::pair<uint64_t, LightSet> latest() const;
    /// The newest update published (an earlier part of a budgeted version, or a version's
    /// final state), null before the first one.
    std::shared_ptr<const Update> latestUpdate() const;

    /// A new subscriber: its slot holds the newest computed update at once (if any; `wake`
    /// is not called for it, the caller takes it when ready), then every update published
    /// after, each with a call of `wake`.
    /// A closed session gives a closed slot.
    std::shared_ptr<SubscriberSlot> subscribe(std::function<void()> wake);
    void unsubscribe(const SubscriberSlot* slot);
    size_t subscribers() const;

    /// Records use of the session by a client (joins, light sets, subscriptions).
    void touch();
    /// How long since the last use, for removing idle sessions.
    std::chrono::steady_clock::duration idleFor() const;

    /// Counts a frame of `bytes` written to a subscriber.
    void countSent(uint64_t bytes);
    /// The session's counters (GetStats).
    v1::SessionStats stats() const;

    /// Blocks until the final state of version ≥ `version`, or any part of a newer one, is
    /// published or `timeout` passes.
    bool waitForVersion(uint64_t version, std::chrono::milliseconds timeout) const;

private:
    /// The pool's step: compute() relights the pending version (the bake's runtime is this
    /// session's meanwhile), finish() encodes and publishes it.
    void compute() override;
    void finish() override;
    /// Encodes and publishes an earlier part of the version compute() relights.
    void publishPart(HalfFrame state, int bounce, double elapsedMs);
    void publish(std::shared_ptr<const Update> update);
    /// Applies `change` to a copy of the presets, commits the result and keeps it; `change`
    /// returning false leaves them as they are (not done).
    Result<PresetsChange> changePresets(const std::function<bool(LightPresets&)>& change,
                                        const PresetsCommit& commit);

    std::string mId;
    std::string mEditorDigest;
    std::string mViewerDigest;
    ServedBake& mBake;
    RelightPool& mPool;
    SessionOptions mOptions;
    std::string mCreator;
    TokenBucket mWriteRate;

    std::mutex mPublishMutex;  ///< orders puts into slots: publishes and first updates
    std::mutex mCommitMutex;   ///< one light set or presets change committed at a time
    mutable std::mutex mMutex;
    mutable std::condition_variable mChanged;
    bool mStopping = false;
    uint64_t mNextVersion = 1;
    LightSet mLatestLights;
    LightPresets mPresets;
    /// The set waiting to be computed: its version, lights and when it was accepted.
    struct Pending {
        uint64_t version = 0;
        LightSet lights;
        std::chrono::system_clock::time_point accepted;
    };
    std::optional<Pending> mPending;
    std::shared_ptr<const Update> mLatest;
    std::vector<std::shared_ptr<SubscriberSlot>> mSlots;
    std::chrono::steady_clock::time_point mLastUse = std::chrono::steady_clock::now();
    v1::SessionStats mStats;           ///< counters except subscribers and live skips
    double mUpdateMsTotal = 0.0;
    double mEncodeMsTotal = 0.0;
    /// Key frames encoded on demand, counted by the updates themselves.
    std::shared_ptr<std::atomic<uint64_t>> mKeysOnDemand = std::make_shared<std::atomic<uint64_t>>(0);

    /// Between compute() and finish(), and from one step to the next: touched by the pool's
    /// step only.
    struct Step {
        std::optional<Pending> job;           ///< what compute() took; empty: nothing to do
        std::shared_ptr<Update> update;       ///< its update, once relit
        std::shared_ptr<HalfFrame> frame;
        double updateMs = 0.0;
        std::shared_ptr<const HalfFrame> previous;  ///< the last published version's caches
        uint64_t previousVersion = 0;
        LightSet previousLights;                    ///< and its light set
        uint32_t deltasSinceKey = 0;
        /// The last state published (the previous version's final state, or a part of this
        /// one): what the next frame is a delta against.
        std::shared_ptr<const HalfFrame> streamed;
        StateId streamedId;
        /// Budgeted sessions: the bounce caches of the previous relight (the estimates'
        /// baseline), those of this one, and how long the previous relight took.
        std::vector<CacheValues> previousBounces;
        std::vector<CacheValues> bounces;
        double relightMs = 0.0;
    } mStep;
};

}  // namespace pic
