#ifndef PIC_SHADERS_SHARED_SKY_CACHES_H
#define PIC_SHADERS_SHARED_SKY_CACHES_H
// Sky caches (core/sky.h): after the last bounce each cache adds the sky it sees, c_i += Σ_k
// W_ik v_k per YCoCg channel. Specialization constants: 0 lY, 1 lC, 2 the visibility's bands.
#include "glue.h"

PIC_NAMESPACE_BEGIN

PIC_CONST(uint, kSkyCachesGroup, 64u);
// The weights' uniform buffer in vec4s: (lY² + 2·lC²)·nV floats, at most (64 + 128)·64.
PIC_CONST(uint, kMaxSkyWeightVec4s, 3072u);

struct SkyCachesPush {
    uint cacheCount;
    uint pad0;
    uint pad1;
    uint pad2;
};
PIC_STRUCT_CHECK(SkyCachesPush, 16);

PIC_NAMESPACE_END

#endif
