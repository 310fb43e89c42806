#ifndef PIC_SHADERS_SHARED_CACHE_LIGHTING_H
#define PIC_SHADERS_SHARED_CACHE_LIGHTING_H
// Cache lighting (paper 000 Figure 2 step 4, eq. 3, §4.6, §4.8). Specialization constants:
// 0 lY, 1 lC, 2 nL, 3 link form (kLinkFormSh / kLinkFormRtp), 4 mapping (kCachePerInvocation
// / kCachePerSubgroup). Links are stored sequentially per cache; a dispatch covers one chunk
// of caches whose links fit one storage binding.
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

struct CacheLightingPush {
    uint firstCache;  // the chunk is caches [firstCache, firstCache + cacheCount)
    uint cacheCount;
    uint pad0;
    uint pad1;
};
PIC_STRUCT_CHECK(CacheLightingPush, 16);

PIC_NAMESPACE_END

#endif
