#include "server/web_scene.h"

#include <bit>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <vector>

#include <zstd.h>
#include <nlohmann/json.hpp>

#include "core/sh.h"
#include "render/gbuffer_geometry.h"
#include "render/renderer.h"

namespace pic {

namespace {

static_assert(std::endian::native == std::endian::little,
              "the browsers' scene is little-endian, written as the host holds it");

/// Where a section's bytes come from.
struct Section {
    const char* name;
    const void* data;
    size_t count;
    size_t stride;
};

template <class T>
Section sectionOf(const char* name, const std::vector<T>& values) {
    return {name, values.data(), values.size(), sizeof(T)};
}

nlohmann::json vec3Json(const glm::vec3& v) {
    return {v.x, v.y, v.z};
}

size_t alignedTo16(size_t n) {
    return (n + 15) & ~size_t(15);
}

}  // namespace

Result<std::string> webSceneOf(const Scene& scene, const BakeData& bake, std::string_view bakeId) {
    PIC_TRY_ASSIGN(GbufferGeometry geometry, gbufferGeometryOf(scene, bake.lightmap.triangleUvs));
    // The browser indexes the cache maps by grid vertex and texel: their lengths must match.
    const GridLayout& grid = bake.grid;
    const size_t gridVertices = size_t(grid.dims.x) * grid.dims.y * grid.dims.z;
    if (grid.cacheIndex.size() != gridVertices)
        return fail(ErrorCode::InvalidInput,
                    "the bake's grid is {}x{}x{} vertices but holds {} cache indices", grid.dims.x,
                    grid.dims.y, grid.dims.z, grid.cacheIndex.size());
    const LightmapLayout& lightmap = bake.lightmap;
    if (lightmap.cacheIndex.size() != size_t(lightmap.width) * lightmap.height)
        return fail(ErrorCode::InvalidInput,
                    "the bake's light map is {}x{} texels but holds {} cache indices",
                    lightmap.width, lightmap.height, lightmap.cacheIndex.size());

    const Section sections[] = {
        sectionOf("vertices", geometry.vertices),
        sectionOf("triangles", geometry.triangles),
        sectionOf("materials", geometry.materials),
        sectionOf("textures", geometry.textures),
        sectionOf("levels", geometry.levels),
        sectionOf("texels", geometry.texels),
        sectionOf("grid_caches", grid.cacheIndex),
        sectionOf("lightmap_caches", lightmap.cacheIndex),
    };

    nlohmann::json json;
    json["format"] = kWebSceneFormat;
    json["bake_id"] = std::string(bakeId);
    json["scene_name"] = std::filesystem::path(scene.sourcePath).filename().string();
    json["scene_hash"] = fmt::format("{:016x}", scene.hash);
    json["bands_y"] = bake.params.bandsY;
    json["bands_c"] = bake.params.bandsC;
    json["caches"] = bake.caches.size();
    json["triangles"] = scene.triangles.size();
    json["grid"] = {{"origin", vec3Json(grid.origin)},
                    {"cell_size", grid.cellSize},
                    {"dims", {grid.dims.x, grid.dims.y, grid.dims.z}}};
    json["lightmap"] = {{"width", lightmap.width}, {"height", lightmap.height}};
    json["bounds"] = {{"min", vec3Json(scene.bounds.min)}, {"max", vec3Json(scene.bounds.max)}};
    const float epsilon = rendererEpsilonOf(scene);
    json["epsilon"] = epsilon;
    json["near"] = epsilon;
    json["no_cache"] = kNoCache;
    // K_l of the clamped cosine per band (core/sh.h clampedCosineZonal): the irradiance's
    // convolution factors, as the renderer's SH tables hold them.
    nlohmann::json& clampedCosine = json["sh"]["clamped_cosine"] = nlohmann::json::array();
    for (int l = 0; l < kMaxShBands; ++l) clampedCosine.push_back(clampedCosineZonal(l));
    nlohmann::json& materials = json["materials"] = nlohmann::json::array();
    for (const Material& material : scene.materials) materials.push_back({{"name", material.name}});
    nlohmann::json& cameras = json["cameras"] = nlohmann::json::array();
    for (const Camera& camera : scene.cameras)
        cameras.push_back({{"name", camera.name},
                           {"eye", vec3Json(camera.eye)},
                           {"target", vec3Json(camera.target)},
                           {"up", vec3Json(camera.up)},
                           {"fovy_degrees", camera.fovyDegrees}});
    // Each section starts on 16 bytes from B, so that it can be read as its structs in place.
    nlohmann::json& layout = json["sections"] = nlohmann::json::array();
    std::vector<size_t> offsets;
    size_t binaryBytes = 0;
    for (const Section& section : sections) {
        const size_t bytes = section.count * section.stride;
        binaryBytes = alignedTo16(binaryBytes);
        offsets.push_back(binaryBytes);
        layout.push_back({{"name", section.name},
                          {"offset", binaryBytes},
                          {"bytes", bytes},
                          {"count", section.count},
                          {"stride", section.stride}});
        binaryBytes += bytes;
    }
    // Invalid UTF-8 in a name (from the glTF file) is replaced rather than refused.
    const std::string text = json.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
    if (text.size() > UINT32_MAX)
        return fail(ErrorCode::InvalidInput, "the scene's JSON takes {} bytes, more than 4 GiB",
                    text.size());

    // Magic, JSON length, JSON, padding, then the sections at B + offset.
    const size_t binaryStart = alignedTo16(kWebSceneMagic.size() + 4 + text.size());
    std::string raw(binaryStart + binaryBytes, '\0');
    std::memcpy(raw.data(), kWebSceneMagic.data(), kWebSceneMagic.size());
    const uint32_t length = uint32_t(text.size());
    std::memcpy(raw.data() + kWebSceneMagic.size(), &length, 4);
    std::memcpy(raw.data() + kWebSceneMagic.size() + 4, text.data(), text.size());
    for (size_t i = 0; i < std::size(sections); ++i)
        if (sections[i].count > 0)
            std::memcpy(raw.data() + binaryStart + offsets[i], sections[i].data,
                        sections[i].count * sections[i].stride);

    // One frame with its content size (ZSTD_compress writes it), so a browser can allocate
    // the whole buffer before it decompresses.
    std::string compressed(ZSTD_compressBound(raw.size()), '\0');
    const size_t written = ZSTD_compress(compressed.data(), compressed.size(), raw.data(),
                                         raw.size(), kWebSceneZstdLevel);
    if (ZSTD_isError(written))
        return fail(ErrorCode::Internal, "zstd could not compress the {} bytes of scene {}: {}",
                    raw.size(), scene.sourcePath, ZSTD_getErrorName(written));
    compressed.resize(written);
    return compressed;
}

}  // namespace pic
