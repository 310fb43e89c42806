#pragma once
/// Line and scatter charts as PNG for the benchmarks' speed and accuracy trade-offs
/// (ARCHITECTURE §5: picbench writes JSON plus PNG charts): axes with ticks, a polyline and/or
/// markers per series, an optional label per point, a legend; one chart or several panels per
/// image. Drawn with PLplot's pngcairo driver (Debian: libplplot-dev, plplot-driver-cairo).

#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "core/error.h"

namespace pic {

struct ChartSeries {
    std::string name;                 ///< legend entry (empty: not in the legend)
    glm::vec3 color{0.0f};            ///< sRGB in [0, 1]
    std::vector<glm::dvec2> points;   ///< in data units, drawn in order
    std::vector<std::string> labels;  ///< empty, or one per point, written beside it
    bool dashed = false;              ///< for goals and references: a dashed line, no markers
    bool connected = true;            ///< false: markers only, a scatter of unordered points
};

struct Chart {
    std::string title;
    std::string xLabel;
    std::string yLabel;
    bool logX = false;      ///< logarithmic x axis (x > 0)
    bool logY = false;      ///< logarithmic y axis (y > 0); yFromZero does not apply to it
    bool yFromZero = true;  ///< the y axis starts at 0 (else at the smallest value)
    std::vector<ChartSeries> series;
};

/// Height in pixels of the overall title band above the panels of writeCharts.
inline constexpr int kChartsTitleHeight = 48;

/// Writes `chart` as a `width` × `height` PNG, atomically (temporary file, then rename).
/// InvalidInput when it has no point, a non-finite value, x ≤ 0 on a log x axis, y ≤ 0 on a
/// log y axis, or the size leaves no room to plot; NotFound when PLplot's pngcairo driver is
/// missing; Io when the file cannot be written.
Result<void> writeChart(const Chart& chart, const std::string& path, int width = 900,
                        int height = 560);

/// Writes `panels` into one PNG, left to right then top to bottom in `columns` columns of
/// `panelWidth` × `panelHeight` pixels, under `title` in a band kChartsTitleHeight pixels
/// high: min(columns, n) × panelWidth by rows × panelHeight + kChartsTitleHeight. Errors as
/// writeChart's, and InvalidInput for no panel or columns < 1.
Result<void> writeCharts(const std::vector<Chart>& panels, const std::string& title,
                         const std::string& path, int columns = 2, int panelWidth = 700,
                         int panelHeight = 480);

/// Indices of the points on the lower-left Pareto front (no other point has x ≤ and y ≤ with
/// one of them strict), by increasing x; of equal points the first is kept; non-finite points
/// are never on it.
std::vector<size_t> paretoFront(std::span<const glm::dvec2> points);

}  // namespace pic
