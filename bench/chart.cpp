#include "bench/chart.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <mutex>

#include <fcntl.h>
#include <unistd.h>

#include <plstream.h>

namespace pic {

namespace {

namespace fs = std::filesystem;

// Colour map 0 slots: PLplot colours by index, slot 0 is the background.
constexpr PLINT kWhite = 0, kInk = 1, kGrid = 2, kTickInk = 3, kFirstSeries = 4;

// PLplot line styles (pllsty): 3 is evenly spaced long dashes.
constexpr PLINT kSolid = 1, kDashed = 3;

// Markers are a glyph (U+25CF, in DejaVu Sans) so that plstring sizes them with the text.
constexpr const char* kMarker = "\u25CF";

// Text sizes relative to a panel's base character height.
constexpr double kTitleScale = 1.15, kTickScale = 0.85, kLegendScale = 0.9, kPointLabelScale = 0.75,
                 kMarkerScale = 0.65, kPageTitleScale = 1.3;

/// A rectangle in pixels from the page's bottom-left corner.
struct Rect {
    double x0 = 0.0, y0 = 0.0, x1 = 0.0, y1 = 0.0;
    double width() const { return x1 - x0; }
    double height() const { return y1 - y0; }
};

/// One axis: its world range (log10 of the data on a log axis) and its labelled ticks.
struct Axis {
    bool log = false;
    double lo = 0.0, hi = 1.0;
    std::vector<double> ticks;        // world units
    std::vector<std::string> labels;  // PLplot text, one per tick
    double fraction(double world) const { return (world - lo) / (hi - lo); }
};

/// Where everything of one panel goes.
struct PanelLayout {
    Rect panel, plot;
    double ch = 12.0;  // base character height (PLplot: of capitals), pixels
    Axis x, y;
    int legendColumns = 1, legendRows = 0;
    double legendGap = 0.0;  // pixels from the plot's top to the legend's bottom
    double titleBaseline = 0.0, yLabelBaseline = 0.0;  // pixels above the plot's top
    double yLabelGap = 0.0;  // pixels left of the plot to the rotated y label's baseline
    double titleScale = kTitleScale, xLabelScale = 1.0, yLabelScale = 1.0;
    bool yLabelAbove = false;  // too long to run up the axis: written above the plot
};

/// PLplot reads '#' as an escape; user text must not start one.
std::string plText(const std::string& text) {
    std::string out;
    for (char c : text) {
        out += c;
        if (c == '#') out += '#';
    }
    return out;
}

/// Estimated width in pixels of `text` at character height `ch`, from DejaVu Sans' advance
/// widths per kind of glyph (PLplot's C++ binding cannot measure text).
double textWidth(const std::string& text, double ch) {
    double ems = 0.0;
    for (char c : text) {
        const auto u = static_cast<unsigned char>(c);
        if ((u & 0xC0) == 0x80) continue;  // UTF-8 continuation byte
        if (c == ' ')
            ems += 0.32;
        else if (std::isdigit(u))
            ems += 0.64;
        else if (std::isupper(u))
            ems += 0.72;
        else if (std::islower(u))
            ems += 0.58;
        else if (u < 0x80)
            ems += 0.45;  // punctuation
        else
            ems += 0.8;  // other scripts and symbols
    }
    return 1.37 * ch * ems;  // PLplot's character height is the cap height, 0.73 em
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

/// A log axis' tick label: plain numbers in [1e-3, 1e4), powers of ten outside.
std::string logTickText(double value) {
    if (value >= 1e-3 && value < 1e4) return tickText(value);
    const int exponent = int(std::floor(std::log10(value) + 1e-9));
    const double mantissa = std::round(value / std::pow(10.0, exponent) * 10.0) / 10.0;
    const std::string power = fmt::format("10#u{}#d", exponent);
    return mantissa == 1.0 ? power : fmt::format("{:g}\u00D7{}", mantissa, power);
}

/// A round step (1, 2 or 5 × 10^k) giving about `count` intervals over `span`.
double niceStep(double span, int count) {
    const double raw = span / std::max(1, count);
    const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
    for (double factor : {1.0, 2.0, 5.0})
        if (factor * magnitude >= raw * (1.0 - 1e-9)) return factor * magnitude;
    return 10.0 * magnitude;
}

/// Multiples of a round step in [lo, hi], about `count` of them.
std::vector<double> linearTicks(double lo, double hi, int count) {
    const double step = niceStep(hi - lo, count);
    std::vector<double> ticks;
    for (double k = std::ceil(lo / step - 1e-9); k * step <= hi + 1e-9 * step; k += 1.0)
        ticks.push_back(std::abs(k) < 0.5 ? 0.0 : k * step);  // exact 0, not -1e-17
    return ticks;
}

/// Tick values for a log axis over world range [lo, hi]: decades when it spans at least
/// two, else 1-2-5 per decade, else (narrower than a factor of about 2.5) a linear step.
std::vector<double> logTicks(double lo, double hi) {
    const auto within = [&](double value) {
        const double w = std::log10(value);
        return w >= lo - 1e-9 && w <= hi + 1e-9;
    };
    std::vector<double> decades, oneTwoFive;
    for (int k = int(std::floor(lo)); k <= int(std::ceil(hi)); ++k) {
        const double decade = std::pow(10.0, k);
        if (within(decade)) decades.push_back(decade);
        for (double m : {1.0, 2.0, 5.0})
            if (within(m * decade)) oneTwoFive.push_back(m * decade);
    }
    if (decades.size() >= 3) {
        // Thinned to at most 8 labels on wide ranges.
        const size_t stride = (decades.size() + 7) / 8;
        std::vector<double> kept;
        for (size_t i = 0; i < decades.size(); i += stride) kept.push_back(decades[i]);
        return kept;
    }
    if (oneTwoFive.size() >= 3) return oneTwoFive;
    std::vector<double> ticks;
    for (double t : linearTicks(std::pow(10.0, lo), std::pow(10.0, hi), 4))
        if (t > 0.0) ticks.push_back(t);
    return ticks;
}

/// Fills `axis` with ticks and labels for data values `values` (world units); `dataTicks`
/// are the values to label instead, when given.
void setTicks(Axis& axis, int count, const std::vector<double>& dataTicks) {
    std::vector<double> values;
    if (!dataTicks.empty())
        values = dataTicks;
    else if (axis.log)
        values = logTicks(axis.lo, axis.hi);
    else
        values = linearTicks(axis.lo, axis.hi, count);
    for (double v : values) {
        axis.ticks.push_back(axis.log ? std::log10(v) : v);
        axis.labels.push_back(axis.log ? logTickText(v) : tickText(v));
    }
}

/// Drops ticks whose label would overprint the previous kept one; `extent(i)` is label i's
/// half size along the axis in pixels, `length` the axis' length in pixels.
void thinTicks(Axis& axis, double length, const std::function<double(size_t)>& extent) {
    Axis kept = axis;
    kept.ticks.clear();
    kept.labels.clear();
    double end = -std::numeric_limits<double>::max();
    for (size_t i = 0; i < axis.ticks.size(); ++i) {
        const double at = axis.fraction(axis.ticks[i]) * length;
        if (at - extent(i) < end) continue;
        kept.ticks.push_back(axis.ticks[i]);
        kept.labels.push_back(axis.labels[i]);
        end = at + extent(i);
    }
    axis = std::move(kept);
}

/// InvalidInput when `chart` has no point, a non-finite value, or a value ≤ 0 on a log axis.
Result<void> checkChart(const Chart& chart) {
    size_t points = 0;
    for (const ChartSeries& series : chart.series)
        for (const glm::dvec2& p : series.points) {
            if (!std::isfinite(p.x) || !std::isfinite(p.y))
                return fail(ErrorCode::InvalidInput,
                            "chart \"{}\": series \"{}\" has a non-finite point", chart.title,
                            series.name);
            if (chart.logX && !(p.x > 0.0))
                return fail(ErrorCode::InvalidInput, "chart \"{}\": x = {} on a log axis",
                            chart.title, p.x);
            if (chart.logY && !(p.y > 0.0))
                return fail(ErrorCode::InvalidInput, "chart \"{}\": y = {} on a log axis",
                            chart.title, p.y);
            ++points;
        }
    if (points == 0) return fail(ErrorCode::InvalidInput, "chart \"{}\" has no point", chart.title);
    return {};
}

/// Markers are drawn for every series but dashed lines (goals and references).
bool hasMarkers(const ChartSeries& series) {
    return !series.dashed || !series.connected;
}

/// A panel's base character height in pixels: text grows with the panel, within readable
/// bounds (capitals 13 px high at 900 × 560).
double baseCharHeight(double width, double height) {
    return std::clamp(0.009 * (width + height), 9.0, 20.0);
}

/// The world ranges and ticks of `chart` (already checked) for a panel of `panel` pixels.
void layoutAxes(const Chart& chart, const Rect& panel, PanelLayout& layout) {
    Axis& x = layout.x;
    Axis& y = layout.y;
    x.log = chart.logX;
    y.log = chart.logY;
    glm::dvec2 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
    std::vector<double> xs;
    for (const ChartSeries& series : chart.series)
        for (const glm::dvec2& p : series.points) {
            const glm::dvec2 w(x.log ? std::log10(p.x) : p.x, y.log ? std::log10(p.y) : p.y);
            lo = glm::min(lo, w);
            hi = glm::max(hi, w);
            xs.push_back(p.x);
        }

    // x: the data with a 5 % margin each side; a single x gets a range around it.
    if (hi.x - lo.x <= 1e-12 * std::max(1.0, std::abs(hi.x))) {
        const double half = x.log ? 0.3 : (lo.x != 0.0 ? 0.1 * std::abs(lo.x) : 0.5);
        lo.x -= half;
        hi.x += half;
    }
    x.lo = lo.x - 0.05 * (hi.x - lo.x);
    x.hi = hi.x + 0.05 * (hi.x - lo.x);

    // y: from zero when asked (linear axes), with room above the highest point.
    const bool pinned = !y.log && chart.yFromZero && lo.y >= 0.0;
    if (!y.log && chart.yFromZero) {
        lo.y = std::min(lo.y, 0.0);
        hi.y = std::max(hi.y, 0.0);
    }
    if (hi.y - lo.y <= 1e-12 * std::max(1.0, std::abs(hi.y))) {
        const double half = y.log ? 0.3 : (lo.y != 0.0 ? 0.1 * std::abs(lo.y) : 0.5);
        if (!pinned) lo.y -= half;
        hi.y += half;
    }
    y.lo = pinned ? lo.y : lo.y - 0.05 * (hi.y - lo.y);
    y.hi = hi.y + 0.08 * (hi.y - lo.y);

    // A few distinct whole-number x on a log axis (subscriber counts, links per cache) are
    // ticks themselves; many, or measured values, get round ticks.
    std::sort(xs.begin(), xs.end());
    xs.erase(std::unique(xs.begin(), xs.end()), xs.end());
    const bool counts = x.log && xs.size() <= 8 && std::all_of(xs.begin(), xs.end(), [](double v) {
                            return v == std::round(v);
                        });
    setTicks(x, std::clamp(int(panel.width() / 100.0), 4, 9), counts ? xs : std::vector<double>{});
    setTicks(y, std::clamp(int(panel.height() / 60.0), 4, 8), {});
}

/// The layout of `chart` (already checked) in `panel`; InvalidInput when the panel leaves no
/// room to plot.
Result<PanelLayout> layoutPanel(const Chart& chart, const Rect& panel) {
    PanelLayout layout;
    layout.panel = panel;
    const double ch = baseCharHeight(panel.width(), panel.height());
    layout.ch = ch;
    layoutAxes(chart, panel, layout);
    const double tickCh = kTickScale * ch;
    const std::string xLabel = chart.xLabel + (chart.logX ? " (log scale)" : "");
    const std::string yLabel = chart.yLabel + (chart.logY ? " (log scale)" : "");

    // Legend: as many columns as the widest name allows, rows filled left to right.
    int named = 0;
    double nameWidth = 0.0;
    for (const ChartSeries& series : chart.series)
        if (!series.name.empty()) {
            ++named;
            nameWidth = std::max(nameWidth, textWidth(series.name, kLegendScale * ch));
        }
    if (named > 0) {
        // pllegend's columns are as wide as the longest name plus the line sample and gaps.
        const double entry = 6.0 * ch + nameWidth;
        const int fit = std::max(1, int(0.96 * panel.width() / entry));
        layout.legendRows = (named + fit - 1) / fit;
        layout.legendColumns = (named + layout.legendRows - 1) / layout.legendRows;
    }

    // Margins: left for the y tick labels and the rotated y label, bottom for the x tick
    // labels and x label, top for the title, the legend and (when long) the y label.
    double yTickWidth = 0.0;
    for (const std::string& label : layout.y.labels)
        yTickWidth = std::max(yTickWidth, textWidth(label, tickCh));
    const double legendHeight = layout.legendRows * 1.6 * ch;  // pllegend's rows, 1.6 ch apart
    const double titleCh = kTitleScale * ch;
    const double bottom = 2.4 * tickCh + 1.95 * ch;  // tick labels, x label, descenders, gap
    double right = ch;
    if (!layout.x.labels.empty())
        right = std::max(right, 0.5 * textWidth(layout.x.labels.back(), tickCh) + 0.3 * ch);
    const auto place = [&](bool yLabelAbove) {
        const bool rotated = !yLabel.empty() && !yLabelAbove;
        const double left = 0.5 * ch + (rotated ? 1.25 * ch : 0.0) + yTickWidth + 0.6 * tickCh;
        // The y label's descenders clear the top tick label, half of which is above the plot.
        double above = 0.5 * ch;
        layout.yLabelBaseline = 1.2 * ch;
        if (yLabelAbove) above = layout.yLabelBaseline + 1.3 * ch;
        layout.legendGap = above;
        above += legendHeight;
        layout.titleBaseline = above + 0.3 * ch + 0.3 * titleCh;  // room for descenders
        if (!chart.title.empty()) above = layout.titleBaseline + 1.0 * titleCh + 0.4 * ch;
        layout.plot = {panel.x0 + left, panel.y0 + bottom, panel.x1 - right, panel.y1 - above};
    };
    layout.yLabelAbove = false;
    place(false);
    if (textWidth(yLabel, ch) > layout.plot.height()) {
        layout.yLabelAbove = true;
        place(true);
    }

    // The rotated y label's baseline clears the tick labels and its descenders.
    layout.yLabelGap = yTickWidth + 0.6 * tickCh + 0.45 * ch;

    // Point labels sit right of their points: widen the right margin until the rightmost
    // ends inside the panel.
    double labelRight = right;
    const double available = panel.x1 - layout.plot.x0;
    for (const ChartSeries& series : chart.series)
        for (size_t i = 0; i < std::min(series.labels.size(), series.points.size()); ++i) {
            if (series.labels[i].empty()) continue;
            const double f =
                layout.x.fraction(chart.logX ? std::log10(series.points[i].x) : series.points[i].x);
            const double reach =
                0.5 * ch + textWidth(series.labels[i], kPointLabelScale * ch) + 0.6 * ch;
            // The label ends at plot.x0 + f·(available − r) + reach; it must end before
            // panel.x1, i.e. r·f ≥ reach − (1 − f)·available.
            if (f > 0.0) labelRight = std::max(labelRight, (reach - (1.0 - f) * available) / f);
        }
    layout.plot.x1 = panel.x1 - std::min(labelRight, 0.3 * panel.width());

    if (layout.plot.width() < 100.0 || layout.plot.height() < 100.0)
        return fail(ErrorCode::InvalidInput, "chart \"{}\": {}x{} pixels leave no room to plot",
                    chart.title, int(panel.width()), int(panel.height()));

    // Text wider than its room shrinks to fit.
    const auto fitScale = [&](const std::string& text, double room, double scale) {
        const double width = textWidth(text, scale * ch);
        return width > room ? scale * room / width : scale;
    };
    layout.titleScale = fitScale(chart.title, 0.96 * panel.width(), kTitleScale);
    const double xCentre = 0.5 * (layout.plot.x0 + layout.plot.x1);
    layout.xLabelScale =
        fitScale(xLabel, 2.0 * std::min(xCentre - panel.x0, panel.x1 - xCentre) - ch, 1.0);
    layout.yLabelScale = layout.yLabelAbove ? fitScale(yLabel, panel.width() - ch, 1.0) : 1.0;

    // Tick labels that would overprint their neighbours are dropped.
    thinTicks(layout.x, layout.plot.width(),
              [&](size_t i) { return 0.5 * textWidth(layout.x.labels[i], tickCh) + 0.4 * tickCh; });
    thinTicks(layout.y, layout.plot.height(), [&](size_t) { return 0.7 * tickCh; });
    return layout;
}

/// Draws one laid-out panel; its series use colour map 0 slots from `firstColor` on.
void drawPanel(plstream& pls, const Chart& chart, const PanelLayout& layout, double mmPerPx,
               PLINT firstColor) {
    const auto mm = [&](double px) { return px * mmPerPx; };
    const Rect& plot = layout.plot;
    const Rect& panel = layout.panel;
    const Axis& x = layout.x;
    const Axis& y = layout.y;
    const double ch = layout.ch;
    const double xPerPx = (x.hi - x.lo) / plot.width(), yPerPx = (y.hi - y.lo) / plot.height();
    const auto toWorld = [&](const glm::dvec2& p) {
        return glm::dvec2(x.log ? std::log10(p.x) : p.x, y.log ? std::log10(p.y) : p.y);
    };

    // The plot area: grid lines at the labelled ticks, under everything else.
    pls.svpa(mm(plot.x0), mm(plot.x1), mm(plot.y0), mm(plot.y1));
    pls.wind(x.lo, x.hi, y.lo, y.hi);
    pls.lsty(kSolid);
    pls.width(1.0);
    pls.col0(kGrid);
    for (double t : x.ticks) pls.join(t, y.lo, t, y.hi);
    for (double t : y.ticks) pls.join(x.lo, t, x.hi, t);

    // Frame and inward ticks at the labels (PLplot's own ticks fall at its steps, not ours),
    // with unlabelled 2–9 minor ticks on log axes.
    pls.col0(kInk);
    pls.box("bc", 0.0, 0, "bc", 0.0, 0);
    const double xTick = 0.45 * ch * yPerPx, yTick = 0.45 * ch * xPerPx;
    const auto xTickAt = [&](double t, double length) {
        pls.join(t, y.lo, t, y.lo + length);
        pls.join(t, y.hi, t, y.hi - length);
    };
    const auto yTickAt = [&](double t, double length) {
        pls.join(x.lo, t, x.lo + length, t);
        pls.join(x.hi, t, x.hi - length, t);
    };
    for (double t : x.ticks) xTickAt(t, xTick);
    for (double t : y.ticks) yTickAt(t, yTick);
    const auto minorTicks = [](const Axis& axis, const auto& tickAt, double length) {
        if (!axis.log || axis.hi - axis.lo > 6.0) return;
        for (int k = int(std::floor(axis.lo)); k <= int(std::ceil(axis.hi)); ++k)
            for (int m = 1; m <= 9; ++m) {
                const double t = k + std::log10(double(m));
                if (t > axis.lo && t < axis.hi) tickAt(t, m == 1 ? 2.0 * length : length);
            }
    };
    minorTicks(x, xTickAt, 0.5 * xTick);
    minorTicks(y, yTickAt, 0.5 * yTick);

    // Tick labels: centred under x ticks, right-aligned and upright left of y ticks.
    pls.col0(kTickInk);
    pls.schr(mm(ch), kTickScale);
    for (size_t i = 0; i < x.ticks.size(); ++i)
        pls.mtex("b", 0.9, x.fraction(x.ticks[i]), 0.5, x.labels[i].c_str());
    for (size_t i = 0; i < y.ticks.size(); ++i)
        pls.mtex("lv", 0.6, y.fraction(y.ticks[i]), 1.0, y.labels[i].c_str());

    // Series over the whole panel, so that markers and point labels at the plot's edge are
    // not clipped; the window is widened to keep the data where the plot area has it.
    pls.svpa(mm(panel.x0), mm(panel.x1), mm(panel.y0), mm(panel.y1));
    pls.wind(x.lo - (plot.x0 - panel.x0) * xPerPx, x.hi + (panel.x1 - plot.x1) * xPerPx,
             y.lo - (plot.y0 - panel.y0) * yPerPx, y.hi + (panel.y1 - plot.y1) * yPerPx);
    std::vector<std::vector<PLFLT>> wx(chart.series.size()), wy(chart.series.size());
    for (size_t s = 0; s < chart.series.size(); ++s)
        for (const glm::dvec2& p : chart.series[s].points) {
            const glm::dvec2 w = toWorld(p);
            wx[s].push_back(w.x);
            wy[s].push_back(w.y);
        }
    // Lines first, markers over all lines, labels over everything.
    pls.width(2.0);
    for (size_t s = 0; s < chart.series.size(); ++s) {
        const ChartSeries& series = chart.series[s];
        if (!series.connected || series.points.size() < 2) continue;
        pls.col0(firstColor + PLINT(s));
        pls.lsty(series.dashed ? kDashed : kSolid);
        pls.line(PLINT(wx[s].size()), wx[s].data(), wy[s].data());
    }
    pls.lsty(kSolid);
    pls.width(1.0);
    pls.schr(mm(ch), kMarkerScale);
    for (size_t s = 0; s < chart.series.size(); ++s) {
        if (!hasMarkers(chart.series[s]) || wx[s].empty()) continue;
        pls.col0(firstColor + PLINT(s));
        pls.string(PLINT(wx[s].size()), wx[s].data(), wy[s].data(), kMarker);
    }
    pls.schr(mm(ch), kPointLabelScale);
    for (size_t s = 0; s < chart.series.size(); ++s) {
        const ChartSeries& series = chart.series[s];
        pls.col0(firstColor + PLINT(s));
        for (size_t i = 0; i < std::min(series.labels.size(), wx[s].size()); ++i)
            if (!series.labels[i].empty())
                pls.ptex(wx[s][i] + 0.5 * ch * xPerPx, wy[s][i] + 0.6 * ch * yPerPx, 1.0, 0.0, 0.0,
                         plText(series.labels[i]).c_str());
    }

    // Back to the plot area: legend, title and axis labels are placed against its edges.
    pls.svpa(mm(plot.x0), mm(plot.x1), mm(plot.y0), mm(plot.y1));
    pls.wind(x.lo, x.hi, y.lo, y.hi);
    pls.col0(kInk);
    if (layout.legendRows > 0) {
        std::vector<PLINT> options, textColors, lineColors, lineStyles, symbolColors, symbolNumbers,
            none;
        std::vector<PLFLT> lineWidths, symbolScales, zeros;
        std::vector<std::string> names;
        for (size_t s = 0; s < chart.series.size(); ++s) {
            const ChartSeries& series = chart.series[s];
            if (series.name.empty()) continue;
            PLINT option = 0;
            if (series.connected) option |= PL_LEGEND_LINE;
            if (hasMarkers(series)) option |= PL_LEGEND_SYMBOL;
            options.push_back(option);
            textColors.push_back(kInk);
            lineColors.push_back(firstColor + PLINT(s));
            lineStyles.push_back(series.dashed ? kDashed : kSolid);
            lineWidths.push_back(2.0);
            symbolColors.push_back(firstColor + PLINT(s));
            symbolScales.push_back(kMarkerScale / kLegendScale);
            symbolNumbers.push_back(
                series.connected ? 2 : 3);  // pllegend puts a single one at the left end
            names.push_back(plText(series.name));
            none.push_back(0);
            zeros.push_back(0.0);
        }
        std::vector<const char*> texts, symbols;
        for (const std::string& name : names) {
            texts.push_back(name.c_str());
            symbols.push_back(kMarker);
        }
        PLFLT legendWidth = 0.0, legendHeight = 0.0;
        pls.schr(mm(ch), 1.0);
        pls.legend(&legendWidth, &legendHeight, PL_LEGEND_ROW_MAJOR,
                   PL_POSITION_TOP | PL_POSITION_OUTSIDE | PL_POSITION_VIEWPORT, 0.0,
                   layout.legendGap / plot.height(), 2.4 * ch / plot.width(), kWhite, kInk, 1,
                   layout.legendRows, layout.legendColumns, PLINT(names.size()), options.data(),
                   0.8, kLegendScale, 1.6, 0.0, textColors.data(), texts.data(), none.data(),
                   none.data(), zeros.data(), zeros.data(), lineColors.data(), lineStyles.data(),
                   lineWidths.data(), symbolColors.data(), symbolScales.data(),
                   symbolNumbers.data(), symbols.data());
    }
    if (!chart.title.empty()) {
        pls.schr(mm(ch), layout.titleScale);
        pls.mtex("t", layout.titleBaseline / (layout.titleScale * ch),
                 (0.5 * (panel.x0 + panel.x1) - plot.x0) / plot.width(), 0.5,
                 plText(chart.title).c_str());
    }
    const std::string xLabel = chart.xLabel + (chart.logX ? " (log scale)" : "");
    const std::string yLabel = chart.yLabel + (chart.logY ? " (log scale)" : "");
    if (!xLabel.empty()) {
        pls.schr(mm(ch), layout.xLabelScale);
        pls.mtex("b", (0.9 * kTickScale * ch + 1.5 * kTickScale * ch) / (layout.xLabelScale * ch),
                 0.5, 0.5, plText(xLabel).c_str());
    }
    if (!yLabel.empty()) {
        pls.schr(mm(ch), layout.yLabelScale);
        if (layout.yLabelAbove)
            pls.mtex("t", layout.yLabelBaseline / (layout.yLabelScale * ch),
                     (panel.x0 + 0.5 * ch - plot.x0) / plot.width(), 0.0, plText(yLabel).c_str());
        else
            // PLplot puts a left-side label's baseline 0.4 character heights inside `disp`.
            pls.mtex("l", layout.yLabelGap / (layout.yLabelScale * ch) + 0.4, 0.5, 0.5,
                     plText(yLabel).c_str());
    }
}

/// PLplot keeps global state and is not thread-safe: one chart at a time.
std::mutex& plplotMutex() {
    static std::mutex mutex;
    return mutex;
}

/// Whether PLplot has the pngcairo driver (Debian's plplot-driver-cairo).
bool havePngCairo(plstream& pls) {
    std::array<const char*, 128> menus{}, names{};
    const char** menu = menus.data();
    const char** name = names.data();
    int count = int(names.size());
    pls.gFileDevs(&menu, &name, &count);
    for (int i = 0; i < count; ++i)
        if (names[i] && std::strcmp(names[i], "pngcairo") == 0) return true;
    return false;
}

/// Draws `panels` (already checked) on a page of `columns` columns and a `band`-pixel title
/// band, and writes it to `path` atomically.
Result<void> renderPage(std::span<const Chart> panels, const std::string& title,
                        const std::string& path, int columns, int panelWidth, int panelHeight,
                        int band) {
    const int n = int(panels.size());
    const int rows = (n + columns - 1) / columns;
    const int width = std::min(columns, n) * panelWidth, height = rows * panelHeight + band;
    std::vector<PanelLayout> layouts;
    for (int i = 0; i < n; ++i) {
        const double x0 = double((i % columns) * panelWidth);
        const double y1 = double(height - band - (i / columns) * panelHeight);
        auto layout = layoutPanel(panels[i], {x0, y1 - panelHeight, x0 + panelWidth, y1});
        if (!layout) return std::unexpected(layout.error());
        layouts.push_back(std::move(*layout));
    }

    // A temporary file beside the target: creating it is what proves the directory exists
    // and is writable, because PLplot exits the process when it cannot open its output.
    // (Not mkstemp: its 0600 would stay on the chart.)
    static std::atomic<uint64_t> counter{0};
    const std::string temp = fmt::format("{}.tmp.{}.{}", path, getpid(), counter++);
    const int fd = open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL, 0666);
    if (fd < 0) return fail(ErrorCode::Io, "cannot write chart {}: {}", path, std::strerror(errno));
    close(fd);

    std::lock_guard lock(plplotMutex());
    {
        plstream pls;
        if (!havePngCairo(pls)) {
            std::remove(temp.c_str());
            return fail(ErrorCode::NotFound,
                        "PLplot's pngcairo driver is missing (Debian: plplot-driver-cairo)");
        }
        pls.sdev("pngcairo");
        pls.sfnam(temp.c_str());
        pls.spage(0.0, 0.0, width, height, 0, 0);
        // Colour map 0: white background, dark ink, light grid, then one slot per series.
        int seriesCount = 0;
        for (const Chart& chart : panels) seriesCount += int(chart.series.size());
        pls.scmap0n(kFirstSeries + seriesCount);
        pls.scolbg(255, 255, 255);
        pls.scol0a(kInk, 25, 25, 25, 1.0);
        pls.scol0a(kGrid, 225, 225, 225, 1.0);
        pls.scol0a(kTickInk, 70, 70, 70, 1.0);
        PLINT slot = kFirstSeries;
        for (const Chart& chart : panels)
            for (const ChartSeries& series : chart.series) {
                const glm::ivec3 rgb =
                    glm::ivec3(glm::round(glm::clamp(series.color, 0.0f, 1.0f) * 255.0f));
                pls.scol0a(slot++, rgb.r, rgb.g, rgb.b, 1.0);
            }
        pls.init();
        pls.adv(0);
        PLFLT xMin = 0.0, xMax = 0.0, yMin = 0.0, yMax = 0.0;
        pls.gspa(xMin, xMax, yMin, yMax);
        const double mmPerPx = (xMax - xMin) / width;  // the cairo driver's page is at 72 dpi

        PLINT firstColor = kFirstSeries;
        for (int i = 0; i < n; ++i) {
            drawPanel(pls, panels[i], layouts[i], mmPerPx, firstColor);
            firstColor += PLINT(panels[i].series.size());
        }
        if (band > 0 && !title.empty()) {
            const double ch = baseCharHeight(panelWidth, panelHeight);
            const double scale = std::min(kPageTitleScale, 0.96 * width / textWidth(title, ch));
            pls.svpa(0.0, width * mmPerPx, (height - band) * mmPerPx, height * mmPerPx);
            pls.wind(0.0, 1.0, 0.0, 1.0);
            pls.col0(kInk);
            pls.schr(ch * mmPerPx, scale);
            pls.ptex(0.5, 0.45, 1.0, 0.0, 0.5, plText(title).c_str());
        }
    }  // ending the stream writes the PNG and closes the file

    std::error_code error;
    const auto size = fs::file_size(temp, error);
    if (error || size == 0 || std::rename(temp.c_str(), path.c_str()) != 0) {
        std::remove(temp.c_str());
        return fail(ErrorCode::Io, "cannot write chart {}", path);
    }
    return {};
}

}  // namespace

Result<void> writeChart(const Chart& chart, const std::string& path, int width, int height) {
    PIC_TRY(checkChart(chart));
    return renderPage(std::span(&chart, 1), "", path, 1, width, height, 0);
}

Result<void> writeCharts(const std::vector<Chart>& panels, const std::string& title,
                         const std::string& path, int columns, int panelWidth, int panelHeight) {
    if (panels.empty()) return fail(ErrorCode::InvalidInput, "charts \"{}\" have no panel", title);
    if (columns < 1)
        return fail(ErrorCode::InvalidInput, "charts \"{}\": {} columns", title, columns);
    for (const Chart& chart : panels) PIC_TRY(checkChart(chart));
    return renderPage(panels, title, path, columns, panelWidth, panelHeight, kChartsTitleHeight);
}

std::vector<size_t> paretoFront(std::span<const glm::dvec2> points) {
    std::vector<size_t> order;
    for (size_t i = 0; i < points.size(); ++i)
        if (std::isfinite(points[i].x) && std::isfinite(points[i].y)) order.push_back(i);
    // By x, then y, then index: a point is on the front exactly when its y is below that of
    // every point before it (those have smaller x, or equal x and no larger y).
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
        if (points[a].x != points[b].x) return points[a].x < points[b].x;
        if (points[a].y != points[b].y) return points[a].y < points[b].y;
        return a < b;
    });
    std::vector<size_t> front;
    double lowest = std::numeric_limits<double>::infinity();
    for (size_t i : order)
        if (points[i].y < lowest) {
            front.push_back(i);
            lowest = points[i].y;
        }
    return front;
}

}  // namespace pic
