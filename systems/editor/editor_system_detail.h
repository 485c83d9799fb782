// Internals of the editor's input system shared by its source files (helpers over EditorState, the tool
// gestures). Not a public header: only systems/editor's own sources include it.
#pragma once

#include "systems/editor/editor_system.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/gtc/matrix_inverse.hpp>

#include "runtime/core/log.h"
#include "runtime/scene/components.h"
#include "systems/editor/selection_edit.h"
#include "systems/ffd/components.h"
#include "systems/picking/components.h"
#include "systems/picking/picking_system.h"
#include "systems/picking/selection.h"
#include "systems/picking/world_space.h"
#include "systems/animation/components.h"
#include "systems/animation/editing.h"
#include "systems/editor/lattice_manage.h"
#include "systems/ffd/operations.h"
#include "systems/splat_render/splat_render.h"

namespace sffd::editor::detail {

constexpr double drag_threshold_px = 3.0;

// editor_system.cpp: small helpers over the editor state.
void say(EditorState& state, std::string message);
Camera* camera_of(ecs::Registry& registry, EditorState& state);
picking::ScreenView screen_view(const Camera& camera, const Viewport& vp);
glm::dmat4 lattice_model(const ecs::Registry& registry, ecs::Entity lattice);
const Lattice* active_lattice(const ecs::Registry& registry, const EditorState& state);
void keep_an_active_lattice(ecs::Registry& registry, EditorState& state);
std::vector<std::uint32_t> selection_of(const ecs::Registry& registry, ecs::Entity lattice);

// One writer of Lattice::current per lattice (systems/editor/README.md, "Edits and the animation"): a
// lattice with a clip that fits it is animated, and animation_system writes its current; the editor's
// stretch, twist and reset of it write the clip's UnkeyedEdit (the pose at the clip time), which the
// animation shows at that time, or key it (auto-key). Any other lattice's current is the editor's.
bool animated_lattice(const ecs::Registry& registry, ecs::Entity lattice);
// The control points the lattice shows this frame: an animated lattice's un-keyed edit when the clip
// time shows it, else Lattice::current.
std::vector<glm::dvec3> shown_pose(const ecs::Registry& registry, ecs::Entity lattice);
// Emplaces or patches the un-keyed edit of an animated lattice.
void set_unkeyed_pose(ecs::Registry& registry, ecs::Entity lattice, UnkeyedEdit edit);

// editor_tools.cpp: mouse gestures (selection clicks and boxes, the brush, tool drags).
void apply_drag(ecs::Registry& registry, const Drag& drag);
bool begin_tool_drag(ecs::Registry& registry, EditorState& state, const Camera& camera, Drag& drag);
void finish_tool_drag(ecs::Registry& registry, EditorState& state, Drag& drag);
void handle_move(ecs::Registry& registry, EditorState& state, Camera& camera, glm::dvec2 cursor);
void handle_press(ecs::Registry& registry, EditorState& state, Camera& camera, const InputEvent& e);
void handle_release(ecs::Registry& registry, EditorState& state, Camera& camera, const InputEvent& e);
// Applies the gestures whose picks the picking phase answered (EditorState::pending_picks), in order.
void apply_pending_picks(ecs::Registry& registry, EditorState& state);
void cancel_drag(ecs::Registry& registry, EditorState& state);
bool is_tool_drag(Drag::Kind kind);  // move, twist or scale
// Proportional editing during a tool drag: the radius times `factor` (the wheel, PageUp/PageDown), the
// drag applied again with it; false (nothing done) outside a tool drag or with proportional editing off.
bool change_proportional_radius(ecs::Registry& registry, EditorState& state, double factor);
// A scale by `factor` along the axis (x, y, z, custom), or uniform (view plane, view); world axes.
glm::dmat3 scale_matrix(AxisMode axis, const Camera& camera, const glm::dvec3& custom_axis, double factor);

// Posts a pick through the cursor for the picking phase (surfaces; control points too when asked) and the
// gesture to apply to its answer (editor_pick_system, right after picking).
void post_pick_at(ecs::Registry& registry, EditorState& state, const Camera& camera, glm::dvec2 cursor,
                  bool control_points, PendingPick action);

// point_tools.cpp: point mode's mouse gestures (point_mode.h).
bool is_point_drag(Drag::Kind kind);
void point_press(ecs::Registry& registry, EditorState& state, const Camera& camera, const InputEvent& e);
void point_move(ecs::Registry& registry, EditorState& state, const Camera& camera, glm::dvec2 cursor);
void point_release(ecs::Registry& registry, EditorState& state, const Camera& camera, const InputEvent& e);
void cancel_point_drag(ecs::Registry& registry, EditorState& state);
// Applies a point gesture in the picking phase (its pick answered, or needing none).
void apply_point_pick(ecs::Registry& registry, EditorState& state, const PendingPick& pick);

// editor_input.cpp
AnimationState* animation_state(ecs::Registry& registry, const EditorState& state);

}  // namespace sffd::editor::detail
