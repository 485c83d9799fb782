// Lattice management in the editor: add a lattice fitted around any cloud (box or oriented
// box, padding, divisions, basis: ffd::fit_lattice, the same code as `splatffd convert --lattice fit`),
// remove it, refit it, reorder a cloud's lattices, switch the active one, export / import lattice JSON.
// Every change is one undo step. Removing a lattice destroys its entity and keeps its components in the
// step; undo creates a new entity with them and maps the clouds' Deformers to it (entity_undo.h), so the
// deformation comes back bit for bit.
//
// Keys (handle_lattice_key, called first by the input system's key handler):
//   shift+a          add a lattice around the target cloud (the selected cloud, else the active lattice's,
//                    else the first) with the fit settings, last in its order; it becomes active
//   delete           remove the active lattice (unbinds it from every cloud)
//   shift+f          refit the active lattice to its clouds with the fit settings (a rest lattice)
//   tab              make the next lattice active (shift+tab: previous)
//   pageup/pagedown  move the active lattice earlier / later in its cloud's order
//   ctrl+e           export the active lattice as JSON (lattice_json_path: named after the lattice)
//   ctrl+i           import that JSON into the active lattice (or as a new lattice on the target cloud
//                    when there is none)
// Panel: the "lattices" section of the Lattice panel (lattice_manager_section, window builds): the same
// actions, the clouds' lattice order and the fit settings.
#pragma once

#include <string>

#include "runtime/ecs/registry.h"
#include "systems/editor/editor_state.h"
#include "systems/ffd/operations.h"

namespace sffd::editor {

// Registry resource (created on first use): the fit used by add and refit, and where export and import
// put the JSON: with `json_folder` set (`splatffd view` sets the scene's folder), <folder>/<active
// lattice's name>.json, so two lattices never share a file; else `json_path` (default "lattice.json").
struct LatticeFitSettings {
    ffd::FitOptions fit;
    std::string json_path = "lattice.json";
    std::string json_folder;
};
LatticeFitSettings& lattice_fit_settings(ecs::Registry& registry);
// The file ctrl+e / ctrl+i use now (see LatticeFitSettings).
std::string lattice_json_path(ecs::Registry& registry, const EditorState& state);

// The cloud add/import work on: the selected entity when it is a cloud, else the first cloud the active
// lattice deforms, else the first cloud (null when the scene has none).
ecs::Entity target_cloud(const ecs::Registry& registry, const EditorState& state);
// The lattices a cloud follows, in order (empty without Deformers).
std::vector<ecs::Entity> lattices_of(const ecs::Registry& registry, ecs::Entity cloud);

bool add_lattice(ecs::Registry& registry, EditorState& state);
bool remove_lattice(ecs::Registry& registry, EditorState& state);
bool refit_lattice(ecs::Registry& registry, EditorState& state);
bool move_lattice_in_order(ecs::Registry& registry, EditorState& state, int delta);
bool cycle_active_lattice(ecs::Registry& registry, EditorState& state, int delta);
bool export_lattice_json(ecs::Registry& registry, EditorState& state, const std::string& path);
bool import_lattice_json(ecs::Registry& registry, EditorState& state, const std::string& path);

// True when the key was one of the above (consumed).
bool handle_lattice_key(ecs::Registry& registry, EditorState& state, const InputEvent& event);

// ImGui section drawn inside the Lattice panel's window (defined in lattices_panel.cpp; window builds only).
void lattice_manager_section(ecs::Registry& registry, EditorState& state);

}  // namespace sffd::editor
