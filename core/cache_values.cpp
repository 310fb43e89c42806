#include "core/cache_values.h"

#include <algorithm>

#include "core/color.h"
#include "core/error.h"
#include "core/sh.h"

namespace pic {
namespace {

/// Collects a stencil's neighbours, then renormalises their weights.
struct StencilBuilder {
    CacheStencil stencil;

    /// Adds a neighbour; neighbours without a cache take no weight.
    void add(uint32_t cacheIndex, float w) {
        if (cacheIndex == kNoCache) return;
        stencil.cache[stencil.count] = cacheIndex;
        stencil.weight[stencil.count] = w;
        ++stencil.count;
    }

    /// The weights are renormalised over the caches that exist; when all of those carry zero
    /// weight (the point sits exactly on a missing vertex or texel, whose own weight is 1)
    /// they are averaged equally instead, so that such a point still sees the radiance of its
    /// neighbours rather than a black speck.
    CacheStencil finish() const {
        CacheStencil out = stencil;
        float total = 0.0f;
        for (int k = 0; k < out.count; ++k) total += out.weight[k];
        for (int k = 0; k < out.count; ++k)
            out.weight[k] = total > 0.0f ? out.weight[k] / total : 1.0f / float(out.count);
        return out;
    }
};

/// Lower vertex index and fraction along one grid axis of a (clamped) vertex coordinate.
void gridAxis(float coordinate, uint32_t vertices, uint32_t& lower, float& fraction) {
    if (vertices < 2) {
        lower = 0;
        fraction = 0.0f;
        return;
    }
    // Points outside the grid take the value of the nearest point on its boundary (the
    // negated comparison also sends NaN to vertex 0 rather than into an out-of-range index).
    const float c = !(coordinate > 0.0f) ? 0.0f : std::min(coordinate, float(vertices - 1));
    lower = std::min(uint32_t(c), vertices - 2);
    fraction = c - float(lower);
}

}  // namespace

CacheValues CacheValues::zeros(size_t caches, uint32_t bandsY, uint32_t bandsC) {
    PIC_CHECK(bandsC <= bandsY && bandsY <= uint32_t(kMaxShBands));
    CacheValues values;
    values.bandsY = bandsY;
    values.bandsC = bandsC;
    values.y.assign(caches * bandsY * bandsY, 0.0f);
    values.co.assign(caches * bandsC * bandsC, 0.0f);
    values.cg.assign(caches * bandsC * bandsC, 0.0f);
    return values;
}

CacheStencil gridStencil(const BakeData& bake, const glm::vec3& position) {
    const GridLayout& grid = bake.grid;
    StencilBuilder stencil;
    if (grid.cellSize > 0.0f && !grid.cacheIndex.empty()) {
        const glm::vec3 p = (position - grid.origin) / grid.cellSize;
        uint32_t lower[3];
        float fraction[3];
        for (int a = 0; a < 3; ++a) gridAxis(p[a], grid.dims[a], lower[a], fraction[a]);
        for (uint32_t corner = 0; corner < 8; ++corner) {
            uint32_t v[3];
            float w = 1.0f;
            bool exists = true;
            for (int a = 0; a < 3; ++a) {
                const uint32_t upper = (corner >> a) & 1u;
                // A one-vertex axis has no upper neighbour.
                exists = exists && !(upper && grid.dims[a] < 2);
                v[a] = lower[a] + upper;
                w *= upper ? fraction[a] : 1.0f - fraction[a];
            }
            if (!exists) continue;
            const size_t index = v[0] + size_t{grid.dims.x} * (v[1] + size_t{grid.dims.y} * v[2]);
            stencil.add(grid.cacheIndex[index], w);
        }
    }
    return stencil.finish();
}

RadianceSh lookupGridRadiance(const BakeData& bake, const CacheValues& values,
                              const glm::vec3& position) {
    return blendCaches(values, gridStencil(bake, position));
}

CacheStencil surfaceStencil(const BakeData& bake, uint32_t triangle, float b1, float b2,
                            const glm::vec3& position) {
    const LightmapLayout& map = bake.lightmap;
    const size_t first = size_t{triangle} * 3;
    if (first + 2 >= map.triangleUvs.size() || map.triangleUvs[first].x == kNotLightmapped ||
        map.width == 0 || map.height == 0)
        return gridStencil(bake, position);

    const glm::vec2 uv = (1.0f - b1 - b2) * map.triangleUvs[first] +
                         b1 * map.triangleUvs[first + 1] + b2 * map.triangleUvs[first + 2];
    // Texel centres sit at (x + 0.5, y + 0.5) in texel units.
    const glm::vec2 p = uv * glm::vec2(float(map.width), float(map.height)) - 0.5f;
    const glm::vec2 base = glm::floor(p);
    const glm::vec2 f = p - base;
    StencilBuilder stencil;
    for (int dy = 0; dy < 2; ++dy) {
        for (int dx = 0; dx < 2; ++dx) {
            const float x = base.x + float(dx);
            const float y = base.y + float(dy);
            // Texels outside the atlas do not exist: they take no weight.
            if (!(x >= 0.0f && y >= 0.0f && x < float(map.width) && y < float(map.height)))
                continue;
            const float w = (dx ? f.x : 1.0f - f.x) * (dy ? f.y : 1.0f - f.y);
            stencil.add(map.cacheIndex[size_t(x) + size_t{map.width} * size_t(y)], w);
        }
    }
    return stencil.finish();
}

RadianceSh lookupSurfaceRadiance(const BakeData& bake, const CacheValues& values, uint32_t triangle,
                                 float b1, float b2, const glm::vec3& position) {
    return blendCaches(values, surfaceStencil(bake, triangle, b1, b2, position));
}

RadianceSh blendCaches(const CacheValues& values, const CacheStencil& stencil) {
    RadianceSh out;
    out.bands = values.bandsY;
    // Interpolate in YCoCg first (the conversion is linear), then convert once per coefficient.
    const size_t countY = shCount(int(values.bandsY));
    const size_t countC = shCount(int(values.bandsC));
    float y[shCount(kMaxShBands)] = {};
    float co[shCount(kMaxShBands)] = {};
    float cg[shCount(kMaxShBands)] = {};
    for (int k = 0; k < stencil.count; ++k) {
        const size_t cache = stencil.cache[k];
        PIC_DCHECK(cache < values.cacheCount());
        const float w = stencil.weight[k];
        const float* srcY = values.y.data() + cache * countY;
        for (size_t i = 0; i < countY; ++i) y[i] += w * srcY[i];
        const float* srcCo = values.co.data() + cache * countC;
        const float* srcCg = values.cg.data() + cache * countC;
        for (size_t i = 0; i < countC; ++i) {
            co[i] += w * srcCo[i];
            cg[i] += w * srcCg[i];
        }
    }
    // Chroma bands above lC are not stored; they take band 0's chroma per luma, so that the
    // luma's higher bands change the light's strength by direction but not its colour (kept
    // grey, they would add white light where luma rises and take it where it falls).
    const glm::vec2 ratio = chromaPerLuma({y[0], co[0], cg[0]});
    for (size_t i = countC; i < countY; ++i) {
        co[i] = ratio.x * y[i];
        cg[i] = ratio.y * y[i];
    }
    for (size_t i = 0; i < countY; ++i) {
        const glm::vec3 rgb = yCoCgToRgb(glm::vec3(y[i], co[i], cg[i]));
        out.rgb[0][i] = rgb.r;
        out.rgb[1][i] = rgb.g;
        out.rgb[2][i] = rgb.b;
    }
    return out;
}

void scaleLumaChroma(RadianceSh& radiance, float y, float cocg) {
    const int count = int(shCount(int(radiance.bands)));
    for (int i = 0; i < count; ++i) {
        glm::vec3 v = rgbToYCoCg({radiance.rgb[0][i], radiance.rgb[1][i], radiance.rgb[2][i]});
        v *= glm::vec3(y, cocg, cocg);
        const glm::vec3 rgb = yCoCgToRgb(v);
        radiance.rgb[0][i] = rgb.r;
        radiance.rgb[1][i] = rgb.g;
        radiance.rgb[2][i] = rgb.b;
    }
}

glm::vec3 irradiance(const RadianceSh& radiance, const glm::vec3& normal) {
    glm::vec3 e;
    for (int c = 0; c < 3; ++c) e[c] = shIrradiance(int(radiance.bands), radiance.rgb[c], normal);
    return e;
}

}  // namespace pic
