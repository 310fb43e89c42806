#pragma once
/// Conversions between the wire messages of proto/pic.proto and pic's own types, shared by
/// the server and the client so that both sides read the wire the same way.

#include <string>

#include <grpcpp/support/status.h>

#include "core/error.h"
#include "core/frame_codec.h"
#include "core/light_set.h"
#include "proto/pic.pb.h"

namespace pic::wire {

/// The request metadata that carries a call's session id, for load balancers that route by
/// session (proto/pic.proto, "Routing").
inline constexpr const char* kSessionMetadata = "pic-session";

/// The request metadata that carries an operator API key, as "Bearer KEY" (proto/pic.proto,
/// "Authentication").
inline constexpr const char* kAuthorizationMetadata = "authorization";

/// The trailing metadata of a RESOURCE_EXHAUSTED reply that says, in milliseconds, when the
/// same call would be accepted.
inline constexpr const char* kRetryAfterMetadata = "retry-after-ms";

/// The largest message a client sends (a light set of kMaxLights lights is under 100 KiB) and
/// the largest a server sends (a key frame of the largest bakes, a scene chunk of 1 MiB); both
/// sides enforce them, so that no peer can make the other buffer an arbitrary amount.
inline constexpr size_t kMaxRequestBytes = size_t(1) << 20;
inline constexpr size_t kMaxReplyBytes = size_t(256) << 20;

/// Whether `id` is a session id as servers draw them: 16 lowercase hex digits.
bool isSessionId(const std::string& id);

/// A light set as the wire carries it: only the fields each light type uses, no range for
/// "no cut-off".
v1::LightSet toProto(const LightSet& lights);

/// Reads and validates a wire light set under the rules of parseLightSet (core/light_set.h),
/// naming the offending field ("lights[2].intensity") and value: InvalidInput.
Result<LightSet> fromProto(const v1::LightSet& lights);

/// The planes of an encoded frame into `frame` (other fields untouched).
void toProto(const EncodedFrame& encoded, v1::Frame& frame);

/// The planes of a wire frame: Corrupt when there are not three, in channel order, with known
/// encodings. The bytes are moved out of `frame`.
Result<EncodedFrame> planesFromProto(v1::Frame& frame);

/// The name of a status code as gRPC spells it: "OK", "UNAUTHENTICATED", ...
const char* statusName(grpc::StatusCode code);

/// The gRPC status for an Error: InvalidInput → INVALID_ARGUMENT, NotFound → NOT_FOUND, ...
grpc::Status toStatus(const Error& error);

/// The Error for a failed call: the status code's name and its message, prefixed by `call`.
Error fromStatus(const grpc::Status& status, const std::string& call);

}  // namespace pic::wire
