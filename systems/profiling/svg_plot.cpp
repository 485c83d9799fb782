#include "systems/profiling/svg_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace sffd::profiling {

namespace {

// Colour-blind-safe palette (Okabe-Ito), then greys.
constexpr const char* palette[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9",
                                   "#000000", "#882255", "#777777", "#AA4499", "#332288", "#117733"};
constexpr const char* dashes[] = {"", "6,3", "2,3", "8,3,2,3"};

std::string escape(const std::string& s) {
    std::string out;
    for (char c : s) {
        switch (c) {
            case '<': out += "&lt;"; break;
            case '>': out += "&gt;"; break;
            case '&': out += "&amp;"; break;
            case '"': out += "&quot;"; break;
            default: out += c;
        }
    }
    return out;
}

std::string fmt(const char* f, double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, f, v);
    return buf;
}

}  // namespace

std::string tick_label(double v) {
    const double a = std::fabs(v);
    auto trim = [](std::string s) {
        if (s.find('.') != std::string::npos) {
            while (!s.empty() && s.back() == '0') s.pop_back();
            if (!s.empty() && s.back() == '.') s.pop_back();
        }
        return s;
    };
    if (a >= 1e6) return trim(fmt("%.2f", v / 1e6)) + "M";
    if (a >= 1e4) return trim(fmt("%.1f", v / 1e3)) + "k";
    if (a >= 100 || a == 0.0) return trim(fmt("%.0f", v));
    if (a >= 1) return trim(fmt("%.2f", v));
    return trim(fmt("%.4f", v));
}

std::vector<double> nice_ticks(double lo, double hi, bool log_scale) {
    std::vector<double> ticks;
    if (!(hi > lo)) {
        ticks.push_back(lo);
        return ticks;
    }
    if (log_scale) {
        const int e0 = static_cast<int>(std::floor(std::log10(lo)));
        const int e1 = static_cast<int>(std::ceil(std::log10(hi)));
        // Few decades: 1-2-5 per decade; many: decades only.
        const bool dense = e1 - e0 <= 3;
        for (int e = e0; e <= e1; ++e)
            for (double m : {1.0, 2.0, 5.0}) {
                if (!dense && m != 1.0) continue;
                const double t = m * std::pow(10.0, e);
                if (t >= lo * (1 - 1e-9) && t <= hi * (1 + 1e-9)) ticks.push_back(t);
            }
        return ticks;
    }
    const double raw = (hi - lo) / 6.0;
    const double mag = std::pow(10.0, std::floor(std::log10(raw)));
    double step = mag;
    for (double m : {1.0, 2.0, 2.5, 5.0, 10.0})
        if (m * mag >= raw) {
            step = m * mag;
            break;
        }
    for (double t = std::ceil(lo / step) * step; t <= hi + step * 1e-9; t += step)
        ticks.push_back(std::fabs(t) < step * 1e-9 ? 0.0 : t);
    return ticks;
}

