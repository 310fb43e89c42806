#include "tests/scenes/gltf_builder.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <span>
#include <utility>

#include <unistd.h>

#include <glm/gtc/quaternion.hpp>
#include <nlohmann/json.hpp>

namespace pic::testscenes {

namespace {

using Json = nlohmann::ordered_json;

// glTF enumerations (glTF 2.0 §5).
constexpr int kComponentFloat = 5126;
constexpr int kComponentUnsignedInt = 5125;
constexpr int kTargetArrayBuffer = 34962;
constexpr int kTargetElementArrayBuffer = 34963;
constexpr int kFilterNearest = 9728;
constexpr int kWrapRepeat = 10497;
constexpr double kCameraZNear = 0.01;  // metres

/// A vector as a JSON array of three numbers.
Json toJson(const glm::dvec3& v) {
    return Json::array({v.x, v.y, v.z});
}

/// Standard base64 (RFC 4648) with padding, for data URIs.
std::string base64(std::span<const uint8_t> bytes) {
    static constexpr char kAlphabet[] =
        "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    out.reserve((bytes.size() + 2) / 3 * 4);
    for (size_t i = 0; i < bytes.size(); i += 3) {
        const size_t n = std::min<size_t>(3, bytes.size() - i);
        uint32_t group = uint32_t(bytes[i]) << 16;
        if (n > 1) group |= uint32_t(bytes[i + 1]) << 8;
        if (n > 2) group |= uint32_t(bytes[i + 2]);
        for (size_t k = 0; k < 4; ++k)
            out += k <= n ? kAlphabet[(group >> (18 - 6 * k)) & 63u] : '=';
    }
    return out;
}

/// Unit quaternion [x, y, z, w] turning the node's −Z into `forward` and its +Y towards `up`.
Json rotationLookingAlong(glm::dvec3 forward, glm::dvec3 up) {
    forward = glm::normalize(forward);
    if (glm::length(glm::cross(forward, up)) < 1e-6)
        up = std::abs(forward.y) < 0.9 ? glm::dvec3(0.0, 1.0, 0.0) : glm::dvec3(0.0, 0.0, 1.0);
    const glm::dvec3 right = glm::normalize(glm::cross(forward, up));
    const glm::dvec3 trueUp = glm::cross(right, forward);
    const glm::dquat q = glm::normalize(glm::quat_cast(glm::dmat3(right, trueUp, -forward)));
    // Adding +0 turns −0 into +0 so that files do not spell "-0.0".
    return Json::array({q.x + 0.0, q.y + 0.0, q.z + 0.0, q.w + 0.0});
}

/// Packs attribute and index arrays into one little-endian buffer with one bufferView each.
class BufferPacker {
public:
    /// Appends `data` as a new bufferView and a tightly packed accessor over it; returns the
    /// accessor index. POSITION accessors get the min/max bounds glTF requires.
    template <class T>
    int addAccessor(std::span<const T> data, int componentType, const char* type, int target,
                    bool withBounds) {
        static_assert(sizeof(T) % 4 == 0, "accessor elements must keep 4-byte alignment");
        PIC_CHECK(!data.empty());
        const size_t offset = mBytes.size();
        const size_t byteLength = data.size_bytes();
        mBytes.resize(offset + byteLength);
        std::memcpy(mBytes.data() + offset, data.data(), byteLength);

        mViews.push_back(Json{
            {"buffer", 0}, {"byteOffset", offset}, {"byteLength", byteLength}, {"target", target}});
        Json accessor{{"bufferView", mViews.size() - 1},
                      {"componentType", componentType},
                      {"count", data.size()},
                      {"type", type}};
        if constexpr (std::is_same_v<T, glm::vec3>) {
            if (withBounds) {
                glm::vec3 lo = data[0];
                glm::vec3 hi = data[0];
                for (const glm::vec3& p : data) {
                    lo = glm::min(lo, p);
                    hi = glm::max(hi, p);
                }
                accessor["min"] = toJson(glm::dvec3(lo));
                accessor["max"] = toJson(glm::dvec3(hi));
            }
        }
        mAccessors.push_back(std::move(accessor));
        return int(mAccessors.size() - 1);
    }

