#pragma once
/// What the G-buffer shader reads of a scene (shaders/shared/gbuffer.h), built on the CPU
/// without Vulkan: the G-buffer pass (render/passes/gbuffer_pass.h) uploads these arrays, and
/// the server sends browsers the same bytes (server/web_scene.h).

#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "core/error.h"
#include "core/scene.h"
#include "shaders/shared/gbuffer.h"

namespace pic {

/// The G-buffer's arrays, each in the std430 layout of its struct.
struct GbufferGeometry {
    std::vector<gpu::GbufferVertex> vertices;      ///< 3 unshared corners per triangle, in order
    std::vector<gpu::GbufferTriangle> triangles;   ///< one per scene triangle
    std::vector<gpu::GbufferMaterial> materials;   ///< one per scene material
    std::vector<gpu::GbufferTexture> textures;     ///< one per scene texture
    std::vector<gpu::GbufferTextureLevel> levels;  ///< every texture's mip levels, level 0 first
    std::vector<glm::vec4> texels;                 ///< every level's texels, linear RGBA
};

/// The G-buffer's arrays of `scene`, with `triangleUvs` (3 per triangle, kNotLightmapped for
/// grid-shaded triangles) as the corners' light-map UVs and the textures' mip chains as the
/// scene holds them (core/texture.h buildMipChain). InvalidInput for a scene without
/// triangles, light-map UVs that are not 3 per triangle, or triangles, materials and textures
/// that do not index each other, or texels that do not fill a texture's or a mip level's size.
Result<GbufferGeometry> gbufferGeometryOf(const Scene& scene,
                                          std::span<const glm::vec2> triangleUvs);

}  // namespace pic
