// Undoable selection change on a lattice (picking::LatticeSelection, owned by systems/picking). The
// selection rules themselves (click/shift/ctrl, box, brush) are picking's (systems/picking/selection.h).
#pragma once

#include <cstdint>
#include <vector>

#include "runtime/ecs/registry.h"
#include "systems/editor/editor_state.h"

namespace sffd::editor {

// Sets the lattice's selection to `indices` (sorted, unique) as one undo step; no step when unchanged.
void set_selection(ecs::Registry& registry, EditorState& state, ecs::Entity lattice,
                   std::vector<std::uint32_t> indices, const char* label);

}  // namespace sffd::editor
