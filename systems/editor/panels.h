// Dear ImGui panels of the editor window (drawn by view_app's present-phase UI system, between the blit
// of the rendered frame and the swap). Panels: menu bar (open/save scene, screenshot, undo/redo), outliner
// of entities, inspector of the selected entity's components (editable; each edit is one undo step),
// lattice settings, tool settings with numeric entry, timeline (play/pause, scrub, set/delete key),
// profiler overlay (frame-time graph, per-system bars), status bar; and the gizmo (pivot, axis, box).
// Every action goes through the same functions as the keyboard shortcuts (editor_system.h).
#pragma once

#include "runtime/app/frame_loop.h"
#include "runtime/ecs/registry.h"

namespace sffd::editor {

// Needs a current ImGui frame (between ImGui::NewFrame and ImGui::Render).
void draw_panels(ecs::Registry& registry, const FrameContext& frame);

}  // namespace sffd::editor
