// Benchmark charts: a PNG of the asked size with the series drawn, and bad data refused.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>

#include <unistd.h>

#include "core/chart.h"
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

TEST(Chart, WritesAPngOfTheAskedSizeWithTheSeriesDrawn) {
    ASSERT_TRUE(fs::exists(kChartFont)) << kChartFont << " missing: scripts/install_deps.sh installs it";
    const fs::path path = fs::temp_directory_path() / fmt::format("pic_chart_{}.png", getpid());
    ASSERT_TRUE(writeChart(sample(), path.string(), 640, 400));
    auto image = readImage(path.string());
    ASSERT_TRUE(image) << image.error().message;
    EXPECT_EQ(image->width, 640u);
    EXPECT_EQ(image->height, 400u);
    size_t red = 0;
    for (const glm::vec3& p : image->pixels) red += p.r > 0.8f && p.g < 0.2f && p.b < 0.2f;
    EXPECT_GT(red, 200u) << "the red series' line and markers";
    fs::remove(path);
}

TEST(Chart, AScatterDrawsMarkersWithoutLines) {
    const fs::path path = fs::temp_directory_path() / fmt::format("pic_scatter_{}.png", getpid());
    const auto redPixels = [&](bool connected) -> size_t {
        Chart chart = sample();
        chart.series[0].connected = connected;
        chart.series[0].labels.clear();
        if (!writeChart(chart, path.string(), 640, 400)) return 0;
        auto image = readImage(path.string());
        if (!image) return 0;
        size_t red = 0;
        for (const glm::vec3& p : image->pixels) red += p.r > 0.8f && p.g < 0.2f && p.b < 0.2f;
        return red;
    };
    const size_t line = redPixels(true), scatter = redPixels(false);
    // Three 7 × 7 markers, and the legend's swatch.
    EXPECT_GE(scatter, 3u * 49u);
    EXPECT_LT(scatter, line / 2) << "lines between the points were drawn";
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
    EXPECT_FALSE(fs::exists(path));
}

}  // namespace
}  // namespace pic
