#include "core/light_set.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <iterator>
#include <limits>
#include <set>
#include <string_view>
#include <system_error>

#include <glm/gtc/constants.hpp>
#include <nlohmann/json.hpp>

namespace pic {

namespace {

// Input keeps the order it was written in, so errors about unknown keys name the first one.
using Json = nlohmann::ordered_json;
// Output prints numbers as float, the type Light holds: each prints in its shortest form
// ("0.1", not "0.10000000149011612") and still parses back to the same float.
using FloatJson = nlohmann::basic_json<nlohmann::ordered_map, std::vector, std::string, bool,
                                       std::int64_t, std::uint64_t, float>;

const char* typeName(LightType type) {
    switch (type) {
    case LightType::Point:
        return "point";
    case LightType::Spot:
        return "spot";
    case LightType::Directional:
        return "directional";
    }
    return "point";
}

/// The float a JSON number holds, or NaN when it is not a finite float (1e39 is a finite
/// double but Inf as a float).
float finiteFloat(const Json& number) {
    double value = number.get<double>();
    if (!std::isfinite(value) || std::abs(value) > double(std::numeric_limits<float>::max()))
        return std::numeric_limits<float>::quiet_NaN();
    return float(value);
}

/// Short form of a JSON value for messages, cut so a huge value cannot flood the terminal.
std::string shown(const Json& value) {
    std::string text = value.dump();
    constexpr size_t kMaxShown = 60;
    if (text.size() > kMaxShown) text = text.substr(0, kMaxShown) + "...";
    return text;
}

/// Reads the fields of one JSON object, naming each by its path ("lights[2].intensity") in
/// errors, and reports keys that were never asked for.
class FieldReader {
public:
    FieldReader(const Json& object, std::string path) : mObject(object), mPath(std::move(path)) {}

    const std::string& path() const { return mPath; }
    std::string fieldPath(std::string_view key) const { return fmt::format("{}.{}", mPath, key); }

    /// The value under key, or null when absent; marks the key as known.
    const Json* find(std::string_view key) {
        mKnown.insert(std::string(key));
        auto it = mObject.find(key);
        return it == mObject.end() ? nullptr : &*it;
    }

    Result<float> number(std::string_view key, float fallback) {
        const Json* value = find(key);
        if (!value) return fallback;
        if (!value->is_number())
            return fail(ErrorCode::InvalidInput, "{} must be a number, got {}", fieldPath(key),
                        shown(*value));
        float number = finiteFloat(*value);
        if (!std::isfinite(number))
            return fail(ErrorCode::InvalidInput, "{} must be finite, got {}", fieldPath(key),
                        shown(*value));
        return number;
    }

    Result<glm::vec3> vec3(std::string_view key, const glm::vec3& fallback) {
        const Json* value = find(key);
        if (!value) return fallback;
        if (!value->is_array() || value->size() != 3)
            return fail(ErrorCode::InvalidInput, "{} must be an array of 3 numbers, got {}",
                        fieldPath(key), shown(*value));
        glm::vec3 v;
        for (int i = 0; i < 3; ++i) {
            const Json& element = (*value)[size_t(i)];
            if (!element.is_number())
                return fail(ErrorCode::InvalidInput, "{}[{}] must be a number, got {}",
                            fieldPath(key), i, shown(element));
            v[i] = finiteFloat(element);
            if (!std::isfinite(v[i]))
                return fail(ErrorCode::InvalidInput, "{}[{}] must be finite, got {}",
                            fieldPath(key), i, shown(element));
        }
        return v;
    }

