// Dear ImGui panels of the editor window (drawn by view_app's present-phase UI system, between the blit
// of the rendered frame and the swap). Panels: menu bar (open/save scene, screenshot, undo/redo), outliner
// of entities, inspector of the selected entity's components (editable; each edit is one undo step),
// lattice settings, tool settings with numeric entry, timeline (play/pause, scrub, set/delete key),
// profiler overlay (frame-time graph, per-system bars), status bar; and the gizmo (pivot, axis, box).
// Every action goes through the same functions as the keyboard shortcuts (editor_system.h).
#pragma once

#include <string>
#include <vector>

#include "runtime/app/frame_loop.h"
#include "runtime/ecs/registry.h"
#include "systems/editor/panel_layout.h"

namespace sffd::editor {

// Needs a current ImGui frame (between ImGui::NewFrame and ImGui::Render).
// Panels are laid out from the window size every frame (panel_layout.h).
void draw_panels(ecs::Registry& registry, const FrameContext& frame);

// The windows the last draw_panels drew and where (ImGui's own position and size after Begin): the
// laid-out panels by title, the menu bar ("##menu") and the status bar ("##status"). `splatffd view
// --panel-rects-json` writes them; tests check they neither overlap nor leave the window.
struct NamedPanelRect {
    std::string name;
    PanelRect rect;
};
std::vector<NamedPanelRect> panel_rects(const ecs::Registry& registry);

// The laid-out panels that are open (not collapsed) in the last draw_panels, in ImGui's window units. ImGui
// draws no background for them: the UI system clears these rectangles to the opaque panel colour
// (ImGuiCol_WindowBg) before ImGui draws, since on a CPU rasteriser a clear costs a small part of the
// blended triangles ImGui would draw there (the sphere's panels at 1280x720, 2-core machine: about 1 ms a
// frame).
std::vector<PanelRect> panel_backgrounds(const ecs::Registry& registry);

// The open (save = false) / save-as dialog: a file browser starting in EditorState::last_folder; Escape
// or Cancel closes it. Needs a current ImGui frame; the dialog is drawn by draw_panels
// (file_dialog_window, file_dialog.cpp). Its folder and listing are a registry resource.
struct EditorState;
void open_file_dialog(ecs::Registry& registry, EditorState& state, bool save);
bool file_dialog_open();
void file_dialog_window(ecs::Registry& registry, EditorState& state);

// SameLine() when a button labelled `next_label` still fits on the current line of the window, so rows
// of buttons wrap in narrow panels instead of being cut at the window's edge.
void same_line_if_fits(const char* next_label);

}  // namespace sffd::editor
