#include "server/service_state.h"

#include <optional>

namespace pic {

namespace {

/// What became of a change's commit to the database: the session moved to another server (a
/// newer version is stored), or the database failed.
struct StoreCommit {
    bool moved = false;
    std::optional<grpc::Status> storeStatus;

    /// Takes the result `saved` of a save of `session`; its error refuses the change.
    Result<void> take(PicServer::State& state, const Session& session, const Result<bool>& saved) {
        if (!saved) {
            storeStatus = state.storeFailed(saved.error());
            return std::unexpected(saved.error());
        }
        if (!*saved) {
            moved = true;
            return fail(ErrorCode::Io, "session {} moved to another server", session.id());
        }
        return {};
    }

    /// The status of a change its commit refused, `notApplied` saying what the client should
    /// know (the session is evicted when it moved); none when the commit did not refuse it.
    std::optional<grpc::Status> refusal(PicServer::State& state,
                                        const std::shared_ptr<Session>& session,
                                        std::string_view notApplied) const {
        if (moved) {
            state.evict(session);
            return grpc::Status(
                grpc::StatusCode::UNAVAILABLE,
                fmt::format("session {} moved to another server; {}", session->id(), notApplied));
        }
        return storeStatus;
    }
};

/// The status of a session's refusal: UNAVAILABLE for Io (the session closed meanwhile), else
/// the error's own.
grpc::Status sessionStatus(const Error& error) {
    return error.code == ErrorCode::Io ? grpc::Status(grpc::StatusCode::UNAVAILABLE, error.message)
                                       : wire::toStatus(error);
}

/// Takes `session`'s turn for a write (Session::takeWriteTurn): false when it may go on, else
/// true with `outcome` (a SetLightsOutcome or PresetsOutcome) refused with the wait.
template <typename Outcome>
bool overWriteRate(const PicServer::State& state, Session& session, Outcome& outcome) {
    const auto wait = session.takeWriteTurn();
    if (wait.count() <= 0) return false;
    outcome.retryAfter = wait;
    outcome.status = grpc::Status(
        grpc::StatusCode::RESOURCE_EXHAUSTED,
        fmt::format("session {} takes at most {:g} light sets a second (preset changes count "
                    "as light sets); retry in {} ms",
                    session.id(), state.options.session.setLightsPerSecond, wait.count()));
    return true;
}

}  // namespace

SetLightsOutcome setLights(PicServer::State& state, const Access& access,
                           const std::function<Result<LightSet>()>& parse) {
    PIC_CHECK(access.status.ok());
    SetLightsOutcome outcome;
    if (access.role != v1::EDITOR) {
        outcome.status = grpc::Status(grpc::StatusCode::PERMISSION_DENIED,
                                      "only an editor token may set lights");
        return outcome;
    }
    const std::shared_ptr<Session>& session = access.session;
    if (overWriteRate(state, *session, outcome)) return outcome;
    auto lights = parse();
    if (!lights) {
        outcome.status = wire::toStatus(lights.error());
        return outcome;
    }
    // Durable before the reply: the set is committed to the database, then queued.
    StoreCommit stored;
    Session::Commit commit;
    if (state.store)
        commit = [&](uint64_t version, const LightSet& set) -> Result<void> {
            return stored.take(state, *session, state.timedStore("save", [&](SessionStore& db) {
                return db.save(PicServer::State::row(*session, version, set, session->presets()));
            }));
        };
    auto version = session->setLights(std::move(*lights), commit);
    if (auto refused =
            stored.refusal(state, session, "the light set was not applied, send it again")) {
        outcome.status = *refused;
        return outcome;
    }
    if (!version) {
        outcome.status = sessionStatus(version.error());
        return outcome;
    }
    outcome.version = *version;
    return outcome;
}

namespace {

const grpc::Status kPresetsEditorsOnly(grpc::StatusCode::PERMISSION_DENIED,
                                       "only an editor token may change presets");

/// A change of `access`'s presets by `change` (Session::setPreset or removePreset, given the
/// commit), committed to the database when the server has one; `notDone` is the status when
/// the session did not make it, `notApplied` what a client hears when the session moved.
PresetsOutcome changePresets(
    PicServer::State& state, const Access& access,
    const std::function<Result<Session::PresetsChange>(const Session::PresetsCommit&)>& change,
    const std::function<grpc::Status()>& notDone, std::string_view notApplied) {
    PresetsOutcome outcome;
    const std::shared_ptr<Session>& session = access.session;
    if (overWriteRate(state, *session, outcome)) return outcome;
    // Durable before the reply, as a light set.
    StoreCommit stored;
    Session::PresetsCommit commit;
    if (state.store)
        commit = [&](uint64_t version, const LightSet& lights, const LightPresets& presets) {
            return stored.take(state, *session, state.timedStore("save", [&](SessionStore& db) {
                return db.savePresets(PicServer::State::row(*session, version, lights, presets));
            }));
        };
    auto changed = change(commit);
    if (auto refused = stored.refusal(state, session, notApplied)) {
        outcome.status = *refused;
        return outcome;
    }
    if (!changed) {
        outcome.status = sessionStatus(changed.error());
        return outcome;
    }
    if (!changed->done) {
        outcome.status = notDone();
        return outcome;
    }
    outcome.names = std::move(changed->names);
    return outcome;
}

}  // namespace

PresetsOutcome setPreset(PicServer::State& state, const Access& access, const std::string& name,
                         const std::function<Result<LightSet>()>& parse) {
    PIC_CHECK(access.status.ok());
    if (access.role != v1::EDITOR) return {kPresetsEditorsOnly, {}};
    auto lights = parse();
    if (!lights) return {wire::toStatus(lights.error()), {}};
    return changePresets(
        state, access,
        [&](const Session::PresetsCommit& commit) {
            return access.session->setPreset(name, std::move(*lights), commit);
        },
        [&] {
            return grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED,
                                fmt::format("session {} holds {} presets, the most a session may; "
                                            "delete one first",
                                            access.session->id(), kMaxPresets));
        },
        "the preset was not saved, send it again");
}

PresetsOutcome removePreset(PicServer::State& state, const Access& access,
                            const std::string& name) {
    PIC_CHECK(access.status.ok());
    if (access.role != v1::EDITOR) return {kPresetsEditorsOnly, {}};
    return changePresets(
        state, access,
        [&](const Session::PresetsCommit& commit) {
            return access.session->removePreset(name, commit);
        },
        [&] {
            return grpc::Status(grpc::StatusCode::NOT_FOUND,
                                fmt::format("session {} has no preset \"{}\"", access.session->id(),
                                            clipped(name)));
        },
        "the preset was not deleted, send it again");
}

}  // namespace pic
