// Point editing in the editor (systems/editor/README.md, "Point mode"): the selection tools of
// systems/point_select and the operations of systems/point_edit on every cloud of the scene (surface
// splats and Gaussians), each one step of the editor's undo stack, and weights from the selection
// (point_weights.h).
//
// Which clouds: every SplatCloud and GaussianCloud entity. A screen tool (box, lasso, polygon, brush)
// asks each cloud for its points in the region, and a set or intersect changes every cloud (a box that
// misses a cloud clears its selection, as a box in empty space does). A click goes to the cloud picking's
// ray hits first (the surface in front), then point_select's click rule in that cloud. Visible only (x-ray
// off) is point_select's depth buffer per cloud: one cloud does not hide another's points.
//
// Undo: a selection step keeps point_select's deltas (at most 2 bytes a changed point); an operation
// keeps point_edit's steps (the same bound). Separate and duplicate create an entity: undo destroys it,
// redo creates it again under a new id, which the step records in the stack's EntityMap (old id -> new),
// so later steps (a lattice added to the part, its Deformers) and the editor's references follow it.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/ecs/registry.h"
#include "systems/editor/point_settings.h"
#include "systems/editor/undo_stack.h"
#include "systems/point_edit/point_edit.h"
#include "systems/point_select/point_select.h"

namespace sffd::editor {

struct EditorState;
struct InputEvent;

// What point mode keeps between events: the settings, the gesture in progress, point_select's caches.
struct PointEditing {
    PointToolSettings settings;
    std::vector<glm::dvec2> path;             // lasso: the drag's path so far; polygon: the clicked vertices
    PointMode gesture_mode = PointMode::set;  // of the polygon being clicked
    // A brush stroke's dabs so far, per cloud (composed into one undo step on release).
    std::vector<std::pair<ecs::Entity, point_select::SelectionDelta>> stroke;
    // Sphere: the centre picked at press (world) and the radius dragged out since (0: none yet).
    bool has_centre = false;
    glm::dvec3 centre{0.0};
    double dragged_radius = 0.0;
    point_select::PointSelectState select;
};

// ---- Undo steps ---------------------------------------------------------------------------------------

// A selection change of several clouds: point_select's deltas toggle their bits, so undo and redo are the
// same call (apply_delta is its own inverse).
class PointSelectionChange final : public Command {
public:
    using Part = std::pair<ecs::Entity, point_select::SelectionDelta>;
    PointSelectionChange(std::string label, std::vector<Part> parts);
    void undo(ecs::Registry& registry, EntityMap& map) const override;
    void redo(ecs::Registry& registry, EntityMap& map) const override;
    bool empty() const override;
    std::size_t bytes() const override;
    const std::vector<Part>& parts() const { return m_parts; }

private:
    std::vector<Part> m_parts;
};

// One point_edit step (hide, unhide, delete, duplicate, separate) of one cloud. The cloud and the entity
// the step created are resolved through the map before undo and redo; redo's new entity is recorded.
class PointEditChange final : public Command {
public:
    explicit PointEditChange(point_edit::PointEditStep step);
    void undo(ecs::Registry& registry, EntityMap& map) const override;
    void redo(ecs::Registry& registry, EntityMap& map) const override;
    bool empty() const override { return m_step.empty(); }
    std::size_t bytes() const override;
    const point_edit::PointEditStep& step() const { return m_step; }
    ecs::Entity created() const { return m_created; }  // the id the creation had when it was made

private:
    ecs::Entity m_cloud, m_created;
    mutable point_edit::PointEditStep m_step;
};

// ---- The clouds and their selections ------------------------------------------------------------------

// Every cloud entity (SplatCloud or GaussianCloud), in registry order.
std::vector<ecs::Entity> point_clouds(const ecs::Registry& registry);
// Sums of point_edit::count_points over every cloud.
point_edit::PointCounts point_totals(const ecs::Registry& registry);

// ---- Operations (each one undo step; none when nothing changed) ---------------------------------------

void toggle_edit_mode(ecs::Registry& registry, EditorState& state);
void set_edit_mode(ecs::Registry& registry, EditorState& state, EditMode mode);

void points_select_all(ecs::Registry& registry, EditorState& state);
void points_select_none(ecs::Registry& registry, EditorState& state);
void points_invert(ecs::Registry& registry, EditorState& state);
void points_grow(ecs::Registry& registry, EditorState& state, double distance);
void points_shrink(ecs::Registry& registry, EditorState& state, double distance);

void points_hide(ecs::Registry& registry, EditorState& state);
void points_unhide(ecs::Registry& registry, EditorState& state);
void points_delete(ecs::Registry& registry, EditorState& state);
// Duplicate / separate: one new entity per cloud with a selection; the last becomes the selected entity
// (so shift+a fits a lattice to it, lattice_manage.h's target_cloud).
void points_duplicate(ecs::Registry& registry, EditorState& state);
void points_separate(ecs::Registry& registry, EditorState& state);

// A region of the screen (box, lasso, polygon, a brush dab) in the current view, for every cloud, as one
// step; `label` names it. Returns the step's parts (for a brush stroke, composed by the caller).
std::vector<PointSelectionChange::Part> points_select_region(ecs::Registry& registry, EditorState& state,
                                                             const picking::ScreenView& view,
                                                             const point_select::ScreenRegion& region,
                                                             PointMode mode);
// Records parts already applied as one step (none when nothing changed) and says what changed.
void push_selection_step(ecs::Registry& registry, EditorState& state, std::string label,
                         std::vector<PointSelectionChange::Part> parts);

// ---- Input --------------------------------------------------------------------------------------------

// Point mode's keys (README.md "Point mode"); true when the key was consumed. Called by the input
// system's key handler in point mode before the lattice keys; a lattice-only key is consumed with a
// status message.
bool handle_point_key(ecs::Registry& registry, EditorState& state, const InputEvent& event);
// A replayed `set point.*` / `weight.*` / `view.lattice` field.
void handle_point_field(EditorState& state, const InputEvent& event);

}  // namespace sffd::editor
