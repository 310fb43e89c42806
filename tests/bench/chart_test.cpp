// Benchmark charts: PNGs of the asked size with the series drawn, several panels in one image,
// bad data and unwritable paths refused, and the Pareto front the sweep labels.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>

#include <unistd.h>

#include "bench/chart.h"
#include "core/image.h"

namespace pic {
namespace {

namespace fs = std::filesystem;

Chart sample() {
    Chart chart;
    chart.title = "latency";
    chart.xLabel = "subscribers";
    chart.yLabel = "ms";
    chart.logX = true;
    ChartSeries series{"p99", {1.0f, 0.0f, 0.0f}};
    series.points = {{1, 40}, {16, 60}, {64, 90}};
    series.labels = {"a", "b", "c"};
    chart.series.push_back(series);
    return chart;
}

/// Pixels of pure-ish red, the sample series' colour.
size_t redPixels(const Image& image) {
    size_t red = 0;
    for (const glm::vec3& p : image.pixels) red += p.r > 0.8f && p.g < 0.2f && p.b < 0.2f;
    return red;
}

TEST(Chart, WritesAPngOfTheAskedSizeWithTheSeriesDrawn) {
    const fs::path path = fs::temp_directory_path() / fmt::format("pic_chart_{}.png", getpid());
    ASSERT_TRUE(writeChart(sample(), path.string(), 640, 400));
    auto image = readImage(path.string());
    ASSERT_TRUE(image) << image.error().message;
    EXPECT_EQ(image->width, 640u);
    EXPECT_EQ(image->height, 400u);
    EXPECT_GT(redPixels(*image), 200u) << "the red series' line and markers";
    fs::remove(path);
}

TEST(Chart, AScatterDrawsMarkersWithoutLines) {
    const fs::path path = fs::temp_directory_path() / fmt::format("pic_scatter_{}.png", getpid());
    const auto red = [&](bool connected) -> size_t {
        Chart chart = sample();
        chart.series[0].connected = connected;
        chart.series[0].labels.clear();
        if (!writeChart(chart, path.string(), 640, 400)) return 0;
        auto image = readImage(path.string());
        return image ? redPixels(*image) : 0;
    };
    const size_t line = red(true), scatter = red(false);
    // Three markers, and the legend's.
    EXPECT_GE(scatter, 40u);
    EXPECT_LT(scatter, line / 2) << "lines between the points were drawn";
    fs::remove(path);
}

TEST(Chart, WritesSeveralPanelsInOnePng) {
    std::vector<Chart> panels(3, sample());
    panels[1].logY = true;
    panels[1].series[0].connected = false;
    panels[2].logX = false;
    panels[2].series.push_back({"goal", glm::vec3(0.3f), {{1, 80}, {64, 80}}, {}, true});
    const fs::path path = fs::temp_directory_path() / fmt::format("pic_charts_{}.png", getpid());
    ASSERT_TRUE(writeCharts(panels, "three panels", path.string(), 2, 400, 300));
    auto image = readImage(path.string());
    ASSERT_TRUE(image) << image.error().message;
    // Two columns, two rows, and the title band.
    EXPECT_EQ(image->width, 800u);
    EXPECT_EQ(image->height, 600u + uint32_t(kChartsTitleHeight));
    size_t dark = 0;
    for (const glm::vec3& p : image->pixels) dark += p.r + p.g + p.b < 1.0f;
    EXPECT_GT(dark, 1000u) << "axes, ticks and text";
    EXPECT_GT(redPixels(*image), 300u) << "the three panels' red series";
    fs::remove(path);
}

TEST(Chart, RefusesBadData) {
    const std::string path = (fs::temp_directory_path() / "pic_chart_refused.png").string();
    Chart empty;
    EXPECT_EQ(writeChart(empty, path).error().code, ErrorCode::InvalidInput);
    Chart nan = sample();
    nan.series[0].points[1].y = std::numeric_limits<double>::quiet_NaN();
    EXPECT_EQ(writeChart(nan, path).error().code, ErrorCode::InvalidInput);
    Chart logZero = sample();
    logZero.series[0].points[0].x = 0.0;
    EXPECT_EQ(writeChart(logZero, path).error().code, ErrorCode::InvalidInput);
    Chart logYZero = sample();
    logYZero.logY = true;
    logYZero.series[0].points[2].y = 0.0;
    EXPECT_EQ(writeChart(logYZero, path).error().code, ErrorCode::InvalidInput);
    logYZero.series[0].points[2].y = -1.0;
    EXPECT_EQ(writeChart(logYZero, path).error().code, ErrorCode::InvalidInput);
    EXPECT_EQ(writeCharts({sample(), logYZero}, "one bad panel", path).error().code,
              ErrorCode::InvalidInput);
    EXPECT_EQ(writeCharts({}, "no panel", path).error().code, ErrorCode::InvalidInput);
    EXPECT_EQ(writeChart(sample(), path, 120, 80).error().code, ErrorCode::InvalidInput);
    EXPECT_FALSE(fs::exists(path));
}

TEST(Chart, APathInAMissingDirectoryIsAnIoError) {
    const fs::path dir = fs::temp_directory_path() / fmt::format("pic_chart_missing_{}", getpid());
    const std::string path = (dir / "chart.png").string();
    auto written = writeChart(sample(), path);
    ASSERT_FALSE(written);
    EXPECT_EQ(written.error().code, ErrorCode::Io);
    auto panels = writeCharts({sample(), sample()}, "two", path);
    ASSERT_FALSE(panels);
    EXPECT_EQ(panels.error().code, ErrorCode::Io);
    EXPECT_FALSE(fs::exists(dir));
}

TEST(ParetoFront, KeepsTheLowerLeftFrontByIncreasingX) {
    const std::vector<glm::dvec2> points{
        {1.0, 5.0},                                       // 0: on the front
        {2.0, 3.0},                                       // 1: on the front
        {2.0, 3.0},                                       // 2: equal to 1, which is kept
        {2.0, 4.0},                                       // 3: same x as 1, higher y
        {3.0, 3.0},                                       // 4: same y as 1, larger x
        {4.0, 1.0},                                       // 5: on the front
        {0.5, 9.0},                                       // 6: on the front, smallest x
        {5.0, 1.0},                                       // 7: same y as 5, larger x
        {4.0, 2.0},                                       // 8: same x as 5, higher y
        {6.0, 0.5},                                       // 9: on the front, lowest y
        {1.0, 5.0},                                       // 10: equal to 0, which is kept
        {std::numeric_limits<double>::quiet_NaN(), 0.0},  // 11: never on it
    };
    EXPECT_EQ(paretoFront(points), (std::vector<size_t>{6, 0, 1, 5, 9}));
    EXPECT_TRUE(paretoFront({}).empty());
    const std::vector<glm::dvec2> one{{3.0, 3.0}};
    EXPECT_EQ(paretoFront(one), (std::vector<size_t>{0}));
}

}  // namespace
}  // namespace pic
