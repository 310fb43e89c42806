#include "render/cpu/sky_caches.h"

#include "core/error.h"
#include "core/parallel.h"
#include "core/sh.h"

namespace pic {
namespace {

/// out[i] += Σ_k weights[i·nV + k]·visibility[k] for i < rows.
void addRows(const float* weights, int rows, const float* visibility, int nV, float* out) {
    for (int i = 0; i < rows; ++i) {
        const float* w = weights + size_t(i) * size_t(nV);
        float sum = 0.0f;
        for (int k = 0; k < nV; ++k) sum += w[k] * visibility[k];
        out[i] += sum;
    }
}

}  // namespace

void addSkyToCaches(const BakeData& bake, const SkyCacheWeights& weights, CacheValues& values) {
    const int nY = shCount(int(values.bandsY)), nC = shCount(int(values.bandsC));
    const int nV = shCount(weights.visibilityBands);
    const size_t caches = bake.caches.size();
    PIC_CHECK(weights.bandsY == int(values.bandsY) && weights.bandsC == int(values.bandsC));
    PIC_CHECK_EQ(bake.cacheSky.size(), caches * size_t(nV));
    PIC_CHECK_EQ(values.cacheCount(), caches);
    parallelFor(0, caches, [&](size_t c) {
        const float* v = &bake.cacheSky[c * size_t(nV)];
        addRows(weights.y.data(), nY, v, nV, &values.y[c * size_t(nY)]);
        addRows(weights.co.data(), nC, v, nV, &values.co[c * size_t(nC)]);
        addRows(weights.cg.data(), nC, v, nV, &values.cg[c * size_t(nC)]);
    }, 256);
}

}  // namespace pic
