#include "render/gbuffer_geometry.h"

#include <algorithm>
#include <iterator>

#include "core/bake_data.h"

namespace pic {

Result<GbufferGeometry> gbufferGeometryOf(const Scene& scene,
                                          std::span<const glm::vec2> triangleUvs) {
    using namespace gpu;
    if (scene.triangles.empty())
        return fail(ErrorCode::InvalidInput, "scene {} has no triangles to render",
                    scene.sourcePath);
    if (triangleUvs.size() != 3 * scene.triangles.size())
        return fail(ErrorCode::InvalidInput,
                    "{} light-map UVs for the {} triangles of scene {}, which need {}",
                    triangleUvs.size(), scene.triangles.size(), scene.sourcePath,
                    3 * scene.triangles.size());
    GbufferGeometry geometry;

    // Textures first: materials name them by index. Each brings its mip chain as built at
    // load (core/texture.h buildMipChain), level 0 first, so both twins read the same levels.
    std::vector<GbufferTexture>& textures = geometry.textures;
    std::vector<GbufferTextureLevel>& levels = geometry.levels;
    std::vector<glm::vec4>& texels = geometry.texels;
    for (size_t i = 0; i < scene.textures.size(); ++i) {
        const Texture& t = scene.textures[i];
        if (t.width <= 0 || t.height <= 0 || t.texels.size() != size_t(t.width) * size_t(t.height))
            return fail(ErrorCode::InvalidInput, "texture {} (\"{}\") is {}x{} with {} texels", i,
                        t.name, t.width, t.height, t.texels.size());
        GbufferTexture record{};
        record.firstLevel = uint32_t(levels.size());
        record.levelCount = t.levelCount();
        record.wrap = (t.repeatS ? kTextureRepeatS : 0u) | (t.repeatT ? kTextureRepeatT : 0u);
        textures.push_back(record);
        const auto addLevel = [&](int width, int height, const std::vector<glm::vec4>& source) {
            levels.push_back({uint32_t(texels.size()), width, height, 0u});
            texels.insert(texels.end(), source.begin(), source.end());
        };
        addLevel(t.width, t.height, t.texels);
        for (const MipLevel& level : t.mips) {
            if (level.width <= 0 || level.height <= 0 ||
                level.texels.size() != size_t(level.width) * size_t(level.height))
                return fail(ErrorCode::InvalidInput,
                            "texture {} (\"{}\") has a mip level {}x{} with {} texels", i, t.name,
                            level.width, level.height, level.texels.size());
            addLevel(level.width, level.height, level.texels);
        }
    }
    std::vector<GbufferMaterial>& materials = geometry.materials;
    const auto textureOk = [&](int index) {
        return index < 0 || size_t(index) < scene.textures.size();
    };
    for (size_t m = 0; m < scene.materials.size(); ++m) {
        const Material& source = scene.materials[m];
        if (!textureOk(source.baseColorTexture) || !textureOk(source.emissiveTexture))
            return fail(ErrorCode::InvalidInput,
                        "material {} (\"{}\") names texture {} or {}, the scene has {}", m,
                        source.name, source.baseColorTexture, source.emissiveTexture,
                        scene.textures.size());
        GbufferMaterial record{};
        record.baseColorFactor = source.baseColorFactor;
        record.emission = source.emission;
        record.baseColorTexture = source.baseColorTexture;
        record.baseColorTexCoord = source.baseColorTexCoord;
        record.emissiveTexture = source.emissiveTexture;
        materials.push_back(record);
    }

    // Three unshared corners per triangle: the light-map UVs belong to a triangle's corner,
    // and the vertex shader numbers triangles by gl_VertexIndex / 3.
    std::vector<GbufferVertex>& vertices = geometry.vertices;
    vertices.reserve(3 * scene.triangles.size());
    std::vector<GbufferTriangle>& triangles = geometry.triangles;
    triangles.reserve(scene.triangles.size());
    for (size_t t = 0; t < scene.triangles.size(); ++t) {
        const Triangle& triangle = scene.triangles[t];
        if (triangle.material >= scene.materials.size() ||
            std::any_of(std::begin(triangle.v), std::end(triangle.v),
                        [&](uint32_t v) { return v >= scene.vertices.size(); }))
            return fail(ErrorCode::InvalidInput,
                        "triangle {} names material {} or a vertex beyond the scene's {} "
                        "materials and {} vertices",
                        t, triangle.material, scene.materials.size(), scene.vertices.size());
        const bool lightmapped = triangleUvs[3 * t].x != kNotLightmapped;
        for (int k = 0; k < 3; ++k) {
            const Vertex& source = scene.vertices[triangle.v[k]];
            GbufferVertex corner{};
            corner.position = source.position;
            corner.color = source.color;
            corner.uv0 = source.uv0;
            corner.uv1 = source.uv1;
            corner.lightmapUv = lightmapped ? triangleUvs[3 * t + k] : glm::vec2(0.0f);
            vertices.push_back(corner);
        }
        GbufferTriangle record{};
        record.normal = scene.triangleNormal(uint32_t(t));
        record.material = triangle.material;
        record.lightmapped = lightmapped ? 1u : 0u;
        // The base-colour UV set's gradients turn the pixel footprint into texels.
        const Material& material = scene.materials[triangle.material];
        if (material.baseColorTexture >= 0) {
            const UvGradients g = scene.uvGradients(uint32_t(t), material.baseColorTexCoord);
            record.uGradient = g.u;
            record.vGradient = g.v;
        }
        triangles.push_back(record);
    }
    return geometry;
}

}  // namespace pic
