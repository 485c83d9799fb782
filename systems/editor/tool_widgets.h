// ImGui widgets of the Tools panel beyond the lattice tools' basics (panels.cpp calls them inside its
// Tools window): proportional editing's settings. They set the editor's own tool state directly, as the
// other tool widgets do (view state, not scene components: no undo step).
#pragma once

#include <string>

#include "runtime/ecs/registry.h"
#include "systems/editor/editor_state.h"

namespace sffd::editor {

// Proportional editing (O): on/off, falloff (shift+O cycles), radius (typed; the wheel and
// PageUp/PageDown change it while dragging). Needs a current ImGui window.
void proportional_widgets(EditorState& state);

// The edit mode (ctrl+tab) as two radio buttons; switching posts set_edit_mode (point_mode.h).
void edit_mode_widgets(ecs::Registry& registry, EditorState& state);
// Point mode's part of the Tools panel: the point tool, mode, radii and tolerance (view state, set
// directly), and the commands and operations (posted: each one undo step in the next input phase).
void point_tools_widgets(ecs::Registry& registry, EditorState& state);
// The status bar's text in point mode: tool, mode, x-ray, the points selected / hidden / deleted.
std::string point_status_text(const ecs::Registry& registry, const EditorState& state);
// Point mode's gestures over the view (ImGui foreground): box, lasso path, polygon, brush circle.
void point_gizmo(const ecs::Registry& registry, const EditorState& state);

}  // namespace sffd::editor