std::string render_svg(const LineChart& c) {
    const double W = c.width, H = c.height;
    // Legend to the right of the plot; margins leave room for tick labels and axis titles.
    const double legend_w = 230.0;
    const double left = 80.0, right = W - legend_w, top = 50.0, bottom = H - 60.0;

    double x0 = std::numeric_limits<double>::max(), x1 = -x0, y0 = x0, y1 = -x0;
    for (const auto& s : c.series)
        for (auto [x, y] : s.points) {
            if (c.log_x && x <= 0) continue;
            if (c.log_y && y <= 0) continue;
            x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
        }
    if (x0 > x1) x0 = 0, x1 = 1, y0 = 0, y1 = 1;
    // Padding: linear y starts at 0 (times); log axes extend to the enclosing 1-2-5 values.
    auto expand_log = [](double& lo, double& hi) {
        auto down = [](double v) {
            const double e = std::pow(10.0, std::floor(std::log10(v)));
            for (double m : {5.0, 2.0, 1.0})
                if (m * e <= v) return m * e;
            return e;
        };
        auto up = [](double v) {
            const double e = std::pow(10.0, std::floor(std::log10(v)));
            for (double m : {1.0, 2.0, 5.0, 10.0})
                if (m * e >= v * (1 - 1e-12)) return m * e;
            return 10 * e;
        };
        lo = down(lo), hi = up(hi);
        if (hi <= lo) hi = lo * 10;
    };
    std::vector<double> data_x;
    if (c.x_ticks_at_data) {
        for (const auto& s : c.series)
            for (auto [x, y] : s.points)
                if (std::find(data_x.begin(), data_x.end(), x) == data_x.end()) data_x.push_back(x);
        std::sort(data_x.begin(), data_x.end());
    }
    if (c.x_ticks_at_data && !data_x.empty()) {
        // Pad by a fraction of the range so the end markers sit inside the frame.
        if (c.log_x) x0 /= 1.25, x1 *= 1.25;
        else {
            const double pad = x1 > x0 ? 0.06 * (x1 - x0) : 1.0;
            x0 -= pad, x1 += pad;
        }
    } else if (c.log_x) {
        expand_log(x0, x1);
    } else if (x1 == x0) {
        x0 -= 1, x1 += 1;
    }
    if (c.log_y) expand_log(y0, y1);
    else {
        y0 = std::min(0.0, y0);
        y1 = y1 > y0 ? y1 * 1.08 : y0 + 1;
    }
    auto tx = [&](double x) {
        const double f = c.log_x ? (std::log10(x) - std::log10(x0)) / (std::log10(x1) - std::log10(x0))
                                 : (x - x0) / (x1 - x0);
        return left + f * (right - left);
    };
    auto ty = [&](double y) {
        const double f = c.log_y ? (std::log10(y) - std::log10(y0)) / (std::log10(y1) - std::log10(y0))
                                 : (y - y0) / (y1 - y0);
        return bottom - f * (bottom - top);
    };

    std::string o;
    o += "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + fmt("%.0f", W) + "\" height=\"" +
         fmt("%.0f", H) + "\" viewBox=\"0 0 " + fmt("%.0f", W) + " " + fmt("%.0f", H) +
         "\" font-family=\"DejaVu Sans, Arial, sans-serif\" font-size=\"13\">\n";
    o += "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
    o += "<text x=\"" + fmt("%.1f", (left + right) / 2) +
         "\" y=\"28\" text-anchor=\"middle\" font-size=\"17\" "
         "font-weight=\"bold\">" +
         escape(c.title) + "</text>\n";
    // Grid and ticks.
    for (double t : c.x_ticks_at_data && !data_x.empty() ? data_x : nice_ticks(x0, x1, c.log_x)) {
        const double x = tx(t);
        o += "<line x1=\"" + fmt("%.1f", x) + "\" y1=\"" + fmt("%.1f", top) + "\" x2=\"" + fmt("%.1f", x) +
             "\" y2=\"" + fmt("%.1f", bottom) + "\" stroke=\"#e4e4e4\"/>\n";
        o += "<line x1=\"" + fmt("%.1f", x) + "\" y1=\"" + fmt("%.1f", bottom) + "\" x2=\"" + fmt("%.1f", x) +
             "\" y2=\"" + fmt("%.1f", bottom + 5) + "\" stroke=\"black\"/>\n";
        o += "<text x=\"" + fmt("%.1f", x) + "\" y=\"" + fmt("%.1f", bottom + 20) +
             "\" text-anchor=\"middle\">" + tick_label(t) + "</text>\n";
    }
    for (double t : nice_ticks(y0, y1, c.log_y)) {
        const double y = ty(t);
        o += "<line x1=\"" + fmt("%.1f", left) + "\" y1=\"" + fmt("%.1f", y) + "\" x2=\"" +
             fmt("%.1f", right) + "\" y2=\"" + fmt("%.1f", y) + "\" stroke=\"#e4e4e4\"/>\n";
        o += "<line x1=\"" + fmt("%.1f", left - 5) + "\" y1=\"" + fmt("%.1f", y) + "\" x2=\"" +
             fmt("%.1f", left) + "\" y2=\"" + fmt("%.1f", y) + "\" stroke=\"black\"/>\n";
        o += "<text x=\"" + fmt("%.1f", left - 8) + "\" y=\"" + fmt("%.1f", y + 4) +
             "\" text-anchor=\"end\">" + tick_label(t) + "</text>\n";
    }
    // Axes and titles.
    o += "<rect x=\"" + fmt("%.1f", left) + "\" y=\"" + fmt("%.1f", top) + "\" width=\"" +
         fmt("%.1f", right - left) + "\" height=\"" + fmt("%.1f", bottom - top) +
         "\" fill=\"none\" stroke=\"black\"/>\n";
    o += "<text x=\"" + fmt("%.1f", (left + right) / 2) + "\" y=\"" + fmt("%.1f", H - 18) +
         "\" text-anchor=\"middle\">" + escape(c.x_label) + (c.log_x ? " (log scale)" : "") + "</text>\n";
    o += "<text transform=\"translate(20," + fmt("%.1f", (top + bottom) / 2) +
         ") rotate(-90)\" text-anchor=\"middle\">" + escape(c.y_label) + (c.log_y ? " (log scale)" : "") +
         "</text>\n";
    // Series.
    for (std::size_t i = 0; i < c.series.size(); ++i) {
        const auto& s = c.series[i];
        const std::string colour = palette[i % std::size(palette)];
        const std::string dash = s.dashed ? "7,4" : dashes[(i / std::size(palette)) % std::size(dashes)];
        std::string pts;
        for (auto [x, y] : s.points) {
            if ((c.log_x && x <= 0) || (c.log_y && y <= 0)) continue;
            pts += fmt("%.1f", tx(x)) + "," + fmt("%.1f", ty(y)) + " ";
        }
        o += "<polyline fill=\"none\" stroke=\"" + colour + "\" stroke-width=\"2\"" +
             (dash.empty() ? "" : " stroke-dasharray=\"" + dash + "\"") + " points=\"" + pts + "\"/>\n";
        if (c.markers)
            for (auto [x, y] : s.points) {
                if ((c.log_x && x <= 0) || (c.log_y && y <= 0)) continue;
                o += "<circle cx=\"" + fmt("%.1f", tx(x)) + "\" cy=\"" + fmt("%.1f", ty(y)) +
                     "\" r=\"3.5\" fill=\"" + colour + "\"/>\n";
            }
        const double ly = top + 10 + 20.0 * static_cast<double>(i);
        o += "<line x1=\"" + fmt("%.1f", right + 15) + "\" y1=\"" + fmt("%.1f", ly) + "\" x2=\"" +
             fmt("%.1f", right + 45) + "\" y2=\"" + fmt("%.1f", ly) + "\" stroke=\"" + colour +
             "\" stroke-width=\"2\"" + (dash.empty() ? "" : " stroke-dasharray=\"" + dash + "\"") + "/>\n";
        o += "<text x=\"" + fmt("%.1f", right + 52) + "\" y=\"" + fmt("%.1f", ly + 4) +
             "\" font-size=\"12\">" + escape(s.name) + "</text>\n";
    }
    o += "</svg>\n";
    return o;
}

}  // namespace sffd::profiling
