#ifndef PIC_SHADERS_SHARED_PULL_H
#define PIC_SHADERS_SHARED_PULL_H
// Pull (paper 000 Figure 2 step 3): one dispatch per hierarchy level. Besides the float flux
// it writes each inner node's radiance Φ / (π·A) as RGBE8 (paper 000 §4.7), which cache
// lighting reads.
#include "glue.h"

PIC_NAMESPACE_BEGIN

PIC_CONST(uint, kPullGroup, 64u);

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

struct PullPush {
    uint firstNode;     // the level is nodes [firstNode, endNode)
    uint endNode;
    uint surfelCount;  // nS: inner node n is pullNodes[n − nS]
    uint pad0;
};
PIC_STRUCT_CHECK(PullPush, 16);

PIC_NAMESPACE_END

#endif
