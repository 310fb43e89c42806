#ifndef PIC_SHADERS_SHARED_GBUFFER_H
#define PIC_SHADERS_SHARED_GBUFFER_H
// The thin client's G-buffer (render/passes/gbuffer_pass.h): the scene's triangles as the rasteriser
// reads them, their materials and textures, and the four RGBA32F targets it writes per pixel:
//   0: world position (metres), light-map u (kNotLightmappedUv: grid-shaded or missed)
//   1: unit geometric normal facing the camera, light-map v
//   2: albedo ρ (linear RGB), 1 where a surface was hit, 0 where the pixel sees nothing
//   3: emitted radiance (W/(m²·sr), emissive scale applied, front faces only), 0
#include "glue.h"

PIC_NAMESPACE_BEGIN

PIC_CONST(uint, kGbufferTargets, 4u);
PIC_CONST(float, kNotLightmappedUv, -1.0);  // core/bake_data.h kNotLightmapped

// One corner of a triangle (vertex input, 3 per triangle, not shared, so that triangle t is
// vertices 3t, 3t + 1, 3t + 2).
struct GbufferVertex {
    vec3 position;    // metres, world space
    float pad0;
    vec4 color;       // COLOR_0, linear RGBA
    vec2 uv0;         // TEXCOORD_0
    vec2 uv1;         // TEXCOORD_1
    vec2 lightmapUv;  // in [0, 1]² of the light-map atlas; unused for grid-shaded triangles
    vec2 pad1;
};
PIC_STRUCT_CHECK(GbufferVertex, 64);
PIC_OFFSET_CHECK(GbufferVertex, color, 16);
PIC_OFFSET_CHECK(GbufferVertex, uv0, 32);
PIC_OFFSET_CHECK(GbufferVertex, uv1, 40);
PIC_OFFSET_CHECK(GbufferVertex, lightmapUv, 48);

// What is constant over a triangle.
struct GbufferTriangle {
    vec3 normal;       // unit geometric normal, counter-clockwise winding (Scene::triangleNormal)
    uint material;     // index into the materials
    vec3 uGradient;    // ∂u/∂position per metre of the base-colour UV set (Scene::uvGradients)
    uint lightmapped;  // 1: shaded from the light map, 0: from the grid
    vec3 vGradient;    // ∂v/∂position per metre of the same set
    uint pad0;
};
PIC_STRUCT_CHECK(GbufferTriangle, 48);
PIC_OFFSET_CHECK(GbufferTriangle, uGradient, 16);
PIC_OFFSET_CHECK(GbufferTriangle, vGradient, 32);

// core/scene.h Material, as far as shading reads it.
struct GbufferMaterial {
    vec4 baseColorFactor;
    vec3 emission;           // W/(m²·sr)
    int baseColorTexture;    // index into the textures, -1 for none
    int baseColorTexCoord;   // 0: TEXCOORD_0, 1: TEXCOORD_1
    int emissiveTexture;     // index into the textures (TEXCOORD_0), -1 for none
    uint pad0;
    uint pad1;
};
PIC_STRUCT_CHECK(GbufferMaterial, 48);

PIC_CONST(uint, kTextureRepeatS, 1u);
PIC_CONST(uint, kTextureRepeatT, 2u);
// core/texture.h kMaxAnisotropy: most trilinear taps of one footprint lookup.
PIC_CONST(int, kGbufferMaxAnisotropy, 16);

// core/texture.h Texture: its mip levels (level 0 first) at [firstLevel, firstLevel +
// levelCount) of the level records.
struct GbufferTexture {
    uint firstLevel;
    int levelCount;
    uint wrap;  // kTextureRepeatS | kTextureRepeatT where the axis repeats, else it clamps
    uint pad0;
};
PIC_STRUCT_CHECK(GbufferTexture, 16);

// One mip level: its texels (linear RGBA, row 0 at v = 0) at [firstTexel, firstTexel +
// width·height) of the texel buffer.
struct GbufferTextureLevel {
    uint firstTexel;
    int width;
    int height;
    uint pad0;
};
PIC_STRUCT_CHECK(GbufferTextureLevel, 16);

// Push constants of both raster stages.
struct GbufferPush {
    mat4 clipFromWorld;  // reversed-Z perspective of the camera (pixel centres = CameraRays')
    vec3 eye;            // metres: decides which face of a triangle the camera sees
    float pad0;
    vec4 directionPerPixelX;  // xyz: CameraRays::directionPerPixelX (texture footprints), w: 0
    vec4 directionPerPixelY;  // xyz: CameraRays::directionPerPixelY, w: 0
};
PIC_STRUCT_CHECK(GbufferPush, 112);

PIC_NAMESPACE_END

#endif