    /// Fails on the first key that no find() asked for: a misspelt field must not silently
    /// fall back to its default.
    Result<void> rejectUnknown() const {
        for (auto it = mObject.begin(); it != mObject.end(); ++it)
            if (!mKnown.contains(it.key()))
                return fail(ErrorCode::InvalidInput, "{} has unknown key \"{}\"", mPath, clipped(it.key()));
        return {};
    }

private:
    const Json& mObject;
    std::string mPath;
    std::set<std::string, std::less<>> mKnown;
};

/// Fields that only some light types use; naming one on another type is almost certainly a
/// mistake in the type (a "point" light with cone angles was meant to be a spot).
Result<void> rejectInapplicable(FieldReader& fields, LightType type,
                                std::initializer_list<std::string_view> keys) {
    for (std::string_view key : keys)
        if (fields.find(key))
            return fail(ErrorCode::InvalidInput, "{} does not apply to a {} light",
                        fields.fieldPath(key), typeName(type));
    return {};
}

/// Whether `name` is an environment file a light set may name: relative, below the scene's
/// folder, an HDR or EXR image.
Result<void> checkEnvironmentName(const std::string& name, const std::string& field) {
    if (name.empty() || name.size() > kMaxEnvironmentBytes)
        return fail(ErrorCode::InvalidInput, "{} must be 1 to {} bytes long, got {}", field,
                    kMaxEnvironmentBytes, name.size());
    if (std::ranges::any_of(name, [](char c) { return static_cast<unsigned char>(c) < 0x20 || c == 0x7F || c == '\\'; }))
        return fail(ErrorCode::InvalidInput, "{} \"{}\" holds a control character or a backslash",
                    field, clipped(name));
    const std::filesystem::path path(name);
    if (path.is_absolute() || name.front() == '/')
        return fail(ErrorCode::InvalidInput,
                    "{} \"{}\" must be relative to the scene's folder, not absolute", field,
                    clipped(name));
    for (const auto& part : path)
        if (part == "..")
            return fail(ErrorCode::InvalidInput,
                        "{} \"{}\" must stay inside the scene's folder (no \"..\")", field,
                        clipped(name));
    std::string extension = path.extension().string();
    std::ranges::transform(extension, extension.begin(),
                           [](char c) { return char(std::tolower(static_cast<unsigned char>(c))); });
    if (extension != ".hdr" && extension != ".exr")
        return fail(ErrorCode::InvalidInput, "{} \"{}\" must be a .hdr or .exr image", field,
                    clipped(name));
    return {};
}

/// A light of type "sky" (the caller has read its id and type).
Result<SkyLight> parseSky(FieldReader& fields, std::string id) {
    SkyLight sky;
    sky.id = std::move(id);
    PIC_TRY_ASSIGN(sky.color, fields.vec3("color", sky.color));
    if (glm::any(glm::lessThan(sky.color, glm::vec3(0.0f))))
        return fail(ErrorCode::InvalidInput, "{} must be non-negative, got [{}, {}, {}]",
                    fields.fieldPath("color"), sky.color.x, sky.color.y, sky.color.z);
    PIC_TRY_ASSIGN(sky.intensity, fields.number("intensity", sky.intensity));
    if (sky.intensity < 0.0f)
        return fail(ErrorCode::InvalidInput, "{} must be finite and ≥ 0, got {}",
                    fields.fieldPath("intensity"), sky.intensity);
    const float peak = sky.intensity * std::max({sky.color.x, sky.color.y, sky.color.z});
    if (sky.intensity > kMaxSkyRadiance || peak > kMaxSkyRadiance)
        return fail(ErrorCode::InvalidInput,
                    "{} × color is {:g} in its largest channel (intensity {:g}); a sky's radiance "
                    "is at most {:g} W/(m²·sr)",
                    fields.fieldPath("intensity"), peak, sky.intensity, kMaxSkyRadiance);
    if (const Json* environment = fields.find("environment")) {
        if (!environment->is_string())
            return fail(ErrorCode::InvalidInput, "{} must be a string, got {}",
                        fields.fieldPath("environment"), shown(*environment));
        sky.environment = environment->get<std::string>();
        PIC_TRY(checkEnvironmentName(sky.environment, fields.fieldPath("environment")));
    }
    PIC_TRY_ASSIGN(sky.rotationDegrees, fields.number("rotation", sky.rotationDegrees));
    if (!(std::abs(sky.rotationDegrees) <= 1e6f))
        return fail(ErrorCode::InvalidInput, "{} must be in [-1e6, 1e6] degrees, got {}",
                    fields.fieldPath("rotation"), sky.rotationDegrees);
    for (std::string_view key : {"position", "direction", "innerConeAngle", "outerConeAngle", "range"})
        if (fields.find(key))
            return fail(ErrorCode::InvalidInput, "{} does not apply to a sky light",
                        fields.fieldPath(key));
    PIC_TRY(fields.rejectUnknown());
    return sky;
}

/// One entry of "lights": a punctual light, or the sky.
struct ParsedLight {
    std::optional<Light> light;
    std::optional<SkyLight> sky;
};

Result<ParsedLight> parseLight(const Json& value, size_t index) {
    std::string path = fmt::format("lights[{}]", index);
    if (!value.is_object())
        return fail(ErrorCode::InvalidInput, "{} must be an object, got {}", path, shown(value));
    FieldReader fields(value, path);
    Light light;

    if (const Json* id = fields.find("id")) {
        if (!id->is_string() || id->get<std::string>().empty())
            return fail(ErrorCode::InvalidInput, "{} must be a non-empty string, got {}",
                        fields.fieldPath("id"), shown(*id));
        light.id = id->get<std::string>();
        if (light.id.size() > kMaxLightIdBytes)
            return fail(ErrorCode::InvalidInput, "{} is {} bytes long; at most {} are allowed",
                        fields.fieldPath("id"), light.id.size(), kMaxLightIdBytes);
        if (!isLightId(light.id))
            return fail(ErrorCode::InvalidInput, "{} {} holds a control character",
                        fields.fieldPath("id"), shown(*id));
    } else {
        light.id = fmt::format("light_{}", index);
    }

    const Json* type = fields.find("type");
    if (!type)
        return fail(ErrorCode::InvalidInput,
                    "{} is missing; it must be \"point\", \"spot\", \"directional\" or \"sky\"",
                    fields.fieldPath("type"));
    if (*type == "sky") {
        PIC_TRY_ASSIGN(SkyLight sky, parseSky(fields, std::move(light.id)));
        return ParsedLight{std::nullopt, std::move(sky)};
    }
    if (*type == "point")
        light.type = LightType::Point;
    else if (*type == "spot")
        light.type = LightType::Spot;
    else if (*type == "directional")
        light.type = LightType::Directional;
    else
        return fail(ErrorCode::InvalidInput,
                    "{} must be \"point\", \"spot\", \"directional\" or \"sky\", got {}",
                    fields.fieldPath("type"), shown(*type));

    // Defaults are those of KHR_lights_punctual, which Light's initialisers already hold.
    PIC_TRY_ASSIGN(light.color, fields.vec3("color", light.color));
    if (glm::any(glm::lessThan(light.color, glm::vec3(0.0f))))
        return fail(ErrorCode::InvalidInput, "{} must be non-negative, got [{}, {}, {}]",
                    fields.fieldPath("color"), light.color.x, light.color.y, light.color.z);

    PIC_TRY_ASSIGN(light.intensity, fields.number("intensity", light.intensity));
    if (light.intensity < 0.0f)
        return fail(ErrorCode::InvalidInput, "{} must be finite and ≥ 0, got {}",
                    fields.fieldPath("intensity"), light.intensity);
    const float peak = light.intensity * std::max({light.color.x, light.color.y, light.color.z});
    if (light.intensity > kMaxLightIntensity || peak > kMaxLightIntensity)
        return fail(ErrorCode::InvalidInput,
                    "{} × color is {:g} in its largest channel (intensity {:g}); at most {:g} (W/sr "
                    "for point and spot lights, W/m² for directional ones)",
                    fields.fieldPath("intensity"), peak, light.intensity, kMaxLightIntensity);

    if (light.type != LightType::Directional) {
        PIC_TRY_ASSIGN(light.position, fields.vec3("position", light.position));
        PIC_TRY_ASSIGN(light.range, fields.number("range", light.range));
        if (!(light.range > 0.0f))
            return fail(ErrorCode::InvalidInput, "{} must be > 0 (absent for no cut-off), got {}",
                        fields.fieldPath("range"), light.range);
    } else {
        if (auto rejected = rejectInapplicable(fields, light.type, {"position", "range"});
            !rejected)
            return std::unexpected(rejected.error());
    }

    if (light.type != LightType::Point) {
        PIC_TRY_ASSIGN(glm::vec3 direction, fields.vec3("direction", light.direction));
        float length = glm::length(direction);
        if (!(length > 0.0f) || !std::isfinite(length))
            return fail(ErrorCode::InvalidInput, "{} must have a non-zero length, got [{}, {}, {}]",
                        fields.fieldPath("direction"), direction.x, direction.y, direction.z);
        // Normalised once: a direction already of unit length (one parseLightSet wrote) keeps
        // its bits, so that a set written by toJson reads back the same (the session database
        // stores sets as JSON; renormalising moved their last bits at each restore).
        light.direction = std::abs(length - 1.0f) > 1e-6f ? direction / length : direction;
    } else {
        if (auto rejected = rejectInapplicable(fields, light.type, {"direction"}); !rejected)
            return std::unexpected(rejected.error());
    }

    if (light.type == LightType::Spot) {
        PIC_TRY_ASSIGN(light.innerConeAngle, fields.number("innerConeAngle", light.innerConeAngle));
        PIC_TRY_ASSIGN(light.outerConeAngle, fields.number("outerConeAngle", light.outerConeAngle));
        float inner = light.innerConeAngle;
        float outer = light.outerConeAngle;
        if (!(outer > 0.0f && outer <= glm::half_pi<float>()))
            return fail(ErrorCode::InvalidInput, "{} must be in (0, π/2], got {}",
                        fields.fieldPath("outerConeAngle"), outer);
        if (!(inner >= 0.0f && inner <= outer))
            return fail(ErrorCode::InvalidInput, "{} must be in [0, outerConeAngle = {}], got {}",
                        fields.fieldPath("innerConeAngle"), outer, inner);
    } else {
        if (auto rejected =
                rejectInapplicable(fields, light.type, {"innerConeAngle", "outerConeAngle"});
            !rejected)
            return std::unexpected(rejected.error());
    }

    if (auto known = fields.rejectUnknown(); !known) return std::unexpected(known.error());
    return ParsedLight{std::move(light), std::nullopt};
}

Result<std::map<std::string, float>> parseEmissiveScale(const Json& value) {
    if (!value.is_object())
        return fail(ErrorCode::InvalidInput, "emissiveScale must be an object, got {}",
                    shown(value));
    std::map<std::string, float> scales;
    for (auto it = value.begin(); it != value.end(); ++it) {
        const Json& scale = it.value();
        float value = scale.is_number() ? finiteFloat(scale) : -1.0f;
        if (!(value >= 0.0f && value <= kMaxEmissiveScale))
            return fail(ErrorCode::InvalidInput,
                        "emissiveScale[\"{}\"] must be a finite number in [0, {:g}], got {}",
                        clipped(it.key()), kMaxEmissiveScale, shown(scale));
        scales[it.key()] = value;
    }
    return scales;
}

Result<IndirectScale> parseIndirectScale(const Json& value) {
    if (!value.is_object())
        return fail(ErrorCode::InvalidInput, "indirectScale must be an object, got {}",
                    shown(value));
    FieldReader fields(value, "indirectScale");
    IndirectScale scale;
    PIC_TRY_ASSIGN(scale.y, fields.number("y", 1.0f));
    PIC_TRY_ASSIGN(scale.cocg, fields.number("cocg", 1.0f));
    for (const auto& [key, factor] : {std::pair{"y", scale.y}, std::pair{"cocg", scale.cocg}})
        if (!(factor >= 0.0f && factor <= kMaxIndirectScale))
            return fail(ErrorCode::InvalidInput, "indirectScale.{} must be in [0, {:g}], got {:g}",
                        key, kMaxIndirectScale, factor);
    PIC_TRY(fields.rejectUnknown());
    return scale;
}

FloatJson vec3Json(const glm::vec3& v) {
    return FloatJson::array({v.x, v.y, v.z});
}

}  // namespace

float LightSet::emissiveScaleOf(const std::string& material) const {
    auto it = emissiveScale.find(material);
    return it == emissiveScale.end() ? 1.0f : it->second;
}

LightSet defaultLightSet(const Scene& scene) {
    LightSet set;
    set.lights = scene.lights;
    return set;
}

bool isLightId(std::string_view id) {
    return !id.empty() && id.size() <= kMaxLightIdBytes &&
           std::ranges::none_of(id, [](char c) { return static_cast<unsigned char>(c) < 0x20 || c == 0x7F; });
}

Result<void> checkPresetName(std::string_view name) {
    const bool allowed =
        !name.empty() && name.size() <= kMaxPresetNameBytes && name.front() != ' ' &&
        name.back() != ' ' && std::ranges::all_of(name, [](char c) {
            return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') ||
                   c == ' ' || c == '_' || c == '.' || c == '-';
        });
    if (!allowed)
        return fail(ErrorCode::InvalidInput,
                    "preset name \"{}\" is not 1 to {} characters of A-Z a-z 0-9 space _ . - "
                    "without a space first or last",
                    clipped(name), kMaxPresetNameBytes);
    return {};
}

Result<LightSet> parseLightSet(const std::string& json) {
    // nlohmann reports syntax errors and number overflow only as exceptions; none leaves here.
    Json root;
    try {
        root = Json::parse(json);
    } catch (const Json::exception& error) {
        return fail(ErrorCode::InvalidInput, "light set is not valid JSON: {}", error.what());
    }
    if (!root.is_object())
        return fail(ErrorCode::InvalidInput, "light set must be a JSON object, got {}",
                    shown(root));

    FieldReader fields(root, "light set");
    LightSet set;
    if (const Json* lights = fields.find("lights")) {
        if (!lights->is_array())
            return fail(ErrorCode::InvalidInput, "lights must be an array, got {}", shown(*lights));
        if (lights->size() > kMaxLights)
            return fail(ErrorCode::InvalidInput, "lights holds {} lights, at most {} are allowed",
                        lights->size(), kMaxLights);
        std::set<std::string> ids;
        for (size_t i = 0; i < lights->size(); ++i) {
            PIC_TRY_ASSIGN(ParsedLight parsed, parseLight((*lights)[i], i));
            const std::string& id = parsed.light ? parsed.light->id : parsed.sky->id;
            // Sessions address lights by id, so two lights must never share one.
            if (!ids.insert(id).second)
                return fail(ErrorCode::InvalidInput, "lights[{}].id \"{}\" is used twice", i,
                            clipped(id));
            if (parsed.sky && set.sky)
                return fail(ErrorCode::InvalidInput,
                            "lights[{}] is a second sky (\"{}\" is one already); a light set "
                            "holds at most one",
                            i, clipped(set.sky->id));
            if (parsed.sky)
                set.sky = std::move(parsed.sky);
            else
                set.lights.push_back(std::move(*parsed.light));
        }
    }
    if (const Json* scales = fields.find("emissiveScale")) {
        PIC_TRY_ASSIGN(set.emissiveScale, parseEmissiveScale(*scales));
    }
    if (const Json* scale = fields.find("indirectScale")) {
        PIC_TRY_ASSIGN(set.indirectScale, parseIndirectScale(*scale));
    }
    if (auto known = fields.rejectUnknown(); !known) return std::unexpected(known.error());
    return set;
}

Result<LightSet> readLightSet(const std::string& path) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec))
        return fail(ErrorCode::NotFound, "light set file {} does not exist", path);
    std::ifstream file(path, std::ios::binary);
    if (!file) return fail(ErrorCode::Io, "cannot open light set file {}", path);
    std::string text{std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
    if (file.bad()) return fail(ErrorCode::Io, "cannot read light set file {}", path);
    auto set = parseLightSet(text);
    if (!set) return fail(set.error().code, "{}: {}", path, set.error().message);
    return set;
}

