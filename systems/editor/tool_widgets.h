// ImGui widgets of the Tools panel beyond the lattice tools' basics (panels.cpp calls them inside its
// Tools window): proportional editing's settings. They set the editor's own tool state directly, as the
// other tool widgets do (view state, not scene components: no undo step).
#pragma once

#include "systems/editor/editor_state.h"

namespace sffd::editor {

// Proportional editing (O): on/off, falloff (shift+O cycles), radius (typed; the wheel and
// PageUp/PageDown change it while dragging). Needs a current ImGui window.
void proportional_widgets(EditorState& state);

}  // namespace sffd::editor
