#include "core/scene_objects.h"

#include <array>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <string_view>
#include <system_error>

#include <fmt/format.h>
#include <glm/gtc/matrix_transform.hpp>

#include "core/bake_data.h"
#include "core/gltf_loader.h"

namespace pic {
namespace {

constexpr const char* kUsage = "tx,ty,tz,rx,ry,rz,s";

/// R = Rz·Ry·Rx of `degrees`.
glm::mat3 rotationOf(const glm::vec3& degrees) {
    glm::mat4 r(1.0f);
    r = glm::rotate(r, glm::radians(degrees.z), glm::vec3(0.0f, 0.0f, 1.0f));
    r = glm::rotate(r, glm::radians(degrees.y), glm::vec3(0.0f, 1.0f, 0.0f));
    r = glm::rotate(r, glm::radians(degrees.x), glm::vec3(1.0f, 0.0f, 0.0f));
    return glm::mat3(r);
}

}  // namespace

Result<ObjectPlacement> parseObjectPlacement(const std::string& path,
                                             const std::string& transform) {
    std::array<float, 7> values{};
    size_t count = 0;
    std::string_view rest = transform;
    while (true) {
        const size_t comma = rest.find(',');
        std::string_view field = rest.substr(0, comma);
        while (!field.empty() && (field.front() == ' ' || field.front() == '\t'))
            field.remove_prefix(1);
        while (!field.empty() && (field.back() == ' ' || field.back() == '\t'))
            field.remove_suffix(1);
        if (count == values.size())
            return fail(ErrorCode::InvalidInput,
                        "--transform needs 7 numbers {}, got more in \"{}\"", kUsage, transform);
        float& value = values[count++];
        const auto [end, ec] = std::from_chars(field.data(), field.data() + field.size(), value);
        if (field.empty() || ec != std::errc() || end != field.data() + field.size() ||
            !std::isfinite(value))
            return fail(ErrorCode::InvalidInput,
                        "--transform needs 7 finite numbers {}, field {} is \"{}\" in \"{}\"",
                        kUsage, count, field, transform);
        if (comma == std::string_view::npos) break;
        rest.remove_prefix(comma + 1);
    }
    if (count != values.size())
        return fail(ErrorCode::InvalidInput, "--transform needs 7 numbers {}, got {} in \"{}\"",
                    kUsage, count, transform);
    if (!(values[6] > 0.0f))
        return fail(ErrorCode::InvalidInput, "--transform scale s must be > 0, got {} in \"{}\"",
                    values[6], transform);
    ObjectPlacement placement;
    placement.path = path;
    placement.translation = {values[0], values[1], values[2]};
    placement.rotationDegrees = {values[3], values[4], values[5]};
    placement.scale = values[6];
    return placement;
}

Result<std::vector<ObjectPlacement>> parseObjectFlags(const std::vector<std::string>& objects,
                                                     const std::vector<std::string>& transforms) {
    if (objects.size() != transforms.size())
        return fail(ErrorCode::InvalidInput,
                    "every --object needs its --transform: {} objects, {} transforms",
                    objects.size(), transforms.size());
    std::vector<ObjectPlacement> placements;
    for (size_t i = 0; i < objects.size(); ++i) {
        PIC_TRY_ASSIGN(ObjectPlacement placement, parseObjectPlacement(objects[i], transforms[i]));
        placements.push_back(std::move(placement));
    }
    return placements;
}

Result<Scene> placeObjects(const Scene& base, const std::vector<ObjectPlacement>& objects) {
    Scene scene = base;
    for (const ObjectPlacement& object : objects) {
        auto loaded = loadScene(object.path);
        if (!loaded)
            return fail(loaded.error().code, "--object {}: {}", object.path,
                        loaded.error().message);
        const Scene& model = *loaded;
        const glm::mat3 rotation = rotationOf(object.rotationDegrees);
        const uint32_t firstVertex = uint32_t(scene.vertices.size());
        const uint32_t firstMaterial = uint32_t(scene.materials.size());
        const int firstTexture = int(scene.textures.size());
        const uint32_t firstPrimitive = uint32_t(scene.primitives.size());
        const uint32_t firstTriangle = uint32_t(scene.triangles.size());
        for (Vertex v : model.vertices) {
            v.position = object.translation + rotation * (object.scale * v.position);
            v.normal = glm::normalize(rotation * v.normal);
            scene.vertices.push_back(v);
        }
        const std::string stem = std::filesystem::path(object.path).stem().string();
        for (Material m : model.materials) {
            m.name = stem + "/" + m.name;
            if (m.baseColorTexture >= 0) m.baseColorTexture += firstTexture;
            if (m.emissiveTexture >= 0) m.emissiveTexture += firstTexture;
            scene.materials.push_back(std::move(m));
        }
        scene.textures.insert(scene.textures.end(), model.textures.begin(), model.textures.end());
        for (Primitive p : model.primitives) {
            p.name = stem + "/" + p.name;
            p.firstTriangle += firstTriangle;
            scene.primitives.push_back(std::move(p));
        }
        for (Triangle t : model.triangles) {
            for (uint32_t& v : t.v) v += firstVertex;
            t.material += firstMaterial;
            t.primitive += firstPrimitive;
            scene.triangles.push_back(t);
        }
    }
    finishScene(scene);
    return scene;
}

double gridCoverage(const Scene& scene, size_t firstVertex, const glm::vec3& origin,
                    float cellSize, const glm::uvec3& dims, const std::vector<uint32_t>& cacheIndex) {
    if (firstVertex >= scene.vertices.size()) return 1.0;
    if (!(cellSize > 0.0f) || dims.x == 0 || dims.y == 0 || dims.z == 0 ||
        cacheIndex.size() != size_t{dims.x} * dims.y * dims.z)
        return 0.0;
    size_t covered = 0;
    for (size_t i = firstVertex; i < scene.vertices.size(); ++i) {
        const glm::vec3 cell = glm::floor((scene.vertices[i].position - origin) / cellSize);
        bool any = false;
        for (int corner = 0; corner < 8 && !any; ++corner) {
            const glm::ivec3 v = glm::ivec3(cell) + glm::ivec3(corner & 1, (corner >> 1) & 1, corner >> 2);
            if (v.x < 0 || v.y < 0 || v.z < 0 || v.x >= int(dims.x) || v.y >= int(dims.y) ||
                v.z >= int(dims.z))
                continue;
            any = cacheIndex[size_t(v.x) + dims.x * (size_t(v.y) + dims.y * size_t(v.z))] !=
                  kNoCache;
        }
        covered += any ? 1 : 0;
    }
    return double(covered) / double(scene.vertices.size() - firstVertex);
}

std::string gridCoverageWarning(double coverage) {
    if (coverage >= 0.9) return {};
    return fmt::format("{:.0f} % of the objects' vertices have no grid cache around them and get "
                       "no indirect light there; a bake made with --grid-caches space fills the "
                       "grid for dynamic objects",
                       100.0 * (1.0 - coverage));
}

}  // namespace pic