namespace {

/// A light set's JSON form.
FloatJson lightSetJson(const LightSet& set) {
    FloatJson lights = FloatJson::array();
    for (const Light& light : set.lights) {
        // Only the fields the type uses, so the output parses back under the same rules.
        FloatJson object;
        object["id"] = light.id;
        object["type"] = typeName(light.type);
        if (light.type != LightType::Directional) object["position"] = vec3Json(light.position);
        if (light.type != LightType::Point) object["direction"] = vec3Json(light.direction);
        object["color"] = vec3Json(light.color);
        object["intensity"] = light.intensity;
        if (light.type == LightType::Spot) {
            object["innerConeAngle"] = light.innerConeAngle;
            object["outerConeAngle"] = light.outerConeAngle;
        }
        // JSON cannot hold infinity: an absent range means no cut-off.
        if (light.type != LightType::Directional && std::isfinite(light.range))
            object["range"] = light.range;
        lights.push_back(std::move(object));
    }
    if (set.sky) {
        FloatJson object;
        object["id"] = set.sky->id;
        object["type"] = "sky";
        object["color"] = vec3Json(set.sky->color);
        object["intensity"] = set.sky->intensity;
        if (!set.sky->environment.empty()) object["environment"] = set.sky->environment;
        if (set.sky->rotationDegrees != 0.0f) object["rotation"] = set.sky->rotationDegrees;
        lights.push_back(std::move(object));
    }
    FloatJson root;
    root["lights"] = std::move(lights);
    FloatJson scales = FloatJson::object();
    for (const auto& [material, scale] : set.emissiveScale) scales[material] = scale;
    root["emissiveScale"] = std::move(scales);
    if (set.indirectScale != IndirectScale{})
        root["indirectScale"] = {{"y", set.indirectScale.y}, {"cocg", set.indirectScale.cocg}};
    return root;
}

}  // namespace

