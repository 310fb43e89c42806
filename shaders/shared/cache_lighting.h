#ifndef PIC_SHADERS_SHARED_CACHE_LIGHTING_H
#define PIC_SHADERS_SHARED_CACHE_LIGHTING_H
// Cache lighting (paper 000 Figure 2 step 4, eq. 3, §4.6, §4.8). Specialization constants:
// 0 lY, 1 lC, 2 nL, 3 link form (kLinkFormSh / kLinkFormRtp), 4 mapping (kCachePerInvocation
// / kCachePerSubgroup), 5 words per texel of the links (1 to 4, dividing a link's words).
// Links are stored sequentially per cache; a dispatch covers one chunk of caches whose links
// fit one texel view (maxTexelBufferElements).
//
// The node radiance and the links are read as uniform texel buffers of 32-bit uint texels, a
// link in texels of 4, 2 or 3 words that divide it (CacheLightingPass): on lavapipe a
// storage-buffer load whose index differs per lane is a branch and a scalar load per lane, a
// texel fetch a gather. Moderate atrium, one cache-lighting pass, medians of 5 alternated
// runs: RTP 5.4 → 3.9 ms, SH 8.9 → 3.7 ms.
#include "glue.h"

PIC_NAMESPACE_BEGIN

PIC_CONST(uint, kCacheLightingGroup, 64u);
PIC_CONST(uint, kLinkFormSh, 0u);
PIC_CONST(uint, kLinkFormRtp, 1u);
// An invocation walks one cache's links (CPU devices: a lane's loads are scalar anyway), or a
// subgroup shares them, lane by lane, and sums its lanes (GPUs: neighbouring lanes read
// neighbouring links, and a few thousand caches still fill the device).
PIC_CONST(uint, kCachePerInvocation, 0u);
PIC_CONST(uint, kCachePerSubgroup, 1u);
// Largest |radiance| a half-float cache coefficient holds; larger values are clamped.
PIC_CONST(float, kHalfMax, 65504.0f);

// A runtime-projected link as the GPU reads it: 16 bytes, one texel of 4 words (the bake's
// RtpLink, tint and offset are 26). Its node's light comes as the radiance of its flux spread
// (shared/pull.h, written by surfel lighting and the pull), so the link keeps V = factor·π·A
// instead of the factor: Φ·factor = (Φ / (π·A))·V. V is the visible fraction of the node in
// the uniform model and may exceed 1 where the flux weights favour the part the cache sees
// (binary16 holds it). The tint (core/color.h encodeLinkTint, there 3 × unorm10) is three
// unorm8 in the words' top bytes, within 1/510 of its largest channel; the direction
// (core/color.h encodeOctahedral, there 2 × snorm16) is 2 × snorm9, within 0.4°; the seen
// share (core/bake_data.h encodeSpreadShare) is its 6-bit code.
struct GpuRtpLink {
    uint nodeAndRed;         // node index (bits 0-23) | tint R << 24
    uint directionAndGreen;  // unit direction cache → node, octahedral x | y << 9
                             // | spread share << 18 | tint G << 24
    uint visibleAndCone;     // binary16 V (0 marks padding) | binary16 (1 − cos α) << 16
    uint pointAndBlue;       // box point (render/node_spread.h encodeBoxPoint) | tint B << 24
};
PIC_STRUCT_CHECK(GpuRtpLink, 16);
PIC_CONST(uint, kGpuLinkNodeBits, 24u);

// An SH-projected link as the GPU reads it: the node index, its tint (unorm10 as in the bake),
// its box point | its spread share's code << 24, then its lY² binary16 coefficients (rescaled
// by π·A to take the node's radiance) two per 32-bit word, then one binary16 more, its
// irradiance along a light-map cache's normal (render/link_irradiance.h linkIrradiance,
// rescaled alike; 0 for grid caches), and zero words up to a multiple of 4, so that 2- or
// 4-word texels divide it: 8, 8, 12 words for lY = 2, 3, 4 (a record always has room for the
// extra half).
#ifdef __cplusplus
inline constexpr uint shLinkWords(uint countY) {
    return (3u + (countY + 1u) / 2u + 3u) / 4u * 4u;
}
#endif

struct CacheLightingPush {
    uint firstCache;  // the chunk is caches [firstCache, firstCache + cacheCount)
    uint cacheCount;
    uint pad0;
    uint pad1;
};
PIC_STRUCT_CHECK(CacheLightingPush, 16);

PIC_NAMESPACE_END

#endif
