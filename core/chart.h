#pragma once
/// Line charts as PNG for the benchmarks' speed and accuracy trade-offs (ARCHITECTURE §5:
/// picbench writes JSON plus PNG charts): axes with ticks, one polyline with markers per
/// series, an optional label per point, a legend. Drawn with OpenImageIO, text in DejaVu Sans
/// (Debian's fonts-dejavu-core).

#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "core/error.h"

namespace pic {

struct ChartSeries {
    std::string name;                 ///< legend entry
    glm::vec3 color{0.0f};            ///< sRGB in [0, 1]
    std::vector<glm::dvec2> points;   ///< in data units, drawn in order
    std::vector<std::string> labels;  ///< empty, or one per point, written beside it
    bool dashed = false;              ///< for goals and references
    bool connected = true;            ///< false: markers only, a scatter of unordered points
};

struct Chart {
    std::string title;
    std::string xLabel;
    std::string yLabel;
    bool logX = false;     ///< logarithmic x axis (x > 0)
    bool yFromZero = true; ///< the y axis starts at 0 (else at the smallest value)
    std::vector<ChartSeries> series;
};

/// The font the charts use.
inline constexpr const char* kChartFont = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";

/// Writes `chart` as a `width` × `height` PNG, atomically. InvalidInput when it has no point,
/// a non-finite value, or x ≤ 0 on a log axis; NotFound when the font is missing; Io when the
/// file cannot be written.
Result<void> writeChart(const Chart& chart, const std::string& path, int width = 900,
                        int height = 560);

}  // namespace pic
