#pragma once
/// The scene a browser draws (GET /v1/scene, server/web_server.h): the G-buffer's arrays of
/// render/gbuffer_geometry.h, the bake's cache layout and what the browser needs to place
/// them, in one zstd frame. This comment is the contract the browser reads.
///
/// The body is one zstd frame that carries its content size. Decompressed, all numbers
/// little-endian:
///
///     bytes 0..7       "PICWEB1" and a zero byte
///     bytes 8..11      J: uint32, the length of the JSON in bytes
///     bytes 12..12+J   the JSON, UTF-8
///     zero bytes up to the next multiple of 16: B, where the binary area starts
///     B + offset       each section's bytes (offset a multiple of 16, zero bytes between)
///
/// The JSON object:
///
///     format        1
///     bake_id       the bake's id (16 hex digits, ServedBake::id)
///     scene_name    the scene file's name
///     scene_hash    Scene::hash, 16 lowercase hex digits
///     bands_y, bands_c   the caches' SH bands lY, lC
///     caches        the bake's unique caches
///     triangles     the scene's triangles
///     grid          {"origin": [x, y, z] metres, "cell_size": metres, "dims": [x, y, z]
///                   vertices per axis}
///     lightmap      {"width", "height"} texels
///     bounds        {"min": [x, y, z], "max": [x, y, z]} metres (Scene::bounds)
///     epsilon       the renderer's ray offset, metres (render/renderer.h rendererEpsilonOf)
///     near          its camera's near-plane distance, metres (the same float)
///     no_cache      the cache index that names no cache (kNoCache, 4294967295)
///     sh            {"clamped_cosine": [K_0, …, K_7]}: the clamped cosine's zonal factor per
///                   band (core/sh.h clampedCosineZonal), which turns radiance SH into
///                   irradiance; the basis itself is GET /v1/sh_basis.glsl
///     materials     [{"name"}], in the scene's order (GbufferMaterial and triangles index it)
///     cameras       [{"name", "eye": [x, y, z], "target": [x, y, z], "up": [x, y, z],
///                   "fovy_degrees"}] (Scene::cameras)
///     sections      [{"name", "offset" (from B), "bytes", "count", "stride"}], bytes =
///                   count × stride (0 for an empty one), in this order:
///
///     vertices         GbufferVertex (shaders/shared/gbuffer.h), 64 bytes: 3 per triangle,
///                      triangle t's corners at 3t, 3t + 1, 3t + 2
///     triangles        GbufferTriangle, 48 bytes, one per triangle
///     materials        GbufferMaterial, 48 bytes, one per material
///     textures         GbufferTexture, 16 bytes, one per texture
///     levels           GbufferTextureLevel, 16 bytes: every texture's mip levels
///     texels           vec4 (float RGBA, linear), 16 bytes: every level's texels
///     grid_caches      uint32 per grid vertex, x + dims.x·(y + dims.y·z) (core/bake_data.h
///                      GridLayout::cacheIndex; no_cache where none)
///     lightmap_caches  uint32 per light-map texel, x + width·y (LightmapLayout::cacheIndex)
///
/// Each section holds the structs' bytes exactly as shaders/shared/gbuffer.h lays them out
/// (std430), so a browser can hand them to its shaders as they are.

#include <string>
#include <string_view>

#include "core/bake_data.h"
#include "core/error.h"
#include "core/scene.h"

namespace pic {

/// First 8 bytes of the decompressed blob.
inline constexpr std::string_view kWebSceneMagic{"PICWEB1\0", 8};
/// The JSON's "format".
inline constexpr int kWebSceneFormat = 1;
/// zstd level of the blob.
inline constexpr int kWebSceneZstdLevel = 3;

/// The blob above for `scene` and its bake `bake` (light-map UVs from
/// bake.lightmap.triangleUvs), named `bakeId`. InvalidInput for what gbufferGeometryOf
/// refuses, or cache maps whose lengths are not the grid's vertices and the light map's
/// texels; Internal when zstd fails.
Result<std::string> webSceneOf(const Scene& scene, const BakeData& bake, std::string_view bakeId);

}  // namespace pic
