#ifndef PIC_SHADERS_SHARED_PULL_H
#define PIC_SHADERS_SHARED_PULL_H
// Pull (paper 000 Figure 2 step 3): one dispatch per hierarchy level. Besides the float flux
// it writes each inner node's radiance Φ / (π·A) as RGBE8 (paper 000 §4.7), which cache
// lighting reads.
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

// An inner node as the pull reads it: one RGBA32UI texel. The pull reads the inner nodes and
// the children's flux as uniform texel buffers, gathers on lavapipe rather than a branch per
// lane (shared/cache_lighting.h).
struct PullNode {
    uint left;  // child nodes
    uint right;
    float radianceScale;  // 1 / (π · area): flux W → radiance W/(m²·sr) of a Lambertian node
    uint pad0;
};
PIC_STRUCT_CHECK(PullNode, 16);
#ifndef __cplusplus
// Inner node i of a uniform texel buffer of RGBA32UI texels, one per record.
PullNode fetchPullNode(usamplerBuffer records, uint i) {
    const uvec4 t = texelFetch(records, int(i));
    return PullNode(t.x, t.y, uintBitsToFloat(t.z), t.w);
}
#endif

struct PullPush {
    uint first;        // level mode: the level is nodes [first, end); tail mode: levels
    uint end;          // [first, end), level k being nodes [levelOffsets[k − 1], levelOffsets[k])
    uint surfelCount;  // nS: inner node n is pullNodes[n − nS]
    uint pad0;
};
PIC_STRUCT_CHECK(PullPush, 16);

PIC_NAMESPACE_END

#endif
