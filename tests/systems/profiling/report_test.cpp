// Statistics and SVG charts, against hand-computed values.
#include <gtest/gtest.h>

#include "systems/profiling/report.h"
#include "systems/profiling/svg_plot.h"

namespace sffd::profiling {
namespace {

TEST(Stats, InterpolatedPercentilesOfKnownSeries) {
    // 1..101: rank p*(n-1) is exact: p50 = 51, p95 = 96, p99 = 100.
    std::vector<double> v;
    for (int i = 101; i >= 1; --i) v.push_back(i);
    const Stats s = compute_stats(v);
    EXPECT_EQ(s.n, 101u);
    EXPECT_DOUBLE_EQ(s.min, 1);
    EXPECT_DOUBLE_EQ(s.max, 101);
    EXPECT_DOUBLE_EQ(s.mean, 51);
    EXPECT_DOUBLE_EQ(s.p50, 51);
    EXPECT_DOUBLE_EQ(s.p95, 96);
    EXPECT_DOUBLE_EQ(s.p99, 100);
    // Four values: p50 halfway between 2nd and 3rd, p95 at rank 2.85.
    const Stats t = compute_stats({4, 1, 3, 2});
    EXPECT_DOUBLE_EQ(t.p50, 2.5);
    EXPECT_DOUBLE_EQ(t.p95, 3.85);
    EXPECT_EQ(compute_stats({}).n, 0u);
}

TEST(SvgPlot, TicksAndLabels) {
    EXPECT_EQ(tick_label(60000), "60k");
    EXPECT_EQ(tick_label(250000), "250k");
    EXPECT_EQ(tick_label(1000000), "1M");
    EXPECT_EQ(tick_label(0.25), "0.25");
    EXPECT_EQ(tick_label(2.5), "2.5");
    EXPECT_EQ(tick_label(0), "0");
    const auto lin = nice_ticks(0, 10, false);
    ASSERT_FALSE(lin.empty());
    EXPECT_DOUBLE_EQ(lin.front(), 0);
    EXPECT_DOUBLE_EQ(lin.back(), 10);
    EXPECT_DOUBLE_EQ(lin[1] - lin[0], 2);
    const auto lg = nice_ticks(50000, 2000000, true);
    EXPECT_EQ(lg, (std::vector<double>{50000, 100000, 200000, 500000, 1000000, 2000000}));
}

TEST(SvgPlot, ChartHasTitleAxesLegendAndOnePolylinePerSeries) {
    LineChart c;
    c.title = "deform time vs points";
    c.x_label = "points";
    c.y_label = "ms";
    c.log_x = c.log_y = true;
    c.series = {{"cpu bernstein", {{60000, 5}, {250000, 20}, {1000000, 80}}},
                {"gpu <bspline>", {{60000, 1}, {250000, 3}, {1000000, 9}}}};
    const std::string svg = render_svg(c);
    EXPECT_EQ(svg.rfind("<svg ", 0), 0u);
    EXPECT_NE(svg.find("deform time vs points"), std::string::npos);
    EXPECT_NE(svg.find("points (log scale)"), std::string::npos);
    EXPECT_NE(svg.find("gpu &lt;bspline&gt;"), std::string::npos);  // escaped legend text
    EXPECT_NE(svg.find(">50k<"), std::string::npos);                // log axis widened to 1-2-5 values
    EXPECT_NE(svg.find(">1M<"), std::string::npos);
    EXPECT_EQ(svg.find(">60k<"), std::string::npos);
    size_t polylines = 0;
    for (size_t at = svg.find("<polyline"); at != std::string::npos; at = svg.find("<polyline", at + 1))
        ++polylines;
    EXPECT_EQ(polylines, 2u);
}

}  // namespace
}  // namespace sffd::profiling
