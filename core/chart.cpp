#include "core/chart.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

namespace pic {

namespace {

namespace OIIO = OIIO_NAMESPACE;

/// Round tick steps (1, 2, 5 × 10^k) giving about `count` ticks over [lo, hi].
std::vector<double> linearTicks(double lo, double hi, int count) {
    const double raw = (hi - lo) / std::max(1, count);
    const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
    double step = magnitude;
    for (double factor : {1.0, 2.0, 5.0, 10.0})
        if (factor * magnitude >= raw) {
            step = factor * magnitude;
            break;
        }
    std::vector<double> ticks;
    for (double t = std::ceil(lo / step) * step; t <= hi + 1e-9 * step; t += step) ticks.push_back(t);
    return ticks;
}

/// Shortest readable form of a tick value.
std::string tickText(double value) {
    char text[32];
    if (std::abs(value) >= 1e5 || (std::abs(value) < 1e-3 && value != 0.0))
        std::snprintf(text, sizeof text, "%.0e", value);
    else if (std::abs(value) >= 100.0)
        std::snprintf(text, sizeof text, "%.0f", value);
    else
        std::snprintf(text, sizeof text, "%.3g", value);  // data-valued ticks: 34.8, not 34.7887
    return text;
}

}  // namespace

Result<void> writeChart(const Chart& chart, const std::string& path, int width, int height) {
    glm::dvec2 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
    size_t points = 0;
    for (const ChartSeries& series : chart.series)
        for (const glm::dvec2& p : series.points) {
            if (!std::isfinite(p.x) || !std::isfinite(p.y))
                return fail(ErrorCode::InvalidInput, "chart \"{}\": series \"{}\" has a non-finite point",
                            chart.title, series.name);
            if (chart.logX && !(p.x > 0.0))
                return fail(ErrorCode::InvalidInput, "chart \"{}\": x = {} on a log axis", chart.title, p.x);
            lo = glm::min(lo, p);
            hi = glm::max(hi, p);
            ++points;
        }
    if (points == 0) return fail(ErrorCode::InvalidInput, "chart \"{}\" has no point", chart.title);
    if (!std::filesystem::exists(kChartFont))
        return fail(ErrorCode::NotFound, "the chart font {} is missing (Debian: fonts-dejavu-core)",
                    kChartFont);

    // Data range with a margin; y from zero unless asked otherwise.
    if (chart.yFromZero) lo.y = std::min(lo.y, 0.0);
    if (hi.y <= lo.y) hi.y = lo.y + 1.0;
    hi.y += 0.08 * (hi.y - lo.y);
    double x0 = chart.logX ? std::log2(lo.x) : lo.x, x1 = chart.logX ? std::log2(hi.x) : hi.x;
    if (x1 <= x0) {
        x0 -= 0.5;
        x1 += 0.5;
    }
    const double pad = 0.05 * (x1 - x0);
    x0 -= pad;
    x1 += pad;

    bool labelled = false;
    for (const ChartSeries& series : chart.series) labelled = labelled || !series.labels.empty();
    // Legend: rows under the title, outside the plot, so that it hides no point; an entry
    // that would run past the right edge starts a new row.
    constexpr int kLegendRow = 22;
    const int left = 90, right = labelled ? 110 : 30, bottom = 70;
    std::vector<glm::ivec2> legendAt;  // per series: x and the row's baseline
    {
        int x = left, y = 57;
        for (const ChartSeries& series : chart.series) {
            const OIIO::ROI extent = OIIO::ImageBufAlgo::text_size(series.name, 14, kChartFont);
            const int entry = 24 + (extent.defined() ? extent.width() : 8 * int(series.name.size()));
            if (x > left && x + entry > width - 12) {
                x = left;
                y += kLegendRow;
            }
            legendAt.push_back({x, y});
            x += entry + 28;
        }
    }
    const int top = 92 + (legendAt.empty() ? 0 : legendAt.back().y - 57);
    const int plotW = width - left - right, plotH = height - top - bottom;
    if (plotW < 100 || plotH < 100)
        return fail(ErrorCode::InvalidInput, "chart size {}x{} is too small", width, height);
    const auto toPixel = [&](glm::dvec2 p) {
        const double x = chart.logX ? std::log2(p.x) : p.x;
        return glm::ivec2(left + int(std::lround((x - x0) / (x1 - x0) * plotW)),
                          top + plotH - int(std::lround((p.y - lo.y) / (hi.y - lo.y) * plotH)));
    };

    OIIO::ImageBuf image(OIIO::ImageSpec(width, height, 3, OIIO::TypeDesc::FLOAT));
    const float white[] = {1.0f, 1.0f, 1.0f}, black[] = {0.0f, 0.0f, 0.0f};
    const float grey[] = {0.85f, 0.85f, 0.85f}, dark[] = {0.3f, 0.3f, 0.3f};
    OIIO::ImageBufAlgo::fill(image, white);
    const auto text = [&](int x, int y, const std::string& s, int size, const float* color,
                          OIIO::ImageBufAlgo::TextAlignX alignX = OIIO::ImageBufAlgo::TextAlignX::Left,
                          OIIO::ImageBufAlgo::TextAlignY alignY = OIIO::ImageBufAlgo::TextAlignY::Baseline) {
        OIIO::ImageBufAlgo::render_text(image, x, y, s, size, kChartFont, OIIO::cspan<float>(color, 3),
                                        alignX, alignY);
    };

    // Grid and ticks.
    for (double t : linearTicks(lo.y, hi.y, 6)) {
        const int y = toPixel({chart.logX ? hi.x : x0, t}).y;
        if (y < top || y > top + plotH) continue;
        OIIO::ImageBufAlgo::render_line(image, left, y, left + plotW, y, OIIO::cspan<float>(grey, 3));
        text(left - 8, y, tickText(t), 14, dark, OIIO::ImageBufAlgo::TextAlignX::Right, OIIO::ImageBufAlgo::TextAlignY::Center);
    }
    std::vector<double> xTicks;
    if (chart.logX) {
        for (const ChartSeries& series : chart.series)
            for (const glm::dvec2& p : series.points) xTicks.push_back(p.x);
        std::sort(xTicks.begin(), xTicks.end());
        xTicks.erase(std::unique(xTicks.begin(), xTicks.end()), xTicks.end());
        // A few distinct x (subscriber counts) are ticks themselves; many (scattered
        // timings) would overprint, so those get 1-2-5 ticks per decade.
        if (xTicks.size() > 8) {
            xTicks.clear();
            const double from = std::exp2(x0), to = std::exp2(x1);
            for (double decade = std::pow(10.0, std::floor(std::log10(from))); decade <= to;
                 decade *= 10.0)
                for (const double m : {1.0, 2.0, 5.0})
                    if (m * decade >= from && m * decade <= to) xTicks.push_back(m * decade);
        }
    } else {
        xTicks = linearTicks(x0, x1, 7);
    }
    for (double t : xTicks) {
        const int x = toPixel({t, lo.y}).x;
        if (x < left || x > left + plotW) continue;
        OIIO::ImageBufAlgo::render_line(image, x, top, x, top + plotH, OIIO::cspan<float>(grey, 3));
        text(x, top + plotH + 20, tickText(t), 14, dark, OIIO::ImageBufAlgo::TextAlignX::Center);
    }
    OIIO::ImageBufAlgo::render_box(image, left, top, left + plotW, top + plotH, OIIO::cspan<float>(black, 3));

    // Series: polylines (dashed ones in segments; none for a scatter), markers, point labels.
    for (const ChartSeries& series : chart.series) {
        const float color[] = {series.color.r, series.color.g, series.color.b};
        for (size_t i = 0; series.connected && i + 1 < series.points.size(); ++i) {
            const glm::ivec2 a = toPixel(series.points[i]), b = toPixel(series.points[i + 1]);
            if (!series.dashed) {
                for (int d = -1; d <= 1; ++d)
                    OIIO::ImageBufAlgo::render_line(image, a.x, a.y + d, b.x, b.y + d, OIIO::cspan<float>(color, 3));
                continue;
            }
            const double length = glm::length(glm::dvec2(b - a));
            const int dashes = std::max(1, int(length / 12.0));
            for (int k = 0; k < dashes; k += 2) {
                const glm::dvec2 p = glm::dvec2(a) + (glm::dvec2(b - a) * double(k)) / double(dashes);
                const glm::dvec2 q = glm::dvec2(a) + (glm::dvec2(b - a) * double(k + 1)) / double(dashes);
                OIIO::ImageBufAlgo::render_line(image, int(p.x), int(p.y), int(q.x), int(q.y), OIIO::cspan<float>(color, 3));
            }
        }
        for (size_t i = 0; i < series.points.size(); ++i) {
            const glm::ivec2 p = toPixel(series.points[i]);
            if (!series.dashed)
                OIIO::ImageBufAlgo::render_box(image, p.x - 3, p.y - 3, p.x + 3, p.y + 3, OIIO::cspan<float>(color, 3), true);
            if (i < series.labels.size() && !series.labels[i].empty())
                text(p.x + 8, p.y - 8, series.labels[i], 13, color);
        }
    }

    // Title, axis labels, legend.
    text(width / 2, 28, chart.title, 18, black, OIIO::ImageBufAlgo::TextAlignX::Center);
    text(left + plotW / 2, height - 18, chart.xLabel + (chart.logX ? " (log scale)" : ""), 15,
         black, OIIO::ImageBufAlgo::TextAlignX::Center);
    text(12, top - 10, chart.yLabel, 15, black);
    for (size_t i = 0; i < chart.series.size(); ++i) {
        const ChartSeries& series = chart.series[i];
        const float color[] = {series.color.r, series.color.g, series.color.b};
        const glm::ivec2 at = legendAt[i];
        OIIO::ImageBufAlgo::render_box(image, at.x, at.y - 9, at.x + 18, at.y - 3,
                                       OIIO::cspan<float>(color, 3), true);
        text(at.x + 24, at.y, series.name, 14, black);
    }

    const std::string temp = path + ".tmp.png";
    OIIO::ImageSpec spec = image.spec();
    spec.set_format(OIIO::TypeDesc::UINT8);
    if (!image.write(temp, OIIO::TypeDesc::UINT8) ||
        std::rename(temp.c_str(), path.c_str()) != 0) {
        std::remove(temp.c_str());
        return fail(ErrorCode::Io, "cannot write chart {}: {}", path, image.geterror());
    }
    return {};
}

}  // namespace pic