std::string toJson(const LightSet& set) {
    return lightSetJson(set).dump(2);
}

std::string toJson(const LightPresets& presets) {
    FloatJson root = FloatJson::object();
    for (const auto& [name, lights] : presets) root[name] = lightSetJson(lights);
    return root.dump();
}

Result<LightPresets> parseLightPresets(const std::string& json) {
    // nlohmann reports syntax errors only as exceptions; none leaves here.
    Json root;
    try {
        root = Json::parse(json);
    } catch (const Json::exception& error) {
        return fail(ErrorCode::InvalidInput, "presets are not valid JSON: {}", error.what());
    }
    if (!root.is_object())
        return fail(ErrorCode::InvalidInput, "presets must be a JSON object, got {}", shown(root));
    if (root.size() > kMaxPresets)
        return fail(ErrorCode::InvalidInput, "{} presets, more than the {} allowed", root.size(),
                    kMaxPresets);
    LightPresets presets;
    for (const auto& [name, value] : root.items()) {
        PIC_TRY(checkPresetName(name));
        auto lights = parseLightSet(value.dump());
        if (!lights)
            return fail(ErrorCode::InvalidInput, "preset \"{}\": {}", name, lights.error().message);
        presets.emplace(name, std::move(*lights));
    }
    return presets;
}

