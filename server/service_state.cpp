#include "server/service_state.h"

#include <optional>

namespace pic {

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
    if (const auto wait = session->takeSetLightsTurn(); wait.count() > 0) {
        outcome.retryAfter = wait;
        outcome.status = grpc::Status(
            grpc::StatusCode::RESOURCE_EXHAUSTED,
            fmt::format("session {} takes at most {:g} light sets a second; retry in {} ms",
                        session->id(), state.options.session.setLightsPerSecond, wait.count()));
        return outcome;
    }
    auto lights = parse();
    if (!lights) {
        outcome.status = wire::toStatus(lights.error());
        return outcome;
    }
    // Durable before the reply: the set is committed to the database, then queued.
    bool moved = false;
    std::optional<grpc::Status> storeStatus;
    Session::Commit commit;
    if (state.store)
        commit = [&](uint64_t version, const LightSet& set) -> Result<void> {
            auto saved = state.timedStore("save", [&](SessionStore& db) {
                return db.save(PicServer::State::row(*session, version, set));
            });
            if (!saved) {
                storeStatus = state.storeFailed(saved.error());
                return std::unexpected(saved.error());
            }
            if (!*saved) {
                moved = true;
                return fail(ErrorCode::Io, "session {} moved to another server", session->id());
            }
            return {};
        };
    auto version = session->setLights(std::move(*lights), commit);
    if (moved) {
        state.evict(session);
        outcome.status = grpc::Status(grpc::StatusCode::UNAVAILABLE,
                                      fmt::format("session {} moved to another server; the light "
                                                  "set was not applied, send it again",
                                                  session->id()));
        return outcome;
    }
    if (storeStatus) {
        outcome.status = *storeStatus;
        return outcome;
    }
    if (!version) {
        // Io: the session closed while the set was being set.
        outcome.status = version.error().code == ErrorCode::Io
                             ? grpc::Status(grpc::StatusCode::UNAVAILABLE, version.error().message)
                             : wire::toStatus(version.error());
        return outcome;
    }
    outcome.version = *version;
    return outcome;
}

}  // namespace pic
