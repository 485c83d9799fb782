#include "systems/editor/panel_layout.h"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <vector>

namespace sffd::editor {

const char* panel_title(Panel p) {
    switch (p) {
        case Panel::outliner: return "Outliner";
        case Panel::inspector: return "Inspector";
        case Panel::frame_time: return "Frame time";
        case Panel::tools: return "Tools";
        case Panel::lattice: return "Lattice";
        case Panel::timeline: return "Timeline";
        case Panel::count: break;
    }
    return "?";
}

namespace {

constexpr float gap = 2.0f;

struct Slot {
    Panel panel;
    float weight;  // share of the column's free height (0: fixed)
    float fixed;   // wanted height when weight == 0
};

// Stacks `slots` top to bottom in [y0, y1]: collapsed panels take their title bar, fixed ones their
// height (shrunk when the column is short), the rest share what is left by weight.
template <std::size_t N>
void stack(std::array<PanelRect, panel_count>& out, const LayoutInput& in, float x, float w, float y0,
           float y1, const std::array<Slot, N>& slots) {
    const float total = std::max(0.0f, y1 - y0 - gap * float(N - 1));
    std::array<float, N> h{};
    float used = 0.0f, weights = 0.0f;
    for (std::size_t i = 0; i < N; ++i) {
        const Slot& s = slots[i];
        if (in.collapsed[std::size_t(s.panel)]) h[i] = in.title;
        else if (s.weight == 0.0f) h[i] = s.fixed;
        else weights += s.weight;
        used += h[i];
    }
    // Fixed and collapsed panels never take more than half of a short column from the weighted ones.
    if (used > total * (weights > 0.0f ? 0.5f : 1.0f) && used > 0.0f) {
        const float scale = total * (weights > 0.0f ? 0.5f : 1.0f) / used;
        for (std::size_t i = 0; i < N; ++i) h[i] *= scale;
        used *= scale;
    }
    const float left = std::max(0.0f, total - used);
    for (std::size_t i = 0; i < N; ++i)
        if (!in.collapsed[std::size_t(slots[i].panel)] && slots[i].weight > 0.0f)
            h[i] = left * slots[i].weight / weights;
    float y = y0;
    for (std::size_t i = 0; i < N; ++i) {
        const float hi = std::floor(h[i]);
        out[std::size_t(slots[i].panel)] = PanelRect{x, y, w, hi};
        y += hi + gap;
    }
}

}  // namespace

std::array<PanelRect, panel_count> layout_panels(const LayoutInput& in) {
    std::array<PanelRect, panel_count> out{};
    const float W = std::max(in.width, 1.0f), H = std::max(in.height, 1.0f);
    const float y0 = std::min(in.top + gap, H), y1 = std::max(y0, H - in.bottom - gap);
    // Columns: a fifth / a quarter of the width within readable limits, never more than 70% together
    // (the model stays visible between them).
    float left = std::clamp(std::round(W * 0.2f), 230.0f, 340.0f);
    float right = std::clamp(std::round(W * 0.25f), 300.0f, 400.0f);
    if (left + right > 0.7f * W) {
        const float s = 0.7f * W / (left + right);
        left = std::floor(left * s), right = std::floor(right * s);
    }
    stack(out, in, 0.0f, left, y0, y1,
          std::array<Slot, 3>{
              {{Panel::outliner, 0.22f, 0}, {Panel::inspector, 0.48f, 0}, {Panel::frame_time, 0.30f, 0}}});
    stack(out, in, W - right, right, y0, y1,
          std::array<Slot, 2>{{{Panel::tools, 0.45f, 0}, {Panel::lattice, 0.55f, 0}}});
    // Timeline: between the columns, above the status bar.
    const float mid_x = left + gap, mid_w = std::max(0.0f, W - right - gap - mid_x);
    const float th =
        std::min(in.collapsed[std::size_t(Panel::timeline)] ? in.title : 64.0f, std::max(0.0f, y1 - y0));
    out[std::size_t(Panel::timeline)] = PanelRect{mid_x, y1 - th, mid_w, th};
    return out;
}

bool panels_start_collapsed(float width, float height) { return width < 1100.0f || height < 650.0f; }

PanelRect view_rect(const std::array<PanelRect, panel_count>& p, const LayoutInput& in) {
    auto all_collapsed = [&](std::initializer_list<Panel> column) {
        for (Panel x : column)
            if (!in.collapsed[std::size_t(x)]) return false;
        return true;
    };
    const PanelRect& outliner = p[std::size_t(Panel::outliner)];
    const PanelRect& tools = p[std::size_t(Panel::tools)];
    const PanelRect& timeline = p[std::size_t(Panel::timeline)];
    const float x0 = all_collapsed({Panel::outliner, Panel::inspector, Panel::frame_time})
                         ? 0.0f
                         : outliner.x + outliner.w + gap;
    const float x1 = all_collapsed({Panel::tools, Panel::lattice}) ? std::max(in.width, 1.0f) : tools.x - gap;
    const float y0 = std::min(in.top + gap, std::max(in.height, 1.0f));
    const float y1 = std::max(y0, timeline.y - gap);
    return PanelRect{x0, y0, std::max(0.0f, x1 - x0), y1 - y0};
}

float graph_scale(std::span<const float> ms) {
    if (ms.empty()) return 1.0f;
    std::vector<float> sorted(ms.begin(), ms.end());
    std::sort(sorted.begin(), sorted.end());
    return std::max(1.5f * sorted[std::min(sorted.size() - 1, sorted.size() * 9 / 10)], 1.0f);
}

bool overlaps(const PanelRect& a, const PanelRect& b) {
    return a.x < b.x + b.w && b.x < a.x + a.w && a.y < b.y + b.h && b.y < a.y + a.h;
}

}  // namespace sffd::editor
