#pragma once
/// Light-map charts (paper 000 §4.4): every triangle gets UVs in one atlas, either from its
/// primitive's TEXCOORD_1 layout or from planar charts that picbake generates, packed with a
/// gutter so that bilinear lookups never read another chart's texels.

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "core/bake_data.h"
#include "core/error.h"
#include "core/scene.h"

namespace pic {

/// How charts are generated and packed.
struct LightmapChartParams {
    float texelSize = 0.0f;         ///< metres per texel (> 0)
    uint32_t padding = 1;           ///< texels of margin on every side of a chart (≥ 1)
    uint32_t maxAtlasSize = 16384;  ///< largest atlas width and height in texels
};

/// One chart's rectangle in the atlas, its padding included. Rectangles never overlap;
/// a chart's triangles lie inside its rectangle shrunk by the padding.
struct LightmapChart {
    uint32_t x = 0;        ///< first texel column
    uint32_t y = 0;        ///< first texel row
    uint32_t width = 0;    ///< texels, padding included
    uint32_t height = 0;   ///< texels, padding included
    bool fromUv1 = false;  ///< one primitive's TEXCOORD_1 layout, else a generated planar chart
};

/// The light-map atlas: UVs for every scene triangle and the chart each belongs to.
/// Texel (x, y) covers UV [x, x+1]/width × [y, y+1]/height; its centre is at +0.5.
struct LightmapCharts {
    uint32_t width = 0;                   ///< atlas texels along u
    uint32_t height = 0;                  ///< atlas texels along v
    float texelSize = 0.0f;               ///< metres per texel the charts were built for
    uint32_t padding = 0;                 ///< texels of margin around each chart
    std::vector<glm::vec2> triangleUvs;   ///< 3 per scene triangle, atlas UV in [0,1]²
    std::vector<uint32_t> triangleChart;  ///< index into `charts` per scene triangle
    std::vector<LightmapChart> charts;    ///< generated charts and TEXCOORD_1 charts
    uint32_t chartCount = 0;              ///< generated planar charts
    uint32_t uv1Primitives = 0;           ///< primitives laid out by their TEXCOORD_1
};

/// Builds and packs the light-map charts of a scene. Primitives with a usable TEXCOORD_1
/// keep its layout (one chart per primitive, scaled to the texel size); all other triangles
/// are grouped into planar charts of edge-connected triangles facing the same way. Fails
/// with InvalidInput on bad parameters or when the atlas would exceed maxAtlasSize².
Result<LightmapCharts> buildLightmapCharts(const Scene& scene, const LightmapChartParams& params);

/// Packs the atlas again with only the charts whose `keep` flag is set (they move by whole
/// texels, so their texel layout on the surface is unchanged); the triangles of the other
/// charts get kNotLightmapped UVs and those charts an empty rectangle. Returns how many
/// triangles were dropped from the light map.
uint32_t repackLightmapCharts(LightmapCharts& charts, const std::vector<uint8_t>& keep);

}  // namespace pic