    const std::vector<uint8_t>& bytes() const { return mBytes; }
    Json& views() { return mViews; }
    Json& accessors() { return mAccessors; }

private:
    std::vector<uint8_t> mBytes;
    Json mViews = Json::array();
    Json mAccessors = Json::array();
};

/// The glTF primitive for `p`, its arrays appended to `packer`.
Json primitiveJson(const PrimitiveData& p, BufferPacker& packer) {
    Json attributes{{"POSITION", packer.addAccessor(std::span(p.positions), kComponentFloat, "VEC3",
                                                    kTargetArrayBuffer, true)}};
    if (!p.normals.empty())
        attributes["NORMAL"] = packer.addAccessor(std::span(p.normals), kComponentFloat, "VEC3",
                                                  kTargetArrayBuffer, false);
    if (!p.uv0.empty())
        attributes["TEXCOORD_0"] = packer.addAccessor(std::span(p.uv0), kComponentFloat, "VEC2",
                                                      kTargetArrayBuffer, false);
    if (!p.uv1.empty())
        attributes["TEXCOORD_1"] = packer.addAccessor(std::span(p.uv1), kComponentFloat, "VEC2",
                                                      kTargetArrayBuffer, false);
    Json primitive{{"attributes", std::move(attributes)}};
    if (!p.indices.empty())
        primitive["indices"] = packer.addAccessor(std::span(p.indices), kComponentUnsignedInt,
                                                  "SCALAR", kTargetElementArrayBuffer, false);
    primitive["material"] = p.material;
    primitive["mode"] = uint32_t(p.mode);
    return primitive;
}

/// The node carrying light number `index`; its −Z is the light's direction.
Json lightNode(const LightDesc& light, size_t index) {
    Json node{{"name", light.name}};
    if (light.type != LightType::Directional) node["translation"] = toJson(light.position);
    if (light.type != LightType::Point)
        node["rotation"] = rotationLookingAlong(light.direction, glm::dvec3(0.0, 1.0, 0.0));
    node["extensions"] = {{"KHR_lights_punctual", {{"light", index}}}};
    return node;
}

/// The KHR_lights_punctual entry of a light.
Json lightJson(const LightDesc& light) {
    Json entry{{"name", light.name}};
    switch (light.type) {
    case LightType::Point:
        entry["type"] = "point";
        break;
    case LightType::Spot:
        entry["type"] = "spot";
        entry["spot"] = {{"innerConeAngle", light.innerConeAngle},
                         {"outerConeAngle", light.outerConeAngle}};
        break;
    case LightType::Directional:
        entry["type"] = "directional";
        break;
    }
    entry["color"] = toJson(light.color);
    entry["intensity"] = light.intensity;
    return entry;
}

/// The node carrying camera number `index`, placed at the eye with its −Z on the target.
Json cameraNode(const CameraDesc& camera, size_t index) {
    return Json{{"name", camera.name},
                {"camera", index},
                {"translation", toJson(camera.eye)},
                {"rotation", rotationLookingAlong(camera.target - camera.eye, camera.up)}};
}

/// A perspective camera with an infinite far plane.
Json cameraJson(const CameraDesc& camera) {
    return Json{{"name", camera.name},
                {"type", "perspective"},
                {"perspective",
                 {{"aspectRatio", camera.aspectRatio},
                  {"yfov", glm::radians(camera.yfovDegrees)},
                  {"znear", kCameraZNear}}}};
}

/// A Lambertian material: metallic 0, roughness 1, emission when it has any.
Json materialJson(const MaterialDesc& m) {
    Json pbr{{"baseColorFactor", {m.baseColor.r, m.baseColor.g, m.baseColor.b, 1.0}},
             {"metallicFactor", 0.0},
             {"roughnessFactor", 1.0}};
    if (m.baseColorTexture >= 0)
        pbr["baseColorTexture"] = {{"index", m.baseColorTexture},
                                   {"texCoord", m.baseColorTexCoord}};
    Json material{{"name", m.name}, {"pbrMetallicRoughness", std::move(pbr)}};
    if (m.emissiveFactor != glm::dvec3(0.0)) material["emissiveFactor"] = toJson(m.emissiveFactor);
    if (m.emissiveStrength != 1.0)
        material["extensions"] = {
            {"KHR_materials_emissive_strength", {{"emissiveStrength", m.emissiveStrength}}}};
    return material;
}

/// Writes `bytes` to a temporary file beside `path`, then renames it into place.
Result<void> writeFileAtomically(const std::filesystem::path& path, std::span<const char> bytes) {
    // The process id keeps concurrent writers of the same scene from sharing a temporary file.
    std::filesystem::path temporary = path;
    temporary += fmt::format(".{}.tmp", ::getpid());
    {
        std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
        if (!out)
            return fail(ErrorCode::Io, "cannot open '{}' for writing: {}", temporary.string(),
                        std::strerror(errno));
        out.write(bytes.data(), std::streamsize(bytes.size()));
        out.close();
        if (!out)
            return fail(ErrorCode::Io, "cannot write '{}': {}", temporary.string(),
                        std::strerror(errno));
    }
    std::error_code error;
    std::filesystem::rename(temporary, path, error);
    if (error)
        return fail(ErrorCode::Io, "cannot rename '{}' to '{}': {}", temporary.string(),
                    path.string(), error.message());
    return {};
}

/// Triangles of a TRIANGLES primitive; 0 for other modes.
uint64_t primitiveTriangles(const PrimitiveData& primitive) {
    if (primitive.mode != PrimitiveMode::Triangles) return 0;
    const size_t corners =
        primitive.indices.empty() ? primitive.positions.size() : primitive.indices.size();
    return corners / 3;
}

}  // namespace

uint32_t GltfBuilder::addMaterial(const MaterialDesc& material) {
    PIC_CHECK(material.baseColorTexture < int(mTextures.size()));
    mMaterials.push_back(material);
    return uint32_t(mMaterials.size() - 1);
}

uint32_t GltfBuilder::addPngTexture(const std::string& name, std::vector<uint8_t> png) {
    PIC_CHECK(!png.empty());
    mTextures.push_back({name, std::move(png)});
    return uint32_t(mTextures.size() - 1);
}

void GltfBuilder::addMesh(const std::string& name, std::vector<PrimitiveData> primitives) {
    PIC_CHECK(!primitives.empty());
    for (const PrimitiveData& p : primitives) {
        const size_t n = p.positions.size();
        PIC_CHECK(n > 0);
        PIC_CHECK(p.material < mMaterials.size());
        PIC_CHECK(p.normals.empty() || p.normals.size() == n);
        PIC_CHECK(p.uv0.empty() || p.uv0.size() == n);
        PIC_CHECK(p.uv1.empty() || p.uv1.size() == n);
        PIC_CHECK(p.uv1.empty() || !p.uv0.empty());
        if (p.mode == PrimitiveMode::Triangles)
            PIC_CHECK((p.indices.empty() ? n : p.indices.size()) % 3 == 0);
        PIC_CHECK(
            std::all_of(p.indices.begin(), p.indices.end(), [n](uint32_t i) { return i < n; }));
    }
    mMeshes.push_back({name, std::move(primitives)});
}

void GltfBuilder::addLight(const LightDesc& light) {
    mLights.push_back(light);
}

void GltfBuilder::addCamera(const CameraDesc& camera) {
    PIC_CHECK(glm::length(camera.target - camera.eye) > 0.0);
    mCameras.push_back(camera);
}

uint64_t GltfBuilder::triangleCount() const {
    uint64_t count = 0;
    for (const Mesh& mesh : mMeshes)
        for (const PrimitiveData& primitive : mesh.primitives)
            count += primitiveTriangles(primitive);
    return count;
}

Result<std::vector<std::string>> GltfBuilder::write(const std::string& outDir,
                                                    const std::string& name) const {
    const std::filesystem::path dir(outDir);
    const std::string binName = name + ".bin";
    Json doc{{"asset", {{"version", "2.0"}, {"generator", "pic_gen_scenes"}}}};

    Json extensionsUsed = Json::array();
    if (!mLights.empty()) extensionsUsed.push_back("KHR_lights_punctual");
    const bool anyStrength =
        std::any_of(mMaterials.begin(), mMaterials.end(),
                    [](const MaterialDesc& m) { return m.emissiveStrength != 1.0; });
    if (anyStrength) extensionsUsed.push_back("KHR_materials_emissive_strength");
    if (!extensionsUsed.empty()) doc["extensionsUsed"] = extensionsUsed;

    // Nodes in a fixed order: meshes, then lights, then cameras.
    Json nodes = Json::array();
    Json meshes = Json::array();
    BufferPacker packer;
    for (const Mesh& mesh : mMeshes) {
        Json primitives = Json::array();
        for (const PrimitiveData& primitive : mesh.primitives)
            primitives.push_back(primitiveJson(primitive, packer));
        nodes.push_back(Json{{"name", mesh.name}, {"mesh", meshes.size()}});
        meshes.push_back(Json{{"name", mesh.name}, {"primitives", std::move(primitives)}});
    }
    Json lights = Json::array();
    for (const LightDesc& light : mLights) {
        nodes.push_back(lightNode(light, lights.size()));
        lights.push_back(lightJson(light));
    }
    Json cameras = Json::array();
    for (const CameraDesc& camera : mCameras) {
        nodes.push_back(cameraNode(camera, cameras.size()));
        cameras.push_back(cameraJson(camera));
    }
    Json materials = Json::array();
    for (const MaterialDesc& material : mMaterials) materials.push_back(materialJson(material));

    Json scene{{"name", name}, {"nodes", Json::array()}};
    for (size_t i = 0; i < nodes.size(); ++i) scene["nodes"].push_back(i);
    doc["scene"] = 0;
    doc["scenes"] = Json::array({std::move(scene)});
    // glTF forbids empty top-level arrays, so each is written only when it has entries.
    if (!nodes.empty()) doc["nodes"] = std::move(nodes);
    if (!meshes.empty()) doc["meshes"] = std::move(meshes);
    if (!materials.empty()) doc["materials"] = std::move(materials);
    if (!cameras.empty()) doc["cameras"] = std::move(cameras);
    if (!mTextures.empty()) {
        doc["samplers"] = Json::array({Json{{"magFilter", kFilterNearest},
                                            {"minFilter", kFilterNearest},
                                            {"wrapS", kWrapRepeat},
                                            {"wrapT", kWrapRepeat}}});
        Json images = Json::array();
        Json textures = Json::array();
        for (const Texture& texture : mTextures) {
            images.push_back(Json{{"name", texture.name},
                                  {"uri", "data:image/png;base64," + base64(texture.png)}});
            textures.push_back(
                Json{{"name", texture.name}, {"sampler", 0}, {"source", textures.size()}});
        }
        doc["images"] = std::move(images);
        doc["textures"] = std::move(textures);
    }
    if (!packer.bytes().empty()) {
        doc["accessors"] = std::move(packer.accessors());
        doc["bufferViews"] = std::move(packer.views());
        doc["buffers"] =
            Json::array({Json{{"byteLength", packer.bytes().size()}, {"uri", binName}}});
    }
    if (!lights.empty())
        doc["extensions"] = {{"KHR_lights_punctual", {{"lights", std::move(lights)}}}};

    std::error_code error;
    std::filesystem::create_directories(dir, error);
    if (error)
        return fail(ErrorCode::Io, "cannot create output folder '{}': {}", outDir, error.message());

    // The buffer goes first so that a .gltf on disk always has its .bin beside it.
    std::vector<std::string> written;
    const std::filesystem::path gltfPath = dir / (name + ".gltf");
    written.push_back(gltfPath.string());
    if (!packer.bytes().empty()) {
        const std::filesystem::path binPath = dir / binName;
        const auto* data = reinterpret_cast<const char*>(packer.bytes().data());
        if (auto ok = writeFileAtomically(binPath, std::span(data, packer.bytes().size())); !ok)
            return std::unexpected(ok.error());
        written.push_back(binPath.string());
    }
    const std::string text = doc.dump(1) + "\n";
    if (auto ok = writeFileAtomically(gltfPath, text); !ok) return std::unexpected(ok.error());
    return written;
}

}  // namespace pic::testscenes
