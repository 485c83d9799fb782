// Point mode's undo steps, operations and keys (point_mode.h); the mouse gestures are point_tools.cpp.
#include "systems/editor/point_mode.h"

#include <memory>

#include "runtime/core/log.h"
#include "runtime/scene/components.h"
#include "systems/editor/editor_state.h"
#include "systems/editor/editor_system.h"
#include "systems/editor/input_record.h"
#include "systems/editor/point_weights.h"
#include "systems/gaussian/components.h"

namespace sffd::editor {

namespace {

void say(EditorState& state, std::string message) {
    log::info("editor: ", message);
    state.status = std::move(message);
}

std::string name_of(const ecs::Registry& r, ecs::Entity e) {
    const Name* n = r.valid(e) ? r.try_get<Name>(e) : nullptr;
    return n && !n->value.empty() ? n->value : "cloud";
}

std::size_t changed(const std::vector<PointSelectionChange::Part>& parts) {
    std::size_t n = 0;
    for (const auto& p : parts) n += p.second.changed();
    return n;
}

}  // namespace

// ---- Undo steps ---------------------------------------------------------------------------------------

PointSelectionChange::PointSelectionChange(std::string label, std::vector<Part> parts)
    : Command(std::move(label)) {
    for (Part& p : parts)
        if (!p.second.empty()) m_parts.push_back(std::move(p));
}

void PointSelectionChange::undo(ecs::Registry& registry, EntityMap& map) const {
    for (std::size_t i = m_parts.size(); i-- > 0;)
        point_select::apply_delta(registry, map(m_parts[i].first), m_parts[i].second);
}

void PointSelectionChange::redo(ecs::Registry& registry, EntityMap& map) const {
    for (const Part& p : m_parts) point_select::apply_delta(registry, map(p.first), p.second);
}

bool PointSelectionChange::empty() const { return m_parts.empty(); }

std::size_t PointSelectionChange::bytes() const {
    std::size_t n = sizeof(*this) + label().capacity() + m_parts.capacity() * sizeof(Part);
    for (const Part& p : m_parts) n += p.second.bytes();
    return n;
}

PointEditChange::PointEditChange(point_edit::PointEditStep step)
    : Command(step.label), m_cloud(step.cloud), m_created(step.created), m_step(std::move(step)) {}

void PointEditChange::undo(ecs::Registry& registry, EntityMap& map) const {
    m_step.cloud = map(m_cloud);
    m_step.created = m_created ? map(m_created) : ecs::null_entity;
    point_edit::undo(registry, m_step);
}

void PointEditChange::redo(ecs::Registry& registry, EntityMap& map) const {
    m_step.cloud = map(m_cloud);
    const ecs::Entity gone = m_created ? map(m_created) : ecs::null_entity;
    const ecs::Entity made = point_edit::redo(registry, m_step);
    if (m_created && made) map.map(gone, made);  // the old id (and every earlier one) resolves to it
}

std::size_t PointEditChange::bytes() const {
    return sizeof(*this) - sizeof(m_step) + m_step.bytes() + label().capacity();
}

// ---- Clouds -------------------------------------------------------------------------------------------

std::vector<ecs::Entity> point_clouds(const ecs::Registry& registry) {
    std::vector<ecs::Entity> out;
    registry.each_entity([&](ecs::Entity e) {
        if (registry.has<SplatCloud>(e) || registry.has<GaussianCloud>(e)) out.push_back(e);
    });
    return out;
}

point_edit::PointCounts point_totals(const ecs::Registry& registry) {
    point_edit::PointCounts t;
    for (ecs::Entity e : point_clouds(registry)) {
        const point_edit::PointCounts c = point_edit::count_points(registry, e);
        t.points += c.points, t.selected += c.selected, t.hidden += c.hidden, t.deleted += c.deleted;
    }
    return t;
}

// ---- Modes --------------------------------------------------------------------------------------------

void set_edit_mode(ecs::Registry& registry, EditorState& state, EditMode mode) {
    if (state.drag.kind != Drag::Kind::none) return;  // one gesture at a time
    state.points.path.clear();
    state.typed = {};
    state.mode = mode;
    if (mode == EditMode::points) {
        const point_edit::PointCounts t = point_totals(registry);
        say(state, log::str("point mode (", point_tool_name(state.points.settings.tool), "): ", t.selected,
                            " of ", t.points, " points selected; ctrl+tab: lattice mode"));
    } else {
        say(state, "lattice mode: control points; ctrl+tab: point mode");
    }
}

void toggle_edit_mode(ecs::Registry& registry, EditorState& state) {
    set_edit_mode(registry, state, state.mode == EditMode::points ? EditMode::lattice : EditMode::points);
}

// ---- Selection commands -------------------------------------------------------------------------------

void push_selection_step(ecs::Registry& registry, EditorState& state, std::string label,
                         std::vector<PointSelectionChange::Part> parts) {
    const std::size_t n = changed(parts);
    if (state.undo.push(std::make_unique<PointSelectionChange>(label, std::move(parts))))
        say(state,
            log::str(label, ": ", n, " points changed, ", point_totals(registry).selected, " selected"));
    else say(state, label + ": the selection did not change");
}

namespace {

template <class Fn>
void select_each(ecs::Registry& registry, EditorState& state, const char* label, Fn&& fn) {
    std::vector<PointSelectionChange::Part> parts;
    for (ecs::Entity e : point_clouds(registry)) parts.emplace_back(e, fn(e));
    const std::size_t n = changed(parts);
    if (state.undo.push(std::make_unique<PointSelectionChange>(label, std::move(parts))))
        say(state,
            log::str(label, ": ", n, " points changed, ", point_totals(registry).selected, " selected"));
    else say(state, std::string(label) + ": the selection did not change");
}

}  // namespace

void points_select_all(ecs::Registry& registry, EditorState& state) {
    select_each(registry, state, "select all points",
                [&](ecs::Entity e) { return point_select::select_all(registry, e); });
}

void points_select_none(ecs::Registry& registry, EditorState& state) {
    select_each(registry, state, "deselect points",
                [&](ecs::Entity e) { return point_select::select_none(registry, e); });
}

void points_invert(ecs::Registry& registry, EditorState& state) {
    select_each(registry, state, "invert point selection",
                [&](ecs::Entity e) { return point_select::invert_selection(registry, e); });
}

void points_grow(ecs::Registry& registry, EditorState& state, double distance) {
    select_each(registry, state, "grow point selection", [&](ecs::Entity e) {
        return point_select::grow_selection(registry, state.points.select, e, distance);
    });
}

void points_shrink(ecs::Registry& registry, EditorState& state, double distance) {
    select_each(registry, state, "shrink point selection", [&](ecs::Entity e) {
        return point_select::shrink_selection(registry, state.points.select, e, distance);
    });
}

std::vector<PointSelectionChange::Part> points_select_region(ecs::Registry& registry, EditorState& state,
                                                             const picking::ScreenView& view,
                                                             const point_select::ScreenRegion& region,
                                                             PointMode mode) {
    point_select::ScreenOptions options;
    options.mode = point_select::Mode(int(mode));
    options.visible_only = !state.xray;
    std::vector<PointSelectionChange::Part> parts;
    for (ecs::Entity e : point_clouds(registry))
        parts.emplace_back(
            e, point_select::select_region(registry, state.points.select, e, view, region, options));
    return parts;
}

// ---- Operations ---------------------------------------------------------------------------------------

namespace {

// Runs a point_edit operation on every cloud as one undo step; returns the last entity it created.
ecs::Entity run_operation(ecs::Registry& registry, EditorState& state, const char* label,
                          point_edit::PointEditStep (*op)(ecs::Registry&, ecs::Entity)) {
    auto group = std::make_unique<CommandGroup>(label);
    std::size_t points = 0;
    ecs::Entity created = ecs::null_entity;
    std::string names;
    for (ecs::Entity e : point_clouds(registry)) {  // a list taken first: separate adds clouds
        point_edit::PointEditStep step = op(registry, e);
        if (step.empty()) continue;
        points += step.points.size();
        if (step.created) {
            created = step.created;
            names += (names.empty() ? "'" : ", '") + name_of(registry, created) + "'";
        }
        group->add(std::make_unique<PointEditChange>(std::move(step)));
    }
    if (!state.undo.push(std::move(group))) {
        say(state, std::string(label) + ": " +
                       (std::string(label) == "unhide all" ? "no hidden points" : "no points selected"));
        return ecs::null_entity;
    }
    say(state, log::str(label, ": ", points, " points", names.empty() ? "" : " into ", names));
    return created;
}

}  // namespace

void points_hide(ecs::Registry& registry, EditorState& state) {
    run_operation(registry, state, "hide", point_edit::hide_selected);
}
void points_unhide(ecs::Registry& registry, EditorState& state) {
    run_operation(registry, state, "unhide all", point_edit::unhide_all);
}
void points_delete(ecs::Registry& registry, EditorState& state) {
    run_operation(registry, state, "delete", point_edit::delete_selected);
}
void points_duplicate(ecs::Registry& registry, EditorState& state) {
    if (const ecs::Entity e = run_operation(registry, state, "duplicate", point_edit::duplicate_selected))
        state.selected_entity = e;
}
void points_separate(ecs::Registry& registry, EditorState& state) {
    if (const ecs::Entity e = run_operation(registry, state, "separate", point_edit::separate_selected))
        state.selected_entity = e;
}

// ---- Keys ---------------------------------------------------------------------------------------------

namespace {

void set_tool(EditorState& state, PointTool tool) {
    state.points.settings.tool = tool;
    state.points.path.clear();
    const char* how = tool == PointTool::select    ? "click a point, drag a box"
                      : tool == PointTool::lasso   ? "drag a path"
                      : tool == PointTool::polygon ? "click the corners, Enter closes"
                      : tool == PointTool::brush   ? "drag; PageUp/PageDown size the brush"
                      : tool == PointTool::sphere  ? "press on the surface, drag the radius"
                                                   : "click a point: its colour within the tolerance";
    say(state, log::str("point tool: ", point_tool_name(tool), " (", how, ")"));
}

void resize(EditorState& state, double factor) {
    PointToolSettings& s = state.points.settings;
    if (s.tool == PointTool::sphere) {
        s.sphere_radius = std::clamp(s.sphere_radius * factor, 1e-6, 1e6);
        say(state, log::str("sphere radius ", s.sphere_radius));
    } else {
        s.brush_radius_px = std::clamp(s.brush_radius_px * factor, 1.0, 4096.0);
        say(state, log::str("brush radius ", s.brush_radius_px, " px"));
    }
}

void close_polygon(ecs::Registry& registry, EditorState& state);

}  // namespace

bool handle_point_key(ecs::Registry& registry, EditorState& state, const InputEvent& e) {
    const bool ctrl = e.modifiers & mods::ctrl, shift = e.modifiers & mods::shift,
               alt = e.modifiers & mods::alt;
    const std::string& k = e.key;
    PointEditing& p = state.points;
    if (p.settings.tool == PointTool::polygon && !p.path.empty() && !ctrl && !alt) {
        if (k == "enter") return close_polygon(registry, state), true;
        if (k == "backspace") {
            p.path.pop_back();
            return say(state, log::str("polygon: ", p.path.size(), " corners")), true;
        }
        if (k == "escape") return p.path.clear(), say(state, "polygon cancelled"), true;
    }
    if (ctrl && !alt) {
        if (k == "i" && !shift) points_invert(registry, state);
        else if (k == "a" && !shift) points_select_all(registry, state);
        else if (k == "equal" || k == "plus") points_grow(registry, state, p.settings.grow_distance);
        else if (k == "minus") points_shrink(registry, state, p.settings.grow_distance);
        else return false;  // undo, redo, save, open, quit, export: every mode's
        return true;
    }
    if (alt) {
        if (k == "a") points_select_none(registry, state);
        else if (k == "h") points_unhide(registry, state);
        else if (k == "w") clear_weights(registry, state);
        return true;  // no other alt key: nothing (not the plain key)
    }
    if (shift) {
        if (k == "d") points_duplicate(registry, state);
        else if (k == "l") set_tool(state, PointTool::polygon);
        else if (k == "b") set_tool(state, PointTool::sphere);
        else if (k == "w")
            weights_from_selection(registry, state, p.settings.weight_radius, p.settings.weight_falloff);
        else if (k == "a" || k == "f" || k == "t" || k == "k" || k == "o" || k == "tab")
            return false;  // add / refit lattice, cage, keys, falloff, previous lattice
        else say(state, "shift+" + k + " is a lattice-mode key (ctrl+tab: lattice mode)");
        return true;
    }
    if (k == "q") set_tool(state, PointTool::select);
    else if (k == "l") set_tool(state, PointTool::lasso);
    else if (k == "b") set_tool(state, PointTool::brush);
    else if (k == "e") set_tool(state, PointTool::colour);
    else if (k == "a") points_select_all(registry, state);
    else if (k == "escape") points_select_none(registry, state);
    else if (k == "h") points_hide(registry, state);
    else if (k == "x" || k == "delete") points_delete(registry, state);
    else if (k == "p") points_separate(registry, state);
    else if (k == "pageup") resize(state, proportional_radius_step);
    else if (k == "pagedown") resize(state, 1.0 / proportional_radius_step);
    else if (k == "f" || k == "t" || k == "space" || k == "left" || k == "right" || k == "n" || k == "k" ||
             k == "tab" || k == "home" || k == "f12" || k == "o")
        return false;  // framing, x-ray, playback, keys, lattices, screenshot, proportional: every mode's
    else say(state, k + " is a lattice-mode key (ctrl+tab: lattice mode)");
    return true;
}

void handle_point_field(EditorState& state, const InputEvent& e) {
    if (e.key == "view.lattice") {
        state.show_lattice = e.value != 0.0;
        return say(state, state.show_lattice ? "lattice overlay on" : "lattice overlay off");
    }
    if (e.key == "view.weights") {
        state.show_weights = e.value != 0.0;
        return say(state,
                   state.show_weights ? "weights shown (blue 0, green 0.5, red 1)" : "weights not shown");
    }
    set_point_field(state.points.settings, e.key, e.value);
    const PointToolSettings& s = state.points.settings;
    say(state,
        log::str("point settings: mode ", point_mode_name(s.mode), ", brush ", s.brush_radius_px,
                 " px, sphere ", s.sphere_radius, ", colour tolerance ", s.colour_tolerance, ", grow ",
                 s.grow_distance, ", weights ", falloff_name(s.weight_falloff), " r ", s.weight_radius));
}

namespace {

void close_polygon(ecs::Registry& registry, EditorState& state) {
    PointEditing& p = state.points;
    std::vector<glm::dvec2> corners = std::move(p.path);
    p.path.clear();
    if (corners.size() < 3) return say(state, "polygon: give at least 3 corners");
    const Camera* camera = registry.valid(state.camera) ? registry.try_get<Camera>(state.camera) : nullptr;
    if (!camera) return;
    PendingPick pick{PendingPick::Action::point_region};
    pick.region = point_select::polygon_region(std::move(corners));
    pick.view = picking::make_screen_view(*camera, {state.viewport.width, state.viewport.height});
    pick.point_mode = p.gesture_mode;
    pick.visible_only = !state.xray;
    state.pending_picks.push_back(std::move(pick));  // after this frame's deformation (editor_pick_system)
}

}  // namespace

}  // namespace sffd::editor
