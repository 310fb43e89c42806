#pragma once
/// Light sets (ARCHITECTURE.md §4): the lights and emissive scales a client sets, read from
/// and written to the JSON form
/// {"lights":[{"id","type","position","direction","color","intensity","innerConeAngle",
///  "outerConeAngle","range"}, {"id","type":"sky","color","intensity","environment",
///  "rotation"}], "emissiveScale":{"<material name>": s}, "indirectScale":{"y": s, "cocg": s}}.

#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.h"
#include "core/scene.h"

namespace pic {

/// Most lights one set may hold.
inline constexpr size_t kMaxLights = 256;
/// Longest light id, in bytes (UTF-8): ids name lights in logs, files and the session
/// database, not payloads.
inline constexpr size_t kMaxLightIdBytes = 128;
/// Largest intensity a light may have, and largest intensity × colour in any channel: W/sr
/// for point and spot lights, W/m² for directional ones (a million suns). Radiance beyond
/// the half-float range (65504 W/(m²·sr)) saturates in the streamed caches; below this bound
/// every pass's arithmetic stays finite.
inline constexpr float kMaxLightIntensity = 1e9f;
/// Largest emissive scale of a material.
inline constexpr float kMaxEmissiveScale = 1e6f;

/// Largest sky radiance, intensity × colour in any channel, W/(m²·sr) (about 40 suns' worth of
/// irradiance on a plane open to the whole sky).
inline constexpr float kMaxSkyRadiance = 1e6f;
/// Longest environment file name, in bytes.
inline constexpr size_t kMaxEnvironmentBytes = 256;

/// Largest artistic scale of the cache term's luma or chroma (IndirectScale).
inline constexpr float kMaxIndirectScale = 16.0f;

/// Artistic control of the cache term (paper 001 §4): factors on its luma Y, the indirect
/// light's "presence", and on its chroma Co and Cg, its colour bleeding. Clients apply them
/// where they reconstruct the cache term from the caches; the caches, and the light they
/// pass on to further bounces, stay physical. 1 and 1 leave the light as computed.
struct IndirectScale {
    float y = 1.0f;
    float cocg = 1.0f;
    friend bool operator==(const IndirectScale&, const IndirectScale&) = default;
};

/// The sky (ARCHITECTURE.md §4): radiance L(ω) = intensity·colour·environment(R⁻¹ω) from
/// every direction no geometry blocks, R the rotation about +Y. core/sky.h evaluates it.
struct SkyLight {
    std::string id = "sky";
    glm::vec3 color{1.0f};
    float intensity = 1.0f;        ///< W/(m²·sr) with a colour of 1 and no environment
    /// Equirectangular .hdr or .exr (+Y up, core/sky.h skyDirection), a path relative to the
    /// scene file's folder without ".." (picserver reads only what ships with its scenes);
    /// empty: a constant sky.
    std::string environment;
    float rotationDegrees = 0.0f;  ///< about +Y, counter-clockwise seen from above
    friend bool operator==(const SkyLight&, const SkyLight&) = default;
};

/// Whether `id` may name a light: 1 to kMaxLightIdBytes bytes without control characters.
bool isLightId(std::string_view id);

/// The dynamic lighting of a scene: punctual lights plus a scale per emissive material.
struct LightSet {
    std::vector<Light> lights;
    std::optional<SkyLight> sky;                 ///< at most one; JSON lists it among the lights
    std::map<std::string, float> emissiveScale;  ///< material name → factor on its emission (default 1)
    IndirectScale indirectScale;                 ///< on the cache term where clients shade

    /// Emission scale of a material (1 when not listed).
    float emissiveScaleOf(const std::string& material) const;
};

/// The scene's own lights (KHR_lights_punctual), no emissive scaling.
LightSet defaultLightSet(const Scene& scene);

/// Parses and validates a light set from JSON text. Errors (InvalidInput) name the field
/// and value: unknown type, NaN/Inf anywhere, negative intensity or colour, an intensity or
/// intensity × colour above kMaxLightIntensity, zero-length direction for spot/directional
/// lights, cone angles outside 0 ≤ inner ≤ outer ≤ π/2 with outer > 0, negative range, more
/// than kMaxLights lights, duplicate ids, ids that isLightId refuses, unknown keys, negative,
/// non-finite or larger than kMaxEmissiveScale emissive scales, a second sky, a sky radiance
/// above kMaxSkyRadiance, an environment that is absolute, climbs with "..", is not .hdr or
/// .exr or is longer than kMaxEnvironmentBytes, indirect scales outside
/// [0, kMaxIndirectScale] or with other keys than y and cocg. Text from the input is clipped
/// in messages. Directions are normalised.
Result<LightSet> parseLightSet(const std::string& json);

/// Reads a light set from a JSON file (NotFound if missing).
Result<LightSet> readLightSet(const std::string& path);

/// Serialises a light set to the same JSON form (round-trips through parseLightSet).
std::string toJson(const LightSet& lights);

/// Most presets (named light sets) one session holds.
inline constexpr size_t kMaxPresets = 32;
/// Longest preset name, in bytes.
inline constexpr size_t kMaxPresetNameBytes = 64;

/// InvalidInput naming `name` unless it may name a preset: 1 to kMaxPresetNameBytes
/// characters of [A-Za-z0-9 _.-], neither the first nor the last a space.
Result<void> checkPresetName(std::string_view name);

/// Presets: light sets by name (checkPresetName), at most kMaxPresets of them.
using LightPresets = std::map<std::string, LightSet>;

/// Presets as one JSON object, name → the light set's JSON form (round-trips through
/// parseLightPresets).
std::string toJson(const LightPresets& presets);
/// Presets from that JSON; InvalidInput for text that is not a JSON object, more than
/// kMaxPresets entries, a name checkPresetName refuses, or a light set parseLightSet refuses
/// (naming the preset and the problem).
Result<LightPresets> parseLightPresets(const std::string& json);

/// Checks a light set against a scene: every emissiveScale key names a material of the scene.
Result<void> checkLightSet(const LightSet& lights, const Scene& scene);

/// The scene's own lights when `path` is empty, else the light set read from `path` and
/// checked against the scene (what every tool's `--lights FILE` means).
Result<LightSet> loadLightSet(const std::string& path, const Scene& scene);

/// Irradiance (W/m², RGB) that light `light` delivers at `position` on a surface with unit
/// normal `normal`, ignoring occlusion: I·cosθ/d² for point and spot lights (with the
/// KHR_lights_punctual spot falloff and range window), E·cosθ for directional lights.
/// Also returns the unit direction towards the light and the distance to it (infinity for
/// directional lights) for a shadow ray.
glm::vec3 lightIrradiance(const Light& light, const glm::vec3& position, const glm::vec3& normal,
                          glm::vec3& toLight, float& distance);

}  // namespace pic
