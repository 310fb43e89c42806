#include "server/session.h"

#include <algorithm>
#include <cstdio>

#include "proto/wire.h"
#include "server/progressive.h"
#include "server/served_bake.h"

namespace pic {

namespace {

using Clock = std::chrono::steady_clock;

double millisecondsSince(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

std::vector<std::string> namesOf(const LightPresets& presets) {
    std::vector<std::string> names;
    for (const auto& [name, lights] : presets) names.push_back(name);
    return names;
}

}  // namespace

std::shared_ptr<const v1::Frame> Update::frameFor(StateId held) const {
    if (base.version == 0 || held == base) return broadcast;
    std::call_once(mKeyOnce, [this] {
        const auto start = Clock::now();
        auto encoded = encodeFrame(*frame, nullptr, zstdLevel);
        if (!encoded) {
            std::fprintf(stderr, "picserver: key frame of version %llu part %u failed: %s\n",
                         (unsigned long long)version, part, encoded.error().message.c_str());
            return;
        }
        auto key = std::make_shared<v1::Frame>(*broadcast);
        key->set_base_version(0);
        key->set_base_part(0);
        wire::toProto(*encoded, *key);
        key->set_encode_ms(millisecondsSince(start));
        mKey = std::move(key);
        mKeyEncoded = true;
        if (keysOnDemand) keysOnDemand->fetch_add(1);
    });
    return mKey;
}

void SubscriberSlot::put(std::shared_ptr<const Update> update) {
    {
        std::lock_guard lock(mMutex);
        if (mPending) ++mSkipped;
        mPending = std::move(update);
    }
    if (mWake) mWake();
}

std::shared_ptr<const Update> SubscriberSlot::take() {
    std::lock_guard lock(mMutex);
    return std::exchange(mPending, nullptr);
}

uint64_t SubscriberSlot::skipped() const {
    std::lock_guard lock(mMutex);
    return mSkipped;
}

void SubscriberSlot::close() {
    {
        std::lock_guard lock(mMutex);
        mClosed = true;
    }
    if (mWake) mWake();
}

bool SubscriberSlot::closed() const {
    std::lock_guard lock(mMutex);
    return mClosed;
}

Session::Session(std::string id, std::string editorDigest, std::string viewerDigest,
                 ServedBake& bake, RelightPool& pool, SessionOptions options, SessionStart start)
    : mId(std::move(id)),
      mEditorDigest(std::move(editorDigest)),
      mViewerDigest(std::move(viewerDigest)),
      mBake(bake),
      mPool(pool),
      mOptions(std::move(options)),
      mCreator(std::move(start.creator)),
      mWriteRate(mOptions.setLightsPerSecond, mOptions.setLightsPerSecond) {
    mLatestLights = start.lights ? std::move(*start.lights) : defaultLightSet(bake.scene());
    mPresets = std::move(start.presets);
    mNextVersion = std::max<uint64_t>(start.version, 1);
    mStats.set_versions_set(mNextVersion);
    mPending = Pending{mNextVersion++, mLatestLights, std::chrono::system_clock::now()};
    mPool.ready(*this, &mBake);
}

Session::~Session() {
    {
        std::lock_guard lock(mMutex);
        mStopping = true;
        mPending.reset();
    }
    mChanged.notify_all();
    mPool.forget(*this);
}

Result<uint64_t> Session::setLights(LightSet lights, const Commit& commit) {
    PIC_TRY(mBake.checkLights(lights));
    // Versions are handed out only here, under the commit lock: the one read now is the one
    // taken below.
    std::lock_guard committing(mCommitMutex);
    uint64_t version = 0;
    {
        std::lock_guard lock(mMutex);
        if (mStopping) return fail(ErrorCode::Io, "session {} was closed", mId);
        version = mNextVersion;
    }
    if (commit) PIC_TRY(commit(version, lights));
    {
        std::lock_guard lock(mMutex);
        if (mStopping) return fail(ErrorCode::Io, "session {} was closed", mId);
        mNextVersion = version + 1;
        mStats.set_versions_set(version);
        mLastUse = std::chrono::steady_clock::now();
        mLatestLights = lights;
        // Coalescing: a set still waiting is replaced, and its version is never produced.
        mPending = Pending{version, std::move(lights), std::chrono::system_clock::now()};
    }
    mChanged.notify_all();
    mPool.ready(*this, &mBake);
    return version;
}

Result<Session::PresetsChange> Session::setPreset(const std::string& name, LightSet lights,
                                                  const PresetsCommit& commit) {
    PIC_TRY(checkPresetName(name));
    PIC_TRY(mBake.checkLights(lights));
    return changePresets(
        [&](LightPresets& presets) {
            if (!presets.contains(name) && presets.size() >= kMaxPresets) return false;
            presets[name] = std::move(lights);
            return true;
        },
        commit);
}

Result<Session::PresetsChange> Session::removePreset(const std::string& name,
                                                     const PresetsCommit& commit) {
    return changePresets([&](LightPresets& presets) { return presets.erase(name) > 0; }, commit);
}

Result<Session::PresetsChange> Session::changePresets(
    const std::function<bool(LightPresets&)>& change, const PresetsCommit& commit) {
    // Under the commit lock: the version, light set and presets read now stay as they are
    // until the change is kept.
    std::lock_guard committing(mCommitMutex);
    uint64_t version = 0;
    LightSet latestLights;
    LightPresets presets;
    {
        std::lock_guard lock(mMutex);
        if (mStopping) return fail(ErrorCode::Io, "session {} was closed", mId);
        version = mNextVersion - 1;
        latestLights = mLatestLights;
        presets = mPresets;
    }
    if (!change(presets)) return PresetsChange{false, namesOf(presets)};
    if (commit) PIC_TRY(commit(version, latestLights, presets));
    std::lock_guard lock(mMutex);
    if (mStopping) return fail(ErrorCode::Io, "session {} was closed", mId);
    mPresets = std::move(presets);
    mLastUse = std::chrono::steady_clock::now();
    return PresetsChange{true, namesOf(mPresets)};
}

LightPresets Session::presets() const {
    std::lock_guard lock(mMutex);
    return mPresets;
}

void Session::close() {
    std::vector<std::shared_ptr<SubscriberSlot>> slots;
    {
        std::lock_guard lock(mMutex);
        mStopping = true;
        mPending.reset();
        slots = mSlots;
    }
    mChanged.notify_all();
    for (const auto& slot : slots) slot->close();
}

void Session::touch() {
    std::lock_guard lock(mMutex);
    mLastUse = std::chrono::steady_clock::now();
}

std::chrono::steady_clock::duration Session::idleFor() const {
    std::lock_guard lock(mMutex);
    return std::chrono::steady_clock::now() - mLastUse;
}

uint64_t Session::latestVersion() const {
    std::lock_guard lock(mMutex);
    return mNextVersion - 1;
}

LightSet Session::latestLights() const {
    std::lock_guard lock(mMutex);
    return mLatestLights;
}

std::pair<uint64_t, LightSet> Session::latest() const {
    std::lock_guard lock(mMutex);
    return {mNextVersion - 1, mLatestLights};
}

std::shared_ptr<const Update> Session::latestUpdate() const {
    std::lock_guard lock(mMutex);
    return mLatest;
}

std::shared_ptr<SubscriberSlot> Session::subscribe(std::function<void()> wake) {
    // Under the publish lock, so that no newer update reaches the slot before the latest.
    std::shared_ptr<SubscriberSlot> slot;
    bool closed = false;
    {
        std::lock_guard publishing(mPublishMutex);
        std::lock_guard lock(mMutex);
        slot = std::make_shared<SubscriberSlot>(std::move(wake), mLatest);
        closed = mStopping;
        if (!closed) mSlots.push_back(slot);
    }
    // A session closed already gives a closed slot (its wake runs outside the locks).
    if (closed) slot->close();
    return slot;
}

void Session::unsubscribe(const SubscriberSlot* slot) {
    std::lock_guard lock(mMutex);
    std::erase_if(mSlots, [slot](const auto& held) { return held.get() == slot; });
    // Its skips stay counted after it leaves.
    mStats.set_versions_skipped(mStats.versions_skipped() + slot->skipped());
    mLastUse = std::chrono::steady_clock::now();
}

size_t Session::subscribers() const {
    std::lock_guard lock(mMutex);
    return mSlots.size();
}

bool Session::waitForVersion(uint64_t version, std::chrono::milliseconds timeout) const {
    std::unique_lock lock(mMutex);
    return mChanged.wait_for(lock, timeout, [&] {
        return mLatest && (mLatest->version > version ||
                           (mLatest->version == version && mLatest->part == 0));
    });
}

void Session::countSent(uint64_t bytes) {
    std::lock_guard lock(mMutex);
    mStats.set_frames_sent(mStats.frames_sent() + 1);
    mStats.set_bytes_sent(mStats.bytes_sent() + bytes);
}

v1::SessionStats Session::stats() const {
    std::lock_guard lock(mMutex);
    v1::SessionStats stats = mStats;
    stats.set_key_frames_on_demand(mKeysOnDemand->load());
    stats.set_subscribers(uint32_t(mSlots.size()));
    for (const auto& slot : mSlots) stats.set_versions_skipped(stats.versions_skipped() + slot->skipped());
    const double computed = double(std::max<uint64_t>(1, stats.versions_computed()));
    stats.set_mean_update_ms(mUpdateMsTotal / computed);
    stats.set_mean_encode_ms(mEncodeMsTotal / computed);
    return stats;
}

void Session::publish(std::shared_ptr<const Update> update) {
    std::lock_guard publishing(mPublishMutex);
    std::vector<std::shared_ptr<SubscriberSlot>> slots;
    {
        std::lock_guard lock(mMutex);
        mLatest = update;
        slots = mSlots;
        uint64_t bytes = 0;
        for (const v1::Plane& plane : update->broadcast->planes()) bytes += plane.data().size();
        mStats.set_broadcast_bytes(mStats.broadcast_bytes() + bytes);
        mStats.set_last_frame_bytes(bytes);
        if (update->part != 0) {
            mStats.set_partial_frames(mStats.partial_frames() + 1);
        } else {
            mStats.set_versions_computed(mStats.versions_computed() + 1);
            if (update->base.version == 0)
                mStats.set_key_frames(mStats.key_frames() + 1);
            else
                mStats.set_delta_frames(mStats.delta_frames() + 1);
            mUpdateMsTotal += update->broadcast->update_ms();
            mEncodeMsTotal += update->encodeMs;
        }
    }
    mChanged.notify_all();
    for (const auto& slot : slots) slot->put(update);
    if (mOptions.log) mOptions.log(UpdateLog{mId, update.get(), slots.size()});
}

void Session::compute() {
    mStep.job.reset();
    {
        std::lock_guard lock(mMutex);
        if (mStopping || !mPending) return;
        mStep.job = std::move(*mPending);
        mPending.reset();
    }
    const Pending& job = *mStep.job;
    mStep.update = std::make_shared<Update>();
    mStep.update->version = job.version;
    mStep.update->zstdLevel = mOptions.zstdLevel;
    mStep.update->keysOnDemand = mKeysOnDemand;
    mStep.frame = std::make_shared<HalfFrame>();
    const auto start = Clock::now();
    // A set that changes only what clients apply (the indirect scales) has the caches of the
    // last version: they are reused, and no pass runs.
    if (mStep.previous && job.lights.lights == mStep.previousLights.lights &&
        job.lights.sky == mStep.previousLights.sky &&
        job.lights.emissiveScale == mStep.previousLights.emissiveScale) {
        *mStep.frame = *mStep.previous;
        mStep.updateMs = millisecondsSince(start);
        return;
    }
    // Budgeted: the bounces are kept (the next update's baseline), and when this update is
    // expected to take longer than the budget, its parts are published as they are due.
    BounceObserver observer;
    std::optional<ProgressiveUpdate> parts;
    double partsMs = 0.0;  // spent encoding and publishing parts
    mStep.bounces.clear();
    if (mOptions.updateBudgetMs > 0.0) {
        if (mStep.streamedId == StateId{mStep.previousVersion, 0})
            parts.emplace(mOptions.updateBudgetMs, mStep.relightMs, mStep.previous.get(),
                          mStep.previousBounces);
        observer = [&](int bounce, const CacheValues& caches, bool last) {
            mStep.bounces.push_back(caches);
            mStep.bounces.back().irradiance = {};
            if (!parts) return;
            auto state = parts->afterBounce(bounce, caches, millisecondsSince(start), last);
            if (!state) return;
            const auto partStart = Clock::now();
            publishPart(std::move(*state), bounce, millisecondsSince(start));
            partsMs += millisecondsSince(partStart);
        };
    }
    if (auto relit = mBake.relight(job.lights, mStep.update->stats, *mStep.frame, observer); !relit) {
        std::fprintf(stderr, "picserver: session %s: version %llu failed: %s\n", mId.c_str(),
                     (unsigned long long)job.version, relit.error().message.c_str());
        mStep.job.reset();
        mStep.bounces.clear();
        return;
    }
    mStep.updateMs = millisecondsSince(start);
    mStep.relightMs = mStep.updateMs - partsMs;
    if (mOptions.updateBudgetMs > 0.0) std::swap(mStep.previousBounces, mStep.bounces);
}

void Session::publishPart(HalfFrame state, int bounce, double elapsedMs) {
    const Pending& job = *mStep.job;
    const auto start = Clock::now();
    auto frame = std::make_shared<const HalfFrame>(std::move(state));
    auto encoded = encodeFrame(*frame, mStep.streamed.get(), mOptions.zstdLevel);
    if (!encoded) {
        std::fprintf(stderr, "picserver: session %s: encoding a part of version %llu failed: %s\n",
                     mId.c_str(), (unsigned long long)job.version, encoded.error().message.c_str());
        return;
    }
    auto update = std::make_shared<Update>();
    update->version = job.version;
    update->part = mStep.streamedId.version == job.version ? mStep.streamedId.part + 1 : 1;
    update->base = mStep.streamedId;
    update->zstdLevel = mOptions.zstdLevel;
    update->keysOnDemand = mKeysOnDemand;
    update->stats.bounces = bounce;
    auto wireFrame = std::make_shared<v1::Frame>();
    wireFrame->set_version(update->version);
    wireFrame->set_part(update->part);
    wireFrame->set_bake_id(mBake.id());
    wireFrame->set_base_version(update->base.version);
    wireFrame->set_base_part(update->base.part);
    wire::toProto(*encoded, *wireFrame);
    update->encodeMs = millisecondsSince(start);
    wireFrame->set_bounces(uint32_t(bounce));
    wireFrame->set_update_ms(elapsedMs);
    wireFrame->set_encode_ms(update->encodeMs);
    wireFrame->set_lights_set_unix_ns(
        std::chrono::duration_cast<std::chrono::nanoseconds>(job.accepted.time_since_epoch()).count());
    // The new direct light shows with the first part; the indirect follows the parts.
    *wireFrame->mutable_lights() = wire::toProto(job.lights);
    update->frame = frame;
    update->broadcast = std::move(wireFrame);
    mStep.streamed = std::move(frame);
    mStep.streamedId = update->id();
    publish(std::move(update));
}

void Session::finish() {
    if (!mStep.job) return;
    const Pending job = *std::exchange(mStep.job, std::nullopt);
    auto update = std::move(mStep.update);
    auto frame = std::move(mStep.frame);

    const bool key = !mStep.previous || mStep.deltasSinceKey + 1 >= mOptions.keyframeInterval;
    const auto encodeStart = Clock::now();
    auto encoded = encodeFrame(*frame, key ? nullptr : mStep.streamed.get(), mOptions.zstdLevel);
    if (!encoded) {
        std::fprintf(stderr, "picserver: session %s: encoding version %llu failed: %s\n",
                     mId.c_str(), (unsigned long long)job.version, encoded.error().message.c_str());
        return;
    }
    auto wireFrame = std::make_shared<v1::Frame>();
    wireFrame->set_version(update->version);
    wireFrame->set_bake_id(mBake.id());
    const StateId base = key ? StateId{} : mStep.streamedId;
    wireFrame->set_base_version(base.version);
    wireFrame->set_base_part(base.part);
    wire::toProto(*encoded, *wireFrame);
    update->encodeMs = millisecondsSince(encodeStart);
    wireFrame->set_bounces(uint32_t(update->stats.bounces));
    for (const auto& [pass, ms] : update->stats.passMs) (*wireFrame->mutable_pass_ms())[pass] = ms;
    wireFrame->set_update_ms(mStep.updateMs);
    wireFrame->set_encode_ms(update->encodeMs);
    wireFrame->set_lights_set_unix_ns(
        std::chrono::duration_cast<std::chrono::nanoseconds>(job.accepted.time_since_epoch()).count());
    *wireFrame->mutable_lights() = wire::toProto(job.lights);

    update->base = base;
    update->frame = frame;
    update->broadcast = std::move(wireFrame);
    mStep.streamed = frame;
    mStep.streamedId = update->id();
    mStep.previous = std::move(frame);
    mStep.previousVersion = update->version;
    mStep.previousLights = job.lights;
    mStep.deltasSinceKey = key ? 0 : mStep.deltasSinceKey + 1;
    publish(std::move(update));
}

}  // namespace pic
