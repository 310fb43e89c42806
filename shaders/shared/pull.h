#ifndef PIC_SHADERS_SHARED_PULL_H
#define PIC_SHADERS_SHARED_PULL_H
// Pull (paper 000 Figure 2 step 3): one dispatch per hierarchy level.
#include "glue.h"

PIC_NAMESPACE_BEGIN

PIC_CONST(uint, kPullGroup, 64u);

struct PullPush {
    uint firstNode;     // the level is nodes [firstNode, endNode)
    uint endNode;
    uint surfelCount;   // nS: inner node n has its children at children[n − nS]
    uint pad0;
};
PIC_STRUCT_CHECK(PullPush, 16);

PIC_NAMESPACE_END

#endif
