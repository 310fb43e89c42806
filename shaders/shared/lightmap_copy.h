#ifndef PIC_SHADERS_SHARED_LIGHTMAP_COPY_H
#define PIC_SHADERS_SHARED_LIGHTMAP_COPY_H
// Light-map copy (paper 000 Figure 2 step 5): caches → coefficient-major texture layers
// (core/cache_textures.h describes the layout). Specialization constants: 0 lY, 1 lC.
#include "glue.h"

PIC_NAMESPACE_BEGIN

PIC_CONST(uint, kLightmapCopyGroup, 256u);

struct LightmapCopyPush {
    uint texelCount;  // grid vertices or light-map texels
    uint pad0;
    uint pad1;
    uint pad2;
};
PIC_STRUCT_CHECK(LightmapCopyPush, 16);

PIC_NAMESPACE_END

#endif
