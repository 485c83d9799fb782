// Where the editor's panels go, computed from the window size every frame (ImGui 1.86 in Debian 12 has
// no docking branch, so the layout is ours): a left column (Outliner, Inspector, Frame time), a right
// column (Tools, Lattice), the Timeline in the strip between them above the status bar. Panels never
// overlap and always lie inside the window, at any size; a collapsed panel keeps only its title bar and
// gives its height to the others in its column. Which panels are collapsed is what the user changes, and
// ImGui's ini file remembers it between runs (view_app.cpp: $XDG_CONFIG_HOME/splatffd/imgui.ini).
// Plain maths, no ImGui: tested on CPU (tests/systems/editor/panel_layout_test.cpp).
#pragma once

#include <array>
#include <cstddef>
#include <span>

namespace sffd::editor {

enum class Panel : std::size_t { outliner, inspector, frame_time, tools, lattice, timeline, count };
inline constexpr std::size_t panel_count = std::size_t(Panel::count);
const char* panel_title(Panel p);  // the ImGui window name

struct PanelRect {
    float x = 0, y = 0, w = 0, h = 0;  // window pixels, (0,0) top left
};

struct LayoutInput {
    float width = 1280, height = 720;  // window (framebuffer) size
    float top = 19;                    // main menu bar height
    float bottom = 24;                 // status bar height
    float title = 19;                  // a collapsed window's height (its title bar)
    std::array<bool, panel_count> collapsed{};
};

std::array<PanelRect, panel_count> layout_panels(const LayoutInput& in);

// Below this window size the panels start collapsed to their title bars (a user's choice, remembered
// in imgui.ini, wins): expanded, the columns would cover the middle of the model and cut their labels.
bool panels_start_collapsed(float width, float height);

// The part of the window no expanded panel covers: between the columns (a column whose panels are all
// collapsed gives its width back), below the menu bar, above the Timeline. The lattice overlay is
// clipped to it, so it is never drawn under a (translucent) panel.
PanelRect view_rect(const std::array<PanelRect, panel_count>& panels, const LayoutInput& in);

// Registry resource: the view rectangle of the last frame whose panels were drawn (absent without
// panels: the whole window is the view). Written by the panels, read by the lattice overlay.
struct EditorViewRect {
    PanelRect rect;
    float width = 0, height = 0;  // the window it is in (a framebuffer of another size scales it)
};

// Top of the frame-time graph: 1.5 x the 90th percentile of `ms` (at least 1 ms), so one slow frame (the
// first, which compiles shaders and uploads: seconds) does not flatten every other frame to the bottom line.
float graph_scale(std::span<const float> ms);

// True when the rectangles share area (touching edges do not count).
bool overlaps(const PanelRect& a, const PanelRect& b);

}  // namespace sffd::editor
