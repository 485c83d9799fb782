// The editor's input system (phase `input`, runtime/app/frame_loop.h).
//   first   applies PendingEdits (pending_edits.h): what the panels posted in the last present phase
//   reads   EditorState::events (resource; the window or the replayer fills it), Camera, Lattice,
//           Transform, SplatCloud / DeformedSplats (through picking), AnimationClip/State (timeline keys)
//   writes  Camera (orbit, pan, zoom, frame), Lattice::current (stretch, twist, reset; via patch so the
//           deformer re-runs) of a lattice without a clip, UnkeyedEdit of an animated one (the animation
//           writes its current), the components posted edits set, picking::LatticeSelection, AnimationClip
//           (set/delete key), AnimationState (play/pause/scrub), EditorState (tools, drag, undo stack,
//           requests); through lattice_manage.h lattice entities (Name, Transform, Lattice:
//           add/remove/refit/import) and clouds' Deformers render::RenderSettings::quality (resource; preview
//           while the view moves, EditorState::preview_while_moving)
// Point mode (ctrl+tab, point_mode.h): point_select's tools and point_edit's operations on the clouds'
// points (PointFlags, PointWeights; duplicate and separate create clouds), weights from the selection.
// Does nothing when the registry has no EditorState. Picks synchronously through the picking library
// (picking::pick on the PickingState resource): a click is answered in the frame it happens in, so a
// replayed session is deterministic frame by frame.
//
// Mouse: left click selects a control point (shift adds, ctrl removes, empty space clears), left drag
// box-selects (same modifiers); with the move/twist tool a plain left drag edits the selection; brush
// tool: left drag paints the control points with the most influence under the surface; alt+left click
// sets the twist pivot to the picked surface point. Right drag orbits, middle drag (or shift+right)
// pans, wheel zooms. Keys: see README.md (q/g/r/b tools, x/y/z/v/c axes, ctrl+z/ctrl+shift+z/ctrl+y,
// ctrl+s, f frame, a select all, escape, p pins, l local/global, t x-ray, home reset, k/shift+k keys,
// space play/pause, left/right step, f12 screenshot). Typed values after g/r: `g z 0.2 enter`,
// `r x 45 enter` (EditorState::typed; number keys and space go to the entry while it is active).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "runtime/app/frame_loop.h"
#include "runtime/ecs/registry.h"
#include "systems/editor/editor_state.h"
#include "systems/ffd/components.h"

