#ifndef PIC_SHADERS_SHARED_BAKE_LAYOUT_H
#define PIC_SHADERS_SHARED_BAKE_LAYOUT_H
// Records of the bake file that the runtime uploads to the GPU as std430 buffers.
// Written once here for C++ and GLSL (STYLE.md 9-10).
#include "glue.h"

PIC_NAMESPACE_BEGIN

PIC_CONST(uint, kNoNode, 0xFFFFFFFFu);
PIC_CONST(uint, kNoCache, 0xFFFFFFFFu);
// Steps of a link's spread share (core/bake_data.h encodeSpreadShare): the GPU's links carry it in
// 6 bits (shared/cache_lighting.h).
PIC_CONST(uint, kSpreadShareSteps, 63u);
PIC_CONST(uint, kCacheKindGrid, 0u);
PIC_CONST(uint, kCacheKindLightmap, 1u);

// A leaf sample of the scene: an equal-area disc on a surface (paper 000 §4.2).
struct Surfel {
    vec3 position;   // metres, world space
    float area;      // m²; equal for all surfels of a bake
    vec3 normal;     // unit, world space
    uint material;   // index into the scene's materials (for emissive scaling at runtime)
    vec3 albedo;     // linear RGB, averaged over the footprint
    float radius;    // metres, sqrt(area / pi)
    vec3 emission;   // radiance W/(m²·sr), averaged over the footprint
    uint triangle;   // scene triangle the surfel lies on
};
PIC_STRUCT_CHECK(Surfel, 64);
#ifndef __cplusplus
// Surfel i of a uniform texel buffer of RGBA32UI texels holding the records, four texels
// each, the floats by bit cast (exact for every pattern; a float format could flush the
// uint fields, which read as denormals).
Surfel fetchSurfel(usamplerBuffer records, uint i) {
    const int t = int(i) * 4;
    const uvec4 a = texelFetch(records, t);
    const uvec4 b = texelFetch(records, t + 1);
    const uvec4 c = texelFetch(records, t + 2);
    const uvec4 d = texelFetch(records, t + 3);
    return Surfel(uintBitsToFloat(a.xyz), uintBitsToFloat(a.w), uintBitsToFloat(b.xyz), b.w,
                  uintBitsToFloat(c.xyz), uintBitsToFloat(c.w), uintBitsToFloat(d.xyz), d.w);
}
#endif

// A node of the surfel hierarchy (paper 000 §4.3). Nodes [0, nS) are the leaves,
// node i being surfel i; inner nodes follow, ordered by level so that each level
// is a contiguous range and every child precedes its parent; the root is last.
struct Node {
    vec3 center;        // metres, area-weighted centre of its surfels
    float area;         // m², sum of its surfels' areas
    vec3 normal;        // unit area-weighted mean normal (zero if they cancel)
    float radius;       // metres, bounding radius of its surfel discs around center
    uint left;          // child node, kNoNode for leaves
    uint right;         // child node, kNoNode for leaves
    uint parent;        // kNoNode for the root
    uint firstSurfel;   // its surfels are [firstSurfel, firstSurfel + surfelCount)
    uint surfelCount;
    uint level;         // 0 for leaves, 1 + max(level of children) otherwise
    uint pad0;
    uint pad1;
};
PIC_STRUCT_CHECK(Node, 64);

// A cache: an SH probe of incident radiance (grid vertex or light-map texel centre).
struct Cache {
    vec3 position;   // metres, world space
    uint kind;       // kCacheKindGrid or kCacheKindLightmap
    vec3 normal;     // unit surface normal for light-map caches, zero for grid caches
    uint texel;      // linear index of its first texel in the grid or light map
};
PIC_STRUCT_CHECK(Cache, 32);

// A runtime-projected link (paper 000 §4.6): incident radiance from node `node`
// is Φ_node · factor · (cone of half-angle α around direction) projected to SH.
struct RtpLink {
    uint node;               // index into the node array; factor 0 marks padding
    float factor;            // visible fraction / (π · node area), 1/(m²·sr)
    uint directionOct;       // unit direction cache → node, octahedral 2 × snorm16
    float oneMinusCosAlpha;  // 1 − cos α of the cone with the node's solid angle
};
PIC_STRUCT_CHECK(RtpLink, 16);

PIC_NAMESPACE_END

#endif
