#ifndef PIC_SHADERS_SHARED_SH_TABLES_H
#define PIC_SHADERS_SHARED_SH_TABLES_H
// The constants shaders need to evaluate core/sh.h's real SH basis and its clamped-cosine
// convolution (filled from pic::shRecurrence and pic::clampedCosineZonal).
#include "glue.h"

PIC_NAMESPACE_BEGIN

PIC_CONST(uint, kShMaxBands, 8u);

// A uniform buffer (std140: float arrays packed four to a vec4, so that the layout is the
// same tight one in C++): element k of an array is [k / 4][k % 4].
struct ShTables {
    vec4 diagonal[2];       // Q_m^m
    vec4 a[16];             // [l·8 + m]: Q_l^m = a·z·Q_{l−1}^m − b·Q_{l−2}^m
    vec4 b[16];             // [l·8 + m]
    vec4 clampedCosine[2];  // K_l of max(0, cos θ): π, 2π/3, π/4, 0, …
};
PIC_STRUCT_CHECK(ShTables, 576);

PIC_NAMESPACE_END

#endif