Result<void> checkLightSet(const LightSet& set, const Scene& scene) {
    std::set<std::string, std::less<>> materials;
    for (const Material& material : scene.materials) materials.insert(material.name);
    for (const auto& [material, scale] : set.emissiveScale) {
        if (!materials.contains(material)) {
            std::string known;
            for (const std::string& name : materials)
                known += fmt::format("{}\"{}\"", known.empty() ? "" : ", ", name);
            return fail(ErrorCode::InvalidInput,
                        "emissiveScale names material \"{}\", which the scene does not have "
                        "(materials: {})",
                        clipped(material), known.empty() ? "none" : known);
        }
    }
    return {};
}

glm::vec3 lightIrradiance(const Light& light, const glm::vec3& position, const glm::vec3& normal,
                          glm::vec3& toLight, float& distance) {
    if (light.type == LightType::Directional) {
        toLight = -light.direction;
        distance = std::numeric_limits<float>::infinity();
        return light.intensity * light.color * std::max(0.0f, glm::dot(normal, toLight));
    }

    glm::vec3 offset = light.position - position;
    distance = glm::length(offset);
    // A point on the light itself receives no defined irradiance; report none rather than Inf.
    if (!(distance > 0.0f)) {
        toLight = normal;
        distance = 0.0f;
        return glm::vec3(0.0f);
    }
    toLight = offset / distance;
    float cosTheta = glm::dot(normal, toLight);
    if (cosTheta <= 0.0f) return glm::vec3(0.0f);

    float attenuation = 1.0f / (distance * distance);
    if (std::isfinite(light.range)) {
        // KHR_lights_punctual's recommended window: smooth, and exactly zero from `range` on.
        float ratio = distance / light.range;
        float ratio2 = ratio * ratio;
        attenuation *= std::clamp(1.0f - ratio2 * ratio2, 0.0f, 1.0f);
    }
    if (light.type == LightType::Spot) {
        float cd = glm::dot(light.direction, -toLight);
        float cosOuter = std::cos(light.outerConeAngle);
        float cosInner = std::cos(light.innerConeAngle);
        if (light.innerConeAngle >= light.outerConeAngle) {
            // Equal angles mean a hard-edged cone; the smooth ramp below would divide by zero.
            attenuation *= cd >= cosOuter ? 1.0f : 0.0f;
        } else {
            // The extension's smooth falloff, linear in cos between the cones, then squared.
            float scale = 1.0f / std::max(0.001f, cosInner - cosOuter);
            float ramp = std::clamp(cd * scale - cosOuter * scale, 0.0f, 1.0f);
            attenuation *= ramp * ramp;
        }
    }
    return light.intensity * light.color * (cosTheta * attenuation);
}

Result<LightSet> loadLightSet(const std::string& path, const Scene& scene) {
    if (path.empty()) return defaultLightSet(scene);
    PIC_TRY_ASSIGN(LightSet lights, readLightSet(path));
    if (auto checked = checkLightSet(lights, scene); !checked)
        return std::unexpected(checked.error());
    return lights;
}

}  // namespace pic
