// The editor's ImGui frame, drawn with the pixels of unchanged panels reused. While a control point is
// dragged most panels (outliner, tools, lattice, timeline) draw the same triangles every frame; on a CPU
// rasteriser those triangles were most of the UI's time (the sphere's drag frame at 1280x720, 2-core
// machine: about 4.5 ms, of which the unchanged panels were about four fifths). A panel whose draw lists
// were the same two frames running is drawn once into a window-sized texture and copied from there
// (glBlitFramebuffer of its rectangle) while it stays the same; changing panels (the frame-time graph)
// and everything outside the laid-out panels (menu bar, status bar, popups, the gizmo's foreground) are
// drawn every frame, after the copies. The laid-out panels are opaque and disjoint (their backgrounds are
// clears, panel_backgrounds()), so a copied rectangle is exactly what drawing the panel would give.
//   reads   ImGui's draw data (after ImGui::Render), panel_backgrounds(), UiCacheOptions (resource)
//   writes  the bound draw framebuffer; UiCacheState (resource: the texture, per-panel hashes, stats)
// Every frame is drawn directly (as without the cache) when a draw list outside the panels comes before a
// panel it overlaps (a floating window under a panel), uses a draw callback, or when the window is
// multisampled (a blit cannot resolve into it).
#pragma once

#include <cstdint>
#include <vector>

#include "runtime/ecs/registry.h"
#include "systems/editor/panel_layout.h"

struct ImDrawData;

namespace sffd::editor {

// Registry resource (optional): the cache is used unless `enabled` is false (`splatffd view
// --no-ui-cache`, for comparisons).
struct UiCacheOptions {
    bool enabled = true;
};

// Counts over the frames drawn so far.
struct UiCacheStats {
    std::uint64_t frames = 0;         // frames drawn through the cache (some panels may still be direct)
    std::uint64_t direct_frames = 0;  // frames drawn without it (disabled, or a case above)
    std::uint64_t reused = 0;         // panel rectangles copied from the texture as they were
    std::uint64_t cached = 0;         // panels drawn into the texture (then copied)
    std::uint64_t drawn = 0;          // panels drawn into the window (they changed since the last frame)
};

// Draws `data` into the bound draw framebuffer: first each rectangle of `panels` (ImGui's units,
// open laid-out panels) cleared to the panel colour (ImGuiCol_WindowBg, opaque), then ImGui's triangles,
// reusing unchanged panels as described above. Needs ImGui's OpenGL backend initialised.
void draw_ui(ecs::Registry& registry, ImDrawData& data, const std::vector<PanelRect>& panels);

UiCacheStats ui_cache_stats(const ecs::Registry& registry);
// Drops the texture (before the GL context goes).
void release_ui_cache(ecs::Registry& registry);

}  // namespace sffd::editor
