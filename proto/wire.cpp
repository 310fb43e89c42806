#include "proto/wire.h"

#include <cmath>
#include <string_view>
#include <utility>

#include <nlohmann/json.hpp>

namespace pic::wire {

namespace {

using Json = nlohmann::ordered_json;

v1::Vec3 vec3(const glm::vec3& v) {
    v1::Vec3 out;
    out.set_x(v.x);
    out.set_y(v.y);
    out.set_z(v.z);
    return out;
}

/// Wire floats are IEEE: NaN and infinities arrive as such and JSON cannot carry them, so
/// they are refused here, naming the field, before the set goes through parseLightSet.
Result<void> checkFinite(float value, std::string_view field) {
    if (!std::isfinite(value))
        return fail(ErrorCode::InvalidInput, "{} must be finite, got {}", field, value);
    return {};
}

Result<Json> vec3Json(const v1::Vec3& v, const std::string& field) {
    PIC_TRY(checkFinite(v.x(), field + "[0]"));
    PIC_TRY(checkFinite(v.y(), field + "[1]"));
    PIC_TRY(checkFinite(v.z(), field + "[2]"));
    return Json::array({v.x(), v.y(), v.z()});
}

Result<Json> lightJson(const v1::Light& light, size_t index) {
    const std::string path = fmt::format("lights[{}]", index);
    Json object;
    if (!light.id().empty()) object["id"] = light.id();
    switch (light.type()) {
    case v1::Light::POINT: object["type"] = "point"; break;
    case v1::Light::SPOT: object["type"] = "spot"; break;
    case v1::Light::DIRECTIONAL: object["type"] = "directional"; break;
    case v1::Light::SKY: object["type"] = "sky"; break;
    default:
        return fail(ErrorCode::InvalidInput,
                    "{}.type must be POINT, SPOT, DIRECTIONAL or SKY, got {}", path,
                    int(light.type()));
    }
    if (light.has_position()) {
        PIC_TRY_ASSIGN(object["position"], vec3Json(light.position(), path + ".position"));
    }
    if (light.has_direction()) {
        PIC_TRY_ASSIGN(object["direction"], vec3Json(light.direction(), path + ".direction"));
    }
    if (light.has_color()) {
        PIC_TRY_ASSIGN(object["color"], vec3Json(light.color(), path + ".color"));
    }
    const std::pair<bool, std::pair<float, const char*>> numbers[] = {
        {light.has_intensity(), {light.intensity(), "intensity"}},
        {light.has_inner_cone_angle(), {light.inner_cone_angle(), "innerConeAngle"}},
        {light.has_outer_cone_angle(), {light.outer_cone_angle(), "outerConeAngle"}},
        {light.has_range(), {light.range(), "range"}},
        {light.has_rotation(), {light.rotation(), "rotation"}},
    };
    for (const auto& [present, field] : numbers) {
        if (!present) continue;
        PIC_TRY(checkFinite(field.first, path + "." + field.second));
        object[field.second] = field.first;
    }
    // An empty string is proto3's absent value: a constant sky.
    if (!light.environment().empty()) object["environment"] = light.environment();
    return object;
}

}  // namespace

v1::LightSet toProto(const LightSet& lights) {
    v1::LightSet out;
    for (const Light& light : lights.lights) {
        v1::Light& wire = *out.add_lights();
        wire.set_id(light.id);
        wire.set_intensity(light.intensity);
        *wire.mutable_color() = vec3(light.color);
        switch (light.type) {
        case LightType::Point: wire.set_type(v1::Light::POINT); break;
        case LightType::Spot: wire.set_type(v1::Light::SPOT); break;
        case LightType::Directional: wire.set_type(v1::Light::DIRECTIONAL); break;
        }
        if (light.type != LightType::Directional) {
            *wire.mutable_position() = vec3(light.position);
            if (std::isfinite(light.range)) wire.set_range(light.range);
        }
        if (light.type != LightType::Point) *wire.mutable_direction() = vec3(light.direction);
        if (light.type == LightType::Spot) {
            wire.set_inner_cone_angle(light.innerConeAngle);
            wire.set_outer_cone_angle(light.outerConeAngle);
        }
    }
    if (lights.sky) {
        v1::Light& wire = *out.add_lights();
        wire.set_id(lights.sky->id);
        wire.set_type(v1::Light::SKY);
        wire.set_intensity(lights.sky->intensity);
        *wire.mutable_color() = vec3(lights.sky->color);
        wire.set_environment(lights.sky->environment);
        if (lights.sky->rotationDegrees != 0.0f) wire.set_rotation(lights.sky->rotationDegrees);
    }
    for (const auto& [material, scale] : lights.emissiveScale)
        (*out.mutable_emissive_scale())[material] = scale;
    if (lights.indirectScale != IndirectScale{}) {
        out.mutable_indirect_scale()->set_y(lights.indirectScale.y);
        out.mutable_indirect_scale()->set_cocg(lights.indirectScale.cocg);
    }
    return out;
}

Result<LightSet> fromProto(const v1::LightSet& lights) {
    if (size_t(lights.lights_size()) > kMaxLights)
        return fail(ErrorCode::InvalidInput, "lights holds {} lights, at most {} are allowed",
                    lights.lights_size(), kMaxLights);
    Json root;
    root["lights"] = Json::array();
    for (int i = 0; i < lights.lights_size(); ++i) {
        PIC_TRY_ASSIGN(Json light, lightJson(lights.lights(i), size_t(i)));
        root["lights"].push_back(std::move(light));
    }
    Json scales = Json::object();
    for (const auto& [material, scale] : lights.emissive_scale()) {
        PIC_TRY(checkFinite(scale, fmt::format("emissiveScale[\"{}\"]", material)));
        scales[material] = scale;
    }
    root["emissiveScale"] = std::move(scales);
    if (lights.has_indirect_scale()) {
        const v1::IndirectScale& wire = lights.indirect_scale();
        Json scale = Json::object();
        if (wire.has_y()) {
            PIC_TRY(checkFinite(wire.y(), "indirectScale.y"));
            scale["y"] = wire.y();
        }
        if (wire.has_cocg()) {
            PIC_TRY(checkFinite(wire.cocg(), "indirectScale.cocg"));
            scale["cocg"] = wire.cocg();
        }
        root["indirectScale"] = std::move(scale);
    }
    return parseLightSet(root.dump());
}

void toProto(const EncodedFrame& encoded, v1::Frame& frame) {
    frame.clear_planes();
    for (int t = 0; t < kFramePlanes; ++t) {
        const EncodedPlane& plane = encoded.planes[size_t(t)];
        v1::Plane& wire = *frame.add_planes();
        wire.set_channel(v1::Channel(t));
        wire.set_encoding(plane.encoding == PlaneEncoding::Key ? v1::KEY : v1::DELTA);
        wire.set_values(plane.values);
        wire.set_data(plane.bytes.data(), plane.bytes.size());
    }
}

Result<EncodedFrame> planesFromProto(v1::Frame& frame) {
    if (frame.planes_size() != kFramePlanes)
        return fail(ErrorCode::Corrupt, "frame of version {} has {} planes, expected {}",
                    frame.version(), frame.planes_size(), kFramePlanes);
    EncodedFrame encoded;
    for (int t = 0; t < kFramePlanes; ++t) {
        v1::Plane& wire = *frame.mutable_planes(t);
        if (wire.channel() != v1::Channel(t))
            return fail(ErrorCode::Corrupt,
                        "frame of version {}: plane {} is channel {}, expected {}", frame.version(),
                        t, int(wire.channel()), framePlaneName(t));
        EncodedPlane& plane = encoded.planes[size_t(t)];
        if (wire.encoding() == v1::KEY)
            plane.encoding = PlaneEncoding::Key;
        else if (wire.encoding() == v1::DELTA)
            plane.encoding = PlaneEncoding::Delta;
        else
            return fail(ErrorCode::Corrupt, "frame of version {}: plane {} has encoding {}",
                        frame.version(), framePlaneName(t), int(wire.encoding()));
        plane.values = wire.values();
        const std::string& data = wire.data();
        plane.bytes.assign(data.begin(), data.end());
    }
    return encoded;
}

grpc::Status toStatus(const Error& error) {
    grpc::StatusCode code = grpc::StatusCode::INTERNAL;
    switch (error.code) {
    case ErrorCode::InvalidInput: code = grpc::StatusCode::INVALID_ARGUMENT; break;
    case ErrorCode::NotFound: code = grpc::StatusCode::NOT_FOUND; break;
    case ErrorCode::Corrupt: code = grpc::StatusCode::DATA_LOSS; break;
    case ErrorCode::Unsupported: code = grpc::StatusCode::UNIMPLEMENTED; break;
    case ErrorCode::Io:
    case ErrorCode::Internal: code = grpc::StatusCode::INTERNAL; break;
    }
    return grpc::Status(code, error.message);
}

const char* statusName(grpc::StatusCode code) {
    switch (code) {
    case grpc::StatusCode::OK: return "OK";
    case grpc::StatusCode::CANCELLED: return "CANCELLED";
    case grpc::StatusCode::UNKNOWN: return "UNKNOWN";
    case grpc::StatusCode::INVALID_ARGUMENT: return "INVALID_ARGUMENT";
    case grpc::StatusCode::DEADLINE_EXCEEDED: return "DEADLINE_EXCEEDED";
    case grpc::StatusCode::NOT_FOUND: return "NOT_FOUND";
    case grpc::StatusCode::ALREADY_EXISTS: return "ALREADY_EXISTS";
    case grpc::StatusCode::PERMISSION_DENIED: return "PERMISSION_DENIED";
    case grpc::StatusCode::UNAUTHENTICATED: return "UNAUTHENTICATED";
    case grpc::StatusCode::RESOURCE_EXHAUSTED: return "RESOURCE_EXHAUSTED";
    case grpc::StatusCode::FAILED_PRECONDITION: return "FAILED_PRECONDITION";
    case grpc::StatusCode::ABORTED: return "ABORTED";
    case grpc::StatusCode::OUT_OF_RANGE: return "OUT_OF_RANGE";
    case grpc::StatusCode::UNIMPLEMENTED: return "UNIMPLEMENTED";
    case grpc::StatusCode::INTERNAL: return "INTERNAL";
    case grpc::StatusCode::UNAVAILABLE: return "UNAVAILABLE";
    case grpc::StatusCode::DATA_LOSS: return "DATA_LOSS";
    default: return "UNKNOWN";
    }
}

bool isSessionId(const std::string& id) {
    return id.size() == 16 && id.find_first_not_of("0123456789abcdef") == std::string::npos;
}

Error fromStatus(const grpc::Status& status, const std::string& call) {
    ErrorCode code = ErrorCode::Internal;
    switch (status.error_code()) {
    case grpc::StatusCode::INVALID_ARGUMENT:
    case grpc::StatusCode::PERMISSION_DENIED:
    case grpc::StatusCode::UNAUTHENTICATED: code = ErrorCode::InvalidInput; break;
    case grpc::StatusCode::NOT_FOUND: code = ErrorCode::NotFound; break;
    case grpc::StatusCode::DATA_LOSS: code = ErrorCode::Corrupt; break;
    case grpc::StatusCode::UNIMPLEMENTED: code = ErrorCode::Unsupported; break;
    case grpc::StatusCode::UNAVAILABLE: code = ErrorCode::Io; break;
    default: code = ErrorCode::Internal; break;
    }
    return Error{code, fmt::format("{}: {} {}", call, statusName(status.error_code()),
                                   status.error_message())};
}

}  // namespace pic::wire
