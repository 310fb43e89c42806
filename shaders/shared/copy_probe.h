#ifndef PIC_SHADERS_SHARED_COPY_PROBE_H
#define PIC_SHADERS_SHARED_COPY_PROBE_H
// Copy probe: the device memory bandwidth a compute shader sees, the floor the benchmark
// compares cache lighting with on a GPU (render/copy_probe.cpp).
#include "glue.h"

PIC_NAMESPACE_BEGIN

PIC_CONST(uint, kCopyProbeGroup, 256u);

struct CopyProbePush {
    uint words;  // uvec4 words to copy
    uint pad0;
    uint pad1;
    uint pad2;
};
PIC_STRUCT_CHECK(CopyProbePush, 16);

PIC_NAMESPACE_END

#endif
