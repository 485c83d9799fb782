// Line charts as standalone SVG: axes with "nice" ticks (linear or log10), labelled axes, title,
// legend, one polyline with markers per series. Used for frame-time plots and sweep plots.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace sffd::profiling {

struct Series {
    std::string name;
    std::vector<std::pair<double, double>> points;  // (x, y), drawn in the given order
    bool dashed = false;                            // e.g. one backend solid, the other dashed
};

struct LineChart {
    std::string title;
    std::string x_label;
    std::string y_label;
    bool log_x = false;
    bool log_y = false;
    bool markers = true;
    bool x_ticks_at_data = false;  // label the x axis at the data's x values (few distinct values)
    int width = 900, height = 560;
    std::vector<Series> series;
};

std::string render_svg(const LineChart& chart);

// Tick values covering [lo, hi]: 1-2-5 steps (linear) or powers of ten with 2 and 5 (log).
std::vector<double> nice_ticks(double lo, double hi, bool log_scale);
// Short tick label: 60000 -> "60k", 1e6 -> "1M", 0.25 -> "0.25".
std::string tick_label(double value);

}  // namespace sffd::profiling