namespace sffd::editor {

void editor_input_system(ecs::Registry& registry, const FrameContext& frame);

// Phase `picking`, after picking_system: applies the gestures whose picks were answered (click select,
// brush, alt+click pivot; EditorState::pending_picks). The input phase posts them as picking requests.
void editor_pick_system(ecs::Registry& registry, const FrameContext& frame);

// Creates the EditorState resource (if absent), picks the camera (first Camera entity; creates one
// framing every point cloud when there is none) and the first lattice as active, pauses animation
// clips (edits of a paused clip's lattice survive; space plays). Returns the state.
EditorState& setup_editor(ecs::Registry& registry, const Viewport& viewport);

// Operations behind the shortcuts and panels; each is one undo step (none when nothing changes).
void undo(ecs::Registry& registry, EditorState& state);
void redo(ecs::Registry& registry, EditorState& state);
void select_all(ecs::Registry& registry, EditorState& state);
void clear_selection(ecs::Registry& registry, EditorState& state);
// Numeric entry: stretch by `displacement` / twist by `degrees` (world units, current axis and pivot
// settings) the editable points of the active lattice.
bool apply_stretch(ecs::Registry& registry, EditorState& state, const glm::dvec3& displacement);
bool apply_twist(ecs::Registry& registry, EditorState& state, double degrees);
// Scale of the editable points about the pivot by the linear map `scale_world` (world axes: a diagonal
// for per-axis factors), with proportional editing when it is on.
bool apply_scale(ecs::Registry& registry, EditorState& state, const glm::dmat3& scale_world);
// Proportional editing's settings (EditorState::proportional): `o`, shift+o, the panel and replays.
void toggle_proportional(EditorState& state);
void cycle_falloff(EditorState& state);
void reset_lattice(ecs::Registry& registry, EditorState& state);  // current = rest
void frame_selection(ecs::Registry& registry, EditorState& state);
// World-space box of every point cloud, surface splats and Gaussians (authored positions); false when
// there is none. Each cloud's box comes from SceneBoundsCache when its entry is current (same change
// stamps of the cloud and its Transform), else from a pass over its points: always exact.
bool scene_bounds(const ecs::Registry& registry, glm::dvec3& lo, glm::dvec3& hi);

// Registry resource: each cloud's world box, with the change stamps it was computed at. The overlay (per
// lattice) and the Lattice panel ask for the scene's box every frame, so without it each frame passed over
// every point of every cloud several times, growing with the clouds. update_scene_bounds_cache()
// recomputes only clouds whose stamps moved (and drops gone ones); the editor's input system runs it at
// the start of each frame.
struct SceneBoundsCache {
    struct Entry {
        ecs::Entity entity;
        std::uint64_t cloud_version = 0, transform_version = 0;
        bool gaussian = false, any = false;
        glm::dvec3 lo{0.0}, hi{0.0};
    };
    std::vector<Entry> entries;
    std::uint64_t computed = 0;  // clouds passed over by update_scene_bounds_cache(), for tests
};
void update_scene_bounds_cache(ecs::Registry& registry);
// Control points of `lattice` (current positions) inside scene_bounds: the Lattice panel's "N inside the
// object's box" and the add-lattice status line (0 when the scene has no cloud).
std::size_t control_points_inside_object(const ecs::Registry& registry, const Lattice& lattice);
// The Outliner's type tag: "surface", "Gaussians", "lattice", "camera", "light", or "" for anything else.
const char* entity_kind(const ecs::Registry& registry, ecs::Entity e);
// Keys the last stretch/twist at the clip's current time (adds a track bound to its points when
// needed, and a clip when the lattice has none); delete_keys_at_time removes every key at the current time.
bool key_last_edit(ecs::Registry& registry, EditorState& state);
bool delete_keys_at_time(ecs::Registry& registry, EditorState& state);
// Clip time of the active lattice's clip (0 without animation) and scrubbing to a time.
double clip_time(const ecs::Registry& registry, const EditorState& state);
void scrub_to(ecs::Registry& registry, EditorState& state, double time);
void toggle_play(ecs::Registry& registry, EditorState& state);

// Lattice settings (need systems/ffd's operations; false with a status message when not built or when
// the operation fails). Each is one undo step; the selection is cleared where indices change meaning.
//   resample: new divisions, same shape (Bernstein degree elevation is exact; lowering is a least-squares
//             fit); mixed raise/lower per axis raises first, then lowers.
//   set_basis: switches Bernstein / B-spline keeping the control points (the shape changes with the basis).
//   fit: a rest lattice around the point clouds this lattice deforms (to_selection: only their points
//        inside the box of the selected control points), same divisions and basis.
//   apply_as_rest: bakes the current deformation into the clouds whose first deformer is this lattice
//        (their authored splats change: nothing moves on screen) and makes the current shape the rest.
bool resample_lattice(ecs::Registry& registry, EditorState& state, glm::ivec3 divisions);
bool set_lattice_basis(ecs::Registry& registry, EditorState& state, LatticeBasis basis);
bool fit_lattice_to(ecs::Registry& registry, EditorState& state, bool to_selection);
bool apply_lattice_as_rest(ecs::Registry& registry, EditorState& state);

// The world-space control points the edit tools would move, and their pivot and axis.
std::vector<std::uint32_t> editable_selection(const ecs::Registry& registry, const EditorState& state);

}  // namespace sffd::editor
