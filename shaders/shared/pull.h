#ifndef PIC_SHADERS_SHARED_PULL_H
#define PIC_SHADERS_SHARED_PULL_H
// Pull (paper 000 Figure 2 step 3): one dispatch per hierarchy level. Besides the float flux
// and its first moment it writes each inner node's light as cache lighting reads it: its
// radiance Φ / (π·A) as RGBE8 (paper 000 §4.7) and its flux's limited linear spread.
#include "glue.h"

PIC_NAMESPACE_BEGIN

PIC_CONST(uint, kPullGroup, 64u);
// Specialization constant 0: one level per dispatch, or the tail, every level from the
// first of a run of levels with at most kPullTailNodes nodes to the root, in one workgroup
// with a barrier between levels (the hierarchy's upper levels are small: 16 of the moderate
// atrium's 23 levels hold at most 256 nodes, and a dispatch with its barrier costs more than
// their additions).
PIC_CONST(uint, kPullModeLevel, 0u);
PIC_CONST(uint, kPullModeTail, 1u);
PIC_CONST(uint, kPullTailNodes, 256u);

// An inner node as the pull reads it: eight RGBA32UI texels. The pull reads the inner nodes and
// the children's flux as uniform texel buffers, gathers on lavapipe rather than a branch per
// lane (shared/cache_lighting.h). Besides the children and 1 / (π·A) it holds the node's
// flux spread (render/node_spread.h NodeSpread): its principal axes, the inverse variances along
// them, the surfels' extent [low, high] along them and each child's flux centroid less the
// node's.
struct PullNode {
    uint left;  // child nodes
    uint right;
    float radianceScale;  // 1 / (π · area): flux W → radiance W/(m²·sr) of a Lambertian node
    uint pad0;
    vec3 axis0;  // principal axes, orthonormal
    float low0;  // least surfel coordinate along each axis about the centroid, ≤ 0, metres
    vec3 axis1;
    float low1;
    vec3 axis2;
    float low2;
    vec3 inverseVariance;  // 1/m² per axis; 0 when the node's surfels share one point
    float pad1;
    vec3 high;  // greatest surfel coordinate along each axis about the centroid, ≥ 0
    float pad2;
    vec3 leftOffset;  // x̄_left − x̄_node, metres
    float pad3;
    vec3 rightOffset;  // x̄_right − x̄_node
    float pad4;
};
PIC_STRUCT_CHECK(PullNode, 128);
PIC_CONST(uint, kPullNodeTexels, 8u);
#ifndef __cplusplus
// Inner node i of a uniform texel buffer of RGBA32UI texels, kPullNodeTexels per record.
PullNode fetchPullNode(usamplerBuffer records, uint i) {
    const int t = int(i * kPullNodeTexels);
    const uvec4 a = texelFetch(records, t);
    const vec4 b = uintBitsToFloat(texelFetch(records, t + 1));
    const vec4 c = uintBitsToFloat(texelFetch(records, t + 2));
    const vec4 d = uintBitsToFloat(texelFetch(records, t + 3));
    const vec4 e = uintBitsToFloat(texelFetch(records, t + 4));
    const vec4 f = uintBitsToFloat(texelFetch(records, t + 5));
    const vec4 g = uintBitsToFloat(texelFetch(records, t + 6));
    const vec4 h = uintBitsToFloat(texelFetch(records, t + 7));
    return PullNode(a.x, a.y, uintBitsToFloat(a.z), a.w, b.xyz, b.w, c.xyz, c.w, d.xyz, d.w,
                    e.xyz, e.w, f.xyz, f.w, g.xyz, g.w, h.xyz, h.w);
}
#endif

// A node as cache lighting reads it: one RGBA32UI texel (render/node_spread.h ChannelSpread and
// ExponentialSpread). Words 0-2 hold the slopes of its flux spread per channel along its
// box's axes, nine snorm8: word 0 R.xyz G.x, word 1 G.yz B.xy, word 2 B.z in bits 0-7; word 3
// the spread's radiance at the box centre, centre / (π·A), as RGBE8. A linear node's slopes
// are rounded towards zero, so that each channel's Σ|slope| stays ≤ 1, and a link at box
// point u reads radiance·(1 + slopes·u) per channel. An exponential node (bit 31 of word 2)
// holds its slopes over kExponentialSpreadCap, rounded to nearest, and ln Z per channel as
// unorm7 over [0, kConcentrationRange] in bits 8-14 (R), 15-21 (G), 22-28 (B) of word 2; a
// link at u that sees share v of it reads radiance·exp(slopes·u − (1 − v)·ln Z).
// Leaves have no slopes (words 0-2 zero).
PIC_CONST(uint, kNodeLightRadianceWord, 3u);
PIC_CONST(uint, kNodeLightExponentialBit, 0x80000000u);
// The largest Σ_k |slope_k| of an exponential spread: its reads span at most e^{±3} about the
// box centre (render/node_spread.h).
PIC_CONST(float, kExponentialSpreadCap, 3.0f);
// ln Z of an exponential spread lies in [0, kConcentrationRange]: with Σ|slope| ≤ 3 and
// a_k ≤ √3·halfExtent_k it is at most ln(sinh(3√3) / (3√3)) < 2.9.
PIC_CONST(float, kConcentrationRange, 4.0f);
// An axis along which a node's variance is below this share of its total is flat: an
// exponential spread takes no slope along it.
PIC_CONST(float, kFlatVariance, 1e-3f);
// A flat node's spread turns exponential where the limiter keeps less than this share of the
// fitted gradient in some channel: its flux is concentrated further than a line can follow.
// Where the limiter keeps more, the line is close (the furnished rooms' blotch index is the
// same with the limit at 1 and at 0.5) and the links read it at less cost.
PIC_CONST(float, kExponentialLimit, 0.5f);
// An exponential spread's normaliser ln Z assumes the node's surfels lie evenly over
// a_k = √3·σ_k about their centroid along each axis. A channel whose flux centroid lies
// further than kExponentialReach·a_k from it contradicts that box model (an even rectangle's
// surfels reach a_k, a disc's 1.15·a_k): the node keeps its limited line. (Exponential, a
// flat node of sparse clumps 3.5 m long, lit at its far end, read 10.8 × at a cache of the
// living room baked with seed 3.)
PIC_CONST(float, kExponentialReach, 1.25f);

struct PullPush {
    uint first;        // level mode: the level is nodes [first, end); tail mode: levels
    uint end;          // [first, end), level k being nodes [levelOffsets[k − 1], levelOffsets[k])
    uint surfelCount;  // nS: inner node n is pullNodes[n − nS]
    uint pad0;
};
PIC_STRUCT_CHECK(PullPush, 16);

PIC_NAMESPACE_END

#endif
