#pragma once
/// `picclient load`: N subscribers in one process plus an editor that changes a light R times
/// a second, measuring per update the time from the editor's call to each subscriber holding
/// the decoded frame of that version or a newer one.

#include <cstdint>
#include <functional>
#include <string>

#include <nlohmann/json.hpp>

#include "client/connection.h"
#include "core/error.h"
#include "core/light_set.h"

namespace pic {

struct LoadOptions {
    uint32_t clients = 1;        ///< subscribers
    double durationSeconds = 10; ///< how long the editor changes lights
    double updateRate = 2;       ///< light changes per second (0: none, subscribers only)
    std::string session;         ///< empty: a new session
    std::string editorToken;     ///< with `session`
    float moveMetres = 0.25f;    ///< radius of the circle the moved point or spot light follows
    float turnDegrees = 5.0f;    ///< amplitude of a moved directional light's swing
    /// Called when every subscriber holds its first frame and the editor starts, and when
    /// every subscriber holds the last version (or the wait for it ended): the window a
    /// benchmark measures the server in.
    std::function<void()> onChangesStart;
    std::function<void()> onChangesEnd;
};

/// Runs the load test against the server behind `connection` and returns the report:
/// `latency_ms` {`p50`, `p95`, `p99`, `max`, `mean`} until a subscriber held each version's
/// final state, `first_change_ms` {`p50`, `p95`, `p99`} until it held any part of it (the
/// same, unless the server streams budgeted parts), `partial_frames`, `updates`,
/// `frames_received`, `errors`,
/// `subscribers_without_last` (those that never held the last version: lost final states),
/// `versions_skipped`, `bytes_per_frame` {`key`, `delta`}, `clients`, `duration_s`,
/// `update_rate`, `session` and the first error messages. The editor moves the first light of
/// the session's set; InvalidInput when the set has none and updates were asked for.
Result<nlohmann::ordered_json> runLoadTest(PicConnection& connection, const LoadOptions& options);

/// The light set the editor sends for its `step`-th change: the first light of `base` moved on
/// a circle (point, spot) or swung about the vertical (directional).
LightSet movedLightSet(const LightSet& base, uint64_t step, const LoadOptions& options);

}  // namespace pic
