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

namespace sffd::editor {

const char* tool_name(Tool tool) {
    switch (tool) {
        case Tool::select: return "select";
        case Tool::move: return "move";
        case Tool::twist: return "twist";
        case Tool::brush: return "brush";
    }
    return "?";
}

namespace {

constexpr double drag_threshold_px = 3.0;

void say(EditorState& state, std::string message) {
    log::info("editor: ", message);
    state.status = std::move(message);
}

Camera* camera_of(ecs::Registry& registry, EditorState& state) {
    if (registry.valid(state.camera))
        if (Camera* c = registry.try_get<Camera>(state.camera)) return c;
    return nullptr;
}

picking::ScreenView screen_view(const Camera& camera, const Viewport& vp) {
    return picking::make_screen_view(camera, {vp.width, vp.height});
}

glm::dmat4 lattice_model(const ecs::Registry& registry, ecs::Entity lattice) {
    return model_matrix(registry.try_get<Transform>(lattice));
}

const Lattice* active_lattice(const ecs::Registry& registry, const EditorState& state) {
    return registry.valid(state.active_lattice) ? registry.try_get<Lattice>(state.active_lattice) : nullptr;
}

// Undoing an added lattice (or redoing a removal) leaves the active entity without a Lattice: another
// lattice, if any, becomes active, so the panels and tools do not show "no lattice" beside lattices.
void keep_an_active_lattice(ecs::Registry& registry, EditorState& state) {
    if (active_lattice(registry, state)) return;
    state.active_lattice = ecs::null_entity;
    registry.view<Lattice>().each([&](ecs::Entity e, Lattice&) {
        if (!state.active_lattice) state.active_lattice = e;
    });
}

std::vector<std::uint32_t> selection_of(const ecs::Registry& registry, ecs::Entity lattice) {
    if (const auto* s = registry.try_get<picking::LatticeSelection>(lattice)) return s->indices;
    return {};
}

picking::PickHit pick_at(ecs::Registry& registry, EditorState& state, const Camera& camera, glm::dvec2 cursor,
                         bool control_points, bool surfaces) {
    picking::PickQuery q = picking::query_at_pixel(screen_view(camera, state.viewport), cursor);
    q.tolerance_px = state.click_tolerance_px;
    q.xray = state.xray;
    q.control_points = control_points;
    q.surfaces = surfaces;
    return picking::pick(registry, picking::picking_state(registry), q);
}

void click_select(ecs::Registry& registry, EditorState& state, const Camera& camera, glm::dvec2 cursor,
                  std::uint8_t modifiers) {
    const picking::SelectMode mode = picking::select_mode(modifiers & mods::shift, modifiers & mods::ctrl);
    const picking::PickHit hit = pick_at(registry, state, camera, cursor, true, true);
    if (hit.kind == picking::PickKind::control_point) {
        state.active_lattice = hit.entity;
        state.selected_entity = hit.entity;
        const std::uint32_t picked[] = {hit.index};
        const picking::LatticeSelection current{selection_of(registry, hit.entity)};
        set_selection(registry, state, hit.entity, picking::select(current, picked, mode).indices, "select");
        say(state, log::str("picked control point ", hit.index));
        return;
    }
    if (hit.kind == picking::PickKind::surface || hit.kind == picking::PickKind::gaussian)
        state.selected_entity = hit.entity;
    if (mode == picking::SelectMode::replace && registry.valid(state.active_lattice))
        set_selection(registry, state, state.active_lattice, {}, "deselect");
}

void box_select(ecs::Registry& registry, EditorState& state, const Camera& camera, glm::dvec2 a, glm::dvec2 b,
                std::uint8_t modifiers) {
    if (!active_lattice(registry, state)) return;
    const picking::SelectMode mode = picking::select_mode(modifiers & mods::shift, modifiers & mods::ctrl);
    const std::vector<std::uint32_t> inside = picking::control_points_in_rect(
        registry, picking::picking_state(registry), state.active_lattice, screen_view(camera, state.viewport),
        picking::ScreenRect{a, b}, !state.xray);
    picking::LatticeSelection current{selection_of(registry, state.active_lattice)};
    set_selection(registry, state, state.active_lattice, picking::select(current, inside, mode).indices, "box select");
    say(state, log::str("box selected ", inside.size(), " control points"));
}

void brush_dab(ecs::Registry& registry, EditorState& state, const Camera& camera, glm::dvec2 cursor,
               picking::SelectMode mode) {
    if (!active_lattice(registry, state)) return;
    const picking::PickHit hit = pick_at(registry, state, camera, cursor, false, true);
    if (hit.kind != picking::PickKind::surface && hit.kind != picking::PickKind::gaussian) return;
    const auto local = picking::surface_hit_in_lattice_space(registry, state.active_lattice, hit);
    if (!local) return;
    const auto picked = picking::brush_select(registry.get<Lattice>(state.active_lattice), *local, {});
    picking::LatticeSelection current{selection_of(registry, state.active_lattice)};
    set_selection(registry, state, state.active_lattice, picking::select(current, picked, mode).indices, "brush");
}

// Pivot and axis of a tool in world space.
glm::dvec3 tool_pivot(const ecs::Registry& registry, const EditorState& state, std::span<const std::uint32_t> points) {
    if (state.pivot_mode == PivotMode::picked_point && state.has_picked_pivot) return state.picked_pivot;
    const Lattice* lattice = active_lattice(registry, state);
    if (!lattice) return glm::dvec3(0.0);
    return glm::dvec3(lattice_model(registry, state.active_lattice) * glm::dvec4(centroid(*lattice, points), 1.0));
}

// Applies the drag's current displacement / angle to the lattice, from the snapshot.
void apply_drag(ecs::Registry& registry, const Drag& drag) {
    if (!registry.valid(drag.lattice) || !registry.has<Lattice>(drag.lattice)) return;
    const glm::dmat4 model = lattice_model(registry, drag.lattice);
    const glm::dmat4 inverse = glm::inverse(model);
    Lattice& lattice = registry.patch<Lattice>(drag.lattice);
    if (lattice.current.size() != drag.start_points.size()) return;
    if (drag.kind == Drag::Kind::move) {
        const glm::dvec3 d = glm::dvec3(inverse * glm::dvec4(drag.displacement_world, 0.0));
        stretch_points(drag.start_points, lattice.current, drag.points, d);
    } else {
        const glm::dvec3 pivot = glm::dvec3(inverse * glm::dvec4(drag.pivot_world, 1.0));
        const glm::dvec3 axis = glm::dvec3(inverse * glm::dvec4(drag.axis_world, 0.0));
        twist_points(drag.start_points, lattice.current, drag.points, pivot, axis, drag.angle);
    }
}

void remember_edit(ecs::Registry& registry, EditorState& state, const Drag& drag) {
    const glm::dmat4 inverse = glm::inverse(lattice_model(registry, drag.lattice));
    LastEdit& e = state.last_edit;
    e.lattice = drag.lattice;
    e.points = drag.points;
    if (drag.kind == Drag::Kind::move) {
        e.kind = LastEdit::Kind::stretch;
        e.displacement = glm::dvec3(inverse * glm::dvec4(drag.displacement_world, 0.0));
    } else {
        e.kind = LastEdit::Kind::twist;
        e.angle = drag.angle;
        e.axis = glm::dvec3(inverse * glm::dvec4(drag.axis_world, 0.0));
        e.pivot = glm::dvec3(inverse * glm::dvec4(drag.pivot_world, 1.0));
    }
}

bool begin_tool_drag(ecs::Registry& registry, EditorState& state, const Camera& camera, Drag& drag) {
    const Lattice* lattice = active_lattice(registry, state);
    if (!lattice) return false;
    drag.points = editable_selection(registry, state);
    if (drag.points.empty()) {
        say(state, state.pin_outer_layer && !selection_of(registry, state.active_lattice).empty()
                       ? "only pinned (outer layer) points selected: unpin with p, or go global with l"
                       : "nothing selected to edit");
        return false;
    }
    drag.kind = state.tool == Tool::move ? Drag::Kind::move : Drag::Kind::twist;
    drag.camera = camera;
    drag.lattice = state.active_lattice;
    drag.start_points = lattice->current;
    drag.before = *lattice;
    drag.pivot_world = tool_pivot(registry, state, drag.points);
    drag.axis_world = axis_direction(state.twist_axis, camera, state.custom_axis);
    drag.angle = 0.0;
    drag.displacement_world = glm::dvec3(0.0);
    return true;
}

void finish_tool_drag(ecs::Registry& registry, EditorState& state, Drag& drag) {
    if (!registry.valid(drag.lattice) || !registry.has<Lattice>(drag.lattice)) return;
    const bool is_move = drag.kind == Drag::Kind::move;
    auto change = std::make_unique<ComponentChange<Lattice>>(is_move ? "stretch" : "twist", drag.lattice, drag.before,
                                                             registry.get<Lattice>(drag.lattice));
    if (state.undo.push(std::move(change))) {
        remember_edit(registry, state, drag);
        say(state, is_move ? log::str("stretched ", drag.points.size(), " control points")
                           : log::str("twisted ", drag.points.size(), " control points by ",
                                      glm::degrees(drag.angle), " degrees"));
        if (state.auto_key) {
            const std::string edited = state.status;
            if (key_last_edit(registry, state)) say(state, edited + " (auto-key: " + state.status + ")");
        } else {
            state.unkeyed = drag.lattice;
            state.play_warned = false;
        }
    }
}

glm::dvec3 move_displacement(const EditorState& state, const Drag& drag, glm::dvec2 cursor) {
    const Camera& cam = drag.camera;
    if (state.move_axis == AxisMode::view_plane)
        return drag_in_view_plane(cam, state.viewport, drag.pivot_world, drag.start, cursor);
    if (state.move_axis == AxisMode::view) {
        // Along the viewing direction: upward drag pushes away, one pixel = one pixel's size at the pivot.
        const double depth = glm::dot(drag.pivot_world - cam.eye, glm::normalize(cam.target - cam.eye));
        const double pixel = 2.0 * depth * std::tan(glm::radians(double(cam.fov_y_degrees)) * 0.5) / state.viewport.height;
        return glm::normalize(cam.target - cam.eye) * ((drag.start.y - cursor.y) * pixel);
    }
    return drag_along_axis(cam, state.viewport, drag.pivot_world, axis_direction(state.move_axis, cam, state.custom_axis),
                           drag.start, cursor);
}

void handle_move(ecs::Registry& registry, EditorState& state, Camera& camera, glm::dvec2 cursor) {
    Drag& drag = state.drag;
    const glm::dvec2 delta = cursor - drag.last;
    switch (drag.kind) {
        case Drag::Kind::none: break;
        case Drag::Kind::pending_click:
            if (glm::length(cursor - drag.start) > drag_threshold_px) drag.kind = Drag::Kind::box;
            break;
        case Drag::Kind::box: break;
        case Drag::Kind::orbit: orbit(camera, delta); break;
        case Drag::Kind::pan: pan(camera, state.viewport, delta); break;
        case Drag::Kind::move:
            drag.displacement_world = move_displacement(state, drag, cursor);
            apply_drag(registry, drag);
            break;
        case Drag::Kind::twist:
            drag.angle += drag_angle(drag.camera, state.viewport, drag.pivot_world, drag.axis_world, drag.last, cursor);
            apply_drag(registry, drag);
            break;
        case Drag::Kind::brush:
            brush_dab(registry, state, camera, cursor,
                      drag.modifiers & mods::ctrl ? picking::SelectMode::remove : picking::SelectMode::add);
            break;
    }
    drag.last = cursor;
}

void handle_press(ecs::Registry& registry, EditorState& state, Camera& camera, const InputEvent& e) {
    state.typed = {};  // a click or drag ends a typed entry unapplied
    Drag& drag = state.drag;
    if (drag.kind != Drag::Kind::none) return;  // one gesture at a time
    drag = Drag{};
    drag.button = e.button;
    drag.modifiers = e.modifiers;
    drag.start = drag.last = state.cursor;
    if (e.button == MouseButton::right) {
        drag.kind = (e.modifiers & mods::shift) ? Drag::Kind::pan : Drag::Kind::orbit;
        return;
    }
    if (e.button == MouseButton::middle) {
        drag.kind = Drag::Kind::pan;
        return;
    }
    if (e.modifiers & mods::alt) {  // pivot at a picked surface point
        const picking::PickHit hit = pick_at(registry, state, camera, state.cursor, false, true);
        if (hit) {
            state.picked_pivot = hit.position;
            state.has_picked_pivot = true;
            state.pivot_mode = PivotMode::picked_point;
            say(state, "pivot set to the picked surface point");
        }
        return;
    }
    const bool plain = (e.modifiers & (mods::shift | mods::ctrl)) == 0;
    if (plain && (state.tool == Tool::move || state.tool == Tool::twist) && begin_tool_drag(registry, state, camera, drag))
        return;
    if (state.tool == Tool::brush) {
        drag.kind = Drag::Kind::brush;
        brush_dab(registry, state, camera, state.cursor, picking::select_mode(e.modifiers & mods::shift, e.modifiers & mods::ctrl));
        return;
    }
    drag.kind = Drag::Kind::pending_click;
}

void handle_release(ecs::Registry& registry, EditorState& state, Camera& camera, const InputEvent& e) {
    Drag& drag = state.drag;
    if (drag.kind == Drag::Kind::none || drag.button != e.button) return;
    switch (drag.kind) {
        case Drag::Kind::pending_click: click_select(registry, state, camera, drag.start, drag.modifiers); break;
        case Drag::Kind::box: box_select(registry, state, camera, drag.start, state.cursor, drag.modifiers); break;
        case Drag::Kind::move:
        case Drag::Kind::twist: finish_tool_drag(registry, state, drag); break;
        default: break;
    }
    drag = Drag{};
}

void cancel_drag(ecs::Registry& registry, EditorState& state) {
    Drag& drag = state.drag;
    if ((drag.kind == Drag::Kind::move || drag.kind == Drag::Kind::twist) && registry.valid(drag.lattice) &&
        registry.has<Lattice>(drag.lattice))
        registry.patch<Lattice>(drag.lattice).current = drag.start_points;
    drag = Drag{};
    say(state, "cancelled");
}

void set_axis(EditorState& state, AxisMode mode) {
    if (state.tool == Tool::twist) {
        state.twist_axis = mode;
    } else {
        state.move_axis = state.move_axis == mode ? AxisMode::view_plane : mode;  // pressing again frees it
        if (mode != AxisMode::view) state.twist_axis = mode;
    }
    say(state, log::str("axis: ", axis_mode_name(state.tool == Tool::twist ? state.twist_axis : state.move_axis)));
}

// Reads up to three leading numbers of a numeric entry ("dx dy dz", commas allowed) into v; returns how
// many were read. trailing_junk (when given) tells whether anything but spaces follows them.
int scan_numbers(const std::string& text, double (&v)[3], bool* trailing_junk = nullptr) {
    std::string cleaned = text;
    std::replace(cleaned.begin(), cleaned.end(), ',', ' ');
    int n = 0;
    const char* p = cleaned.c_str();
    while (n < 3) {
        char* end = nullptr;
        const double x = std::strtod(p, &end);
        if (end == p) break;
        v[n++] = x;
        p = end;
    }
    while (*p == ' ') ++p;
    if (trailing_junk) *trailing_junk = *p != '\0';
    return n;
}

// Up to three numbers of a numeric entry; returns how many were read, or -1 when junk follows them.
int parse_numbers(const std::string& text, double (&v)[3]) {
    bool junk = false;
    const int n = scan_numbers(text, v, &junk);
    return junk ? -1 : n;  // trailing junk: not a number list
}

const char* typed_char(const std::string& key) {
    static const char* digits[] = {"0", "1", "2", "3", "4", "5", "6", "7", "8", "9"};
    for (const char* d : digits)
        if (key == d) return d;
    if (key == "minus") return "-";
    if (key == "period") return ".";
    if (key == "comma") return ",";
    if (key == "space") return " ";
    return nullptr;
}

std::string typed_prompt(const EditorState& state) {
    const TypedEntry& t = state.typed;
    const AxisMode axis = t.tool == Tool::twist ? state.twist_axis : state.move_axis;
    return std::string(t.tool == Tool::twist ? "twist " : "move ") + axis_mode_name(axis) + ": " + t.text +
           "_  (Enter applies, Esc cancels)";
}

void apply_typed(ecs::Registry& registry, EditorState& state) {
    TypedEntry t = std::move(state.typed);
    state.typed = {};
    double v[3] = {0, 0, 0};
    const int n = parse_numbers(t.text, v);
    if (t.tool == Tool::twist) {
        if (n == 1) apply_twist(registry, state, v[0]);
        else say(state, "typed twist '" + t.text + "': give one angle in degrees");
        return;
    }
    const AxisMode axis = state.move_axis;
    const bool along = axis == AxisMode::x || axis == AxisMode::y || axis == AxisMode::z || axis == AxisMode::custom;
    if (n == 1 && along) {
        const Camera* camera = camera_of(registry, state);
        if (camera) apply_stretch(registry, state, axis_direction(axis, *camera, state.custom_axis) * v[0]);
    } else if (n == 3) {
        apply_stretch(registry, state, {v[0], v[1], v[2]});
    } else {
        say(state, "typed move '" + t.text + "': give one distance after x, y or z, or three values dx dy dz");
    }
}

// Keys while a typed entry is active; false when the key ends the entry and is handled as usual.
bool handle_typed_key(ecs::Registry& registry, EditorState& state, const InputEvent& e) {
    TypedEntry& t = state.typed;
    const std::string& k = e.key;
    if ((e.modifiers & (mods::ctrl | mods::alt)) == 0) {
        if (const char* c = typed_char(k)) {
            t.text += c;
            state.status = typed_prompt(state);
            return true;
        }
        if (k == "backspace") {
            if (!t.text.empty()) t.text.pop_back();
            state.status = typed_prompt(state);
            return true;
        }
        if (k == "x" || k == "y" || k == "z") {
            // The first axis key of an entry sets the axis (whatever the last entry left); the same key
            // again frees it, as outside an entry.
            const AxisMode mode = k == "x" ? AxisMode::x : k == "y" ? AxisMode::y : AxisMode::z;
            if (!t.axis_typed && t.tool == Tool::move) state.move_axis = AxisMode::view_plane;
            if (!t.axis_typed && t.tool == Tool::twist) state.twist_axis = AxisMode::view;
            t.axis_typed = true;
            set_axis(state, mode);
            state.status = typed_prompt(state);
            return true;
        }
        if (k == "enter") {
            apply_typed(registry, state);
            return true;
        }
        if (k == "escape") {
            state.typed = {};
            say(state, "typed entry cancelled");
            return true;
        }
    }
    state.typed = {};
    return false;
}

void handle_text(ecs::Registry& registry, EditorState& state, const std::string& text) {
    // Numeric entry: "dx dy dz" (commas allowed) for move, "degrees" for twist.
    state.typed = {};
    double v[3] = {0, 0, 0};
    const int n = scan_numbers(text, v);  // the leading numbers; what follows them is not checked here
    if (state.tool == Tool::twist && n >= 1) apply_twist(registry, state, v[0]);
    else if (state.tool == Tool::move && n == 3) apply_stretch(registry, state, {v[0], v[1], v[2]});
    else say(state, "numeric entry '" + text + "': move takes 'dx dy dz', twist takes 'degrees'");
}

void handle_key(ecs::Registry& registry, EditorState& state, const InputEvent& e) {
    const bool ctrl = e.modifiers & mods::ctrl, shift = e.modifiers & mods::shift;
    const std::string& k = e.key;
    if (state.drag.kind != Drag::Kind::none) {
        if (k == "escape") cancel_drag(registry, state);
        return;  // no other shortcuts mid-gesture
    }
    if (state.typed.active && handle_typed_key(registry, state, e)) return;
    if (handle_lattice_key(registry, state, e)) return;  // add/remove/refit/order/export/import (lattice_manage.h)
    if (ctrl) {
        if (k == "z" && shift) redo(registry, state);
        else if (k == "z") undo(registry, state);
        else if (k == "y") redo(registry, state);
        else if (k == "s") state.request_save = true;
        else if (k == "a") select_all(registry, state);
        else if (k == "q") state.request_quit = true;
        else if (k == "o") state.request_open_dialog = true;
        return;
    }
    if (k == "q") state.tool = Tool::select, say(state, "tool: select");
    else if (k == "g" || k == "w" || k == "r") {
        state.tool = k == "r" ? Tool::twist : Tool::move;
        state.typed = TypedEntry{true, state.tool, {}};
        say(state, std::string(k == "r" ? "tool: twist" : "tool: move") +
                       " (drag, or type a value: x/y/z axis, number, Enter)");
    }
    else if (k == "b") state.tool = Tool::brush, say(state, "tool: brush");
    else if (k == "x") set_axis(state, AxisMode::x);
    else if (k == "y") set_axis(state, AxisMode::y);
    else if (k == "z") set_axis(state, AxisMode::z);
    else if (k == "v") set_axis(state, AxisMode::view);
    else if (k == "c") set_axis(state, AxisMode::custom);
    else if (k == "a") select_all(registry, state);
    else if (k == "escape") clear_selection(registry, state);
    else if (k == "f") frame_selection(registry, state);
    else if (k == "p") state.pin_outer_layer = !state.pin_outer_layer,
                       say(state, state.pin_outer_layer ? "outer layer pinned" : "outer layer unpinned");
    else if (k == "l") state.scope = state.scope == ToolScope::local ? ToolScope::global : ToolScope::local,
                       say(state, state.scope == ToolScope::local ? "scope: local (selection)" : "scope: global (all points)");
    else if (k == "t" && shift) state.lattice_cage_only = !state.lattice_cage_only,
                                say(state, state.lattice_cage_only ? "lattice: outer cage only" : "lattice: all points and cells");
    else if (k == "t") state.xray = !state.xray, say(state, state.xray ? "x-ray on" : "x-ray off");
    else if (k == "o") state.pivot_mode = state.pivot_mode == PivotMode::centroid ? PivotMode::picked_point : PivotMode::centroid;
    else if (k == "home") reset_lattice(registry, state);
    else if (k == "k" && shift) delete_keys_at_time(registry, state);
    else if (k == "k") key_last_edit(registry, state);
    else if (k == "space") toggle_play(registry, state);
    else if (k == "n") state.auto_key = !state.auto_key, say(state, state.auto_key ? "auto-key on: edits are keyed at the clip time"
                                                                                   : "auto-key off");
    else if (k == "left") scrub_to(registry, state, clip_time(registry, state) - 1.0 / 24.0);
    else if (k == "right") scrub_to(registry, state, clip_time(registry, state) + 1.0 / 24.0);
    else if (k == "f12") state.request_screenshot = true;
}

AnimationState* animation_state(ecs::Registry& registry, const EditorState& state) {
    return registry.valid(state.active_lattice) ? registry.try_get<AnimationState>(state.active_lattice) : nullptr;
}

// Preview while moving, HQ at rest (EditorState::preview_while_moving): writes RenderSettings::quality.
void adapt_quality(ecs::Registry& registry, EditorState& state, bool scrolled) {
    auto* settings = registry.try_resource<render::RenderSettings>();
    if (!settings) return;
    if (state.rest_quality < 0) {  // first frame: the quality the view started with, the camera as it is
        state.rest_quality = int(settings->quality);
        if (const Camera* cam = camera_of(registry, state)) state.last_camera = *cam;
    }
    const Drag::Kind k = state.drag.kind;
    bool moving = scrolled || k == Drag::Kind::orbit || k == Drag::Kind::pan || k == Drag::Kind::move ||
                  k == Drag::Kind::twist || k == Drag::Kind::brush;
    registry.view<AnimationState>().each([&](ecs::Entity, AnimationState& a) { moving |= a.playing; });
    if (const Camera* cam = camera_of(registry, state)) {
        const Camera& l = state.last_camera;
        moving |= cam->eye != l.eye || cam->target != l.target || cam->up != l.up || cam->fov_y_degrees != l.fov_y_degrees;
        state.last_camera = *cam;
    }
    state.still_frames = moving ? 0 : std::min(state.still_frames + 1, 1 << 20);
    const auto rest = render::Quality(state.rest_quality);
    state.previewing = state.preview_while_moving && rest != render::Quality::preview && state.still_frames < state.refine_after;
    settings->quality = state.previewing ? render::Quality::preview : rest;
}

}  // namespace

void set_selection(ecs::Registry& registry, EditorState& state, ecs::Entity lattice, std::vector<std::uint32_t> indices,
                   const char* label) {
    if (!registry.valid(lattice) || !registry.has<Lattice>(lattice)) return;
    const auto* current = registry.try_get<picking::LatticeSelection>(lattice);
    if (current && current->indices == indices) return;
    if (!current && indices.empty()) return;
    ComponentEdit<picking::LatticeSelection> edit(registry, lattice, label);
    if (current) registry.patch<picking::LatticeSelection>(lattice).indices = std::move(indices);
    else registry.emplace<picking::LatticeSelection>(lattice, picking::LatticeSelection{std::move(indices)});
    state.undo.push(edit.finish(registry));
}

std::vector<std::uint32_t> editable_selection(const ecs::Registry& registry, const EditorState& state) {
    const Lattice* lattice = active_lattice(registry, state);
    if (!lattice) return {};
    const std::vector<std::uint32_t> sel = selection_of(registry, state.active_lattice);
    return editable_points(*lattice, sel, state.scope, state.pin_outer_layer);
}

bool scene_bounds(const ecs::Registry& registry, glm::dvec3& lo, glm::dvec3& hi) {
    bool any = false;
    lo = glm::dvec3(std::numeric_limits<double>::max());
    hi = -lo;
    registry.view<const SplatCloud>().each([&](ecs::Entity e, const SplatCloud& cloud) {
        const glm::dmat4 model = model_matrix(registry.try_get<Transform>(e));
        glm::dvec3 a(std::numeric_limits<double>::max()), b(-std::numeric_limits<double>::max());
        for (const glm::vec3& p : cloud.positions) {
            const glm::dvec3 w = glm::dvec3(model * glm::dvec4(cloud.origin + glm::dvec3(p), 1.0));
            a = glm::min(a, w), b = glm::max(b, w);
        }
        if (!cloud.positions.empty()) lo = glm::min(lo, a), hi = glm::max(hi, b), any = true;
    });
    return any;
}

EditorState& setup_editor(ecs::Registry& registry, const Viewport& viewport) {
    EditorState* state = registry.try_resource<EditorState>();
    if (!state) state = &registry.set_resource<EditorState>();
    state->viewport = viewport;
    if (!registry.valid(state->camera) || !registry.has<Camera>(state->camera)) {
        state->camera = ecs::null_entity;
        registry.view<Camera>().each([&](ecs::Entity e, Camera&) { state->camera = e; });
    }
    if (!registry.valid(state->camera)) {
        const ecs::Entity e = registry.create();
        registry.emplace<Name>(e, Name{"editor camera"});
        Camera& cam = registry.emplace<Camera>(e);
        glm::dvec3 lo, hi;
        if (scene_bounds(registry, lo, hi)) {
            cam.eye = glm::dvec3(0.35, 0.3, 1.0);  // direction only; framing sets the distance
            const glm::dvec3 corners[2] = {lo, hi};
            frame_points(cam, viewport, corners, 1.05);
            cam.near_plane = float(glm::length(hi - lo) * 1e-3);
        }
        state->camera = e;
    }
    if (!registry.valid(state->active_lattice) || !registry.has<Lattice>(state->active_lattice)) {
        state->active_lattice = ecs::null_entity;
        registry.view<Lattice>().each([&](ecs::Entity e, Lattice&) { state->active_lattice = e; });
    }
    registry.view<AnimationState>().each([&](ecs::Entity, AnimationState& s) { sffd::pause(s); });
    return *state;
}

void editor_input_system(ecs::Registry& registry, const FrameContext& frame) {
    EditorState* state = registry.try_resource<EditorState>();
    if (!state) return;
    Camera* camera = camera_of(registry, *state);
    std::vector<InputEvent> events;
    if (state->replay) events = state->replay->take(frame.frame);
    for (InputEvent& e : state->events) events.push_back(std::move(e));
    state->events.clear();
    for (InputEvent& e : events) e.frame = frame.frame;
    if (state->record) state->recorded.insert(state->recorded.end(), events.begin(), events.end());
    for (const InputEvent& e : events) {
        camera = camera_of(registry, *state);  // undo may have touched components: look it up again
        if (!camera) break;
        switch (e.kind) {
            case InputKind::move:
                state->cursor = e.position;
                handle_move(registry, *state, *camera, e.position);
                break;
            case InputKind::press: handle_press(registry, *state, *camera, e); break;
            case InputKind::release: handle_release(registry, *state, *camera, e); break;
            case InputKind::scroll: zoom(*camera, e.scroll); break;
            case InputKind::key: handle_key(registry, *state, e); break;
            case InputKind::text: handle_text(registry, *state, e.key); break;
        }
    }
    if (state->request_frame_selection) {
        state->request_frame_selection = false;
        frame_selection(registry, *state);
    }
    adapt_quality(registry, *state, std::any_of(events.begin(), events.end(), [](const InputEvent& e) {
                      return e.kind == InputKind::scroll;
                  }));
}

void undo(ecs::Registry& registry, EditorState& state) {
    if (state.drag.kind != Drag::Kind::none) return;
    const std::size_t at = state.undo.position();
    if (state.undo.undo(registry)) say(state, "undo " + state.undo.at(at - 1).label());
    else say(state, "nothing to undo");
    keep_an_active_lattice(registry, state);
}

void redo(ecs::Registry& registry, EditorState& state) {
    if (state.drag.kind != Drag::Kind::none) return;
    const std::size_t at = state.undo.position();
    if (state.undo.redo(registry)) say(state, "redo " + state.undo.at(at).label());
    else say(state, "nothing to redo");
    keep_an_active_lattice(registry, state);
}

void select_all(ecs::Registry& registry, EditorState& state) {
    const Lattice* lattice = active_lattice(registry, state);
    if (!lattice) return;
    std::vector<std::uint32_t> all(lattice->current.size());
    for (std::uint32_t i = 0; i < all.size(); ++i) all[i] = i;
    set_selection(registry, state, state.active_lattice, std::move(all), "select all");
}

void clear_selection(ecs::Registry& registry, EditorState& state) {
    if (active_lattice(registry, state)) set_selection(registry, state, state.active_lattice, {}, "deselect");
}

bool apply_stretch(ecs::Registry& registry, EditorState& state, const glm::dvec3& displacement) {
    Camera* camera = camera_of(registry, state);
    if (!camera || state.drag.kind != Drag::Kind::none) return false;
    const Tool tool = state.tool;
    state.tool = Tool::move;
    Drag drag;
    const bool ok = begin_tool_drag(registry, state, *camera, drag);
    state.tool = tool;
    if (!ok) return false;
    drag.displacement_world = displacement;
    apply_drag(registry, drag);
    finish_tool_drag(registry, state, drag);
    return true;
}

bool apply_twist(ecs::Registry& registry, EditorState& state, double degrees) {
    Camera* camera = camera_of(registry, state);
    if (!camera || state.drag.kind != Drag::Kind::none) return false;
    const Tool tool = state.tool;
    state.tool = Tool::twist;
    Drag drag;
    const bool ok = begin_tool_drag(registry, state, *camera, drag);
    state.tool = tool;
    if (!ok) return false;
    drag.angle = glm::radians(degrees);
    apply_drag(registry, drag);
    finish_tool_drag(registry, state, drag);
    return true;
}

void reset_lattice(ecs::Registry& registry, EditorState& state) {
    if (!active_lattice(registry, state)) return;
    if (state.undo.record<Lattice>(registry, state.active_lattice, "reset", [](Lattice& l) { l.current = l.rest; }))
        say(state, "lattice reset to rest");
}

void frame_selection(ecs::Registry& registry, EditorState& state) {
    Camera* camera = camera_of(registry, state);
    if (!camera) return;
    std::vector<glm::dvec3> points;
    if (const Lattice* lattice = active_lattice(registry, state)) {
        const glm::dmat4 model = lattice_model(registry, state.active_lattice);
        for (std::uint32_t i : selection_of(registry, state.active_lattice))
            if (i < lattice->current.size()) points.push_back(glm::dvec3(model * glm::dvec4(lattice->current[i], 1.0)));
    }
    if (points.size() < 2) {
        glm::dvec3 lo, hi;
        if (scene_bounds(registry, lo, hi)) points.push_back(lo), points.push_back(hi);
    }
    frame_points(*camera, state.viewport, points, 1.2);
}

double clip_time(const ecs::Registry& registry, const EditorState& state) {
    if (registry.valid(state.active_lattice))
        if (const auto* s = registry.try_get<AnimationState>(state.active_lattice)) return s->time;
    return 0.0;
}

void scrub_to(ecs::Registry& registry, EditorState& state, double time) {
    if (AnimationState* s = animation_state(registry, state)) {
        const auto* clip = registry.try_get<AnimationClip>(state.active_lattice);
        const double duration = clip ? clip->duration : 1.0;
        sffd::scrub(registry.patch<AnimationState>(state.active_lattice), std::clamp(time, 0.0, duration));
        (void)s;
    }
}

void toggle_play(ecs::Registry& registry, EditorState& state) {
    bool any_playing = false;
    registry.view<AnimationState>().each([&](ecs::Entity, AnimationState& s) { any_playing |= s.playing; });
    // Playing poses the lattice from its clip: an un-keyed stretch/twist would silently vanish.
    const ecs::Entity unkeyed = state.unkeyed;
    if (!any_playing && registry.valid(unkeyed) && registry.has<AnimationClip>(unkeyed) && registry.has<Lattice>(unkeyed)) {
        if (!state.play_warned) {
            const Name* n = registry.try_get<Name>(unkeyed);
            say(state, "playing would discard the un-keyed edit of " + (n && !n->value.empty() ? n->value : std::string("the lattice")) +
                           ": k keys it, n turns auto-key on, space again plays anyway");
            state.play_warned = true;
            return;
        }
        state.unkeyed = ecs::null_entity;  // played anyway: the clip's pose replaces it
        state.play_warned = false;
    }
    registry.view<AnimationState>().each([&](ecs::Entity e, AnimationState&) {
        AnimationState& s = registry.patch<AnimationState>(e);
        if (any_playing) sffd::pause(s);
        else sffd::play(s);
    });
    say(state, any_playing ? "paused" : "playing");
}

bool key_last_edit(ecs::Registry& registry, EditorState& state) {
    const LastEdit& edit = state.last_edit;
    if (edit.kind == LastEdit::Kind::none || !registry.valid(edit.lattice) || !registry.has<Lattice>(edit.lattice)) {
        say(state, "set key: stretch or twist something first");
        return false;
    }
    const ecs::Entity e = edit.lattice;
    auto group = std::make_unique<CommandGroup>("set key");
    ComponentEdit<AnimationClip> clip_edit(registry, e, "clip");
    ComponentEdit<AnimationState> state_edit(registry, e, "animation state");
    if (!registry.has<AnimationClip>(e)) {
        AnimationClip clip;
        clip.name = "editor";
        attach_clip(registry, e, std::move(clip), false);
    }
    const double time = registry.get<AnimationState>(e).time;
    AnimationClip& clip = registry.patch<AnimationClip>(e);
    const TrackKind kind = edit.kind == LastEdit::Kind::stretch ? TrackKind::stretch : TrackKind::twist;
    std::size_t track = clip.tracks.size();
    for (std::size_t t = 0; t < clip.tracks.size(); ++t) {
        const AnimationTrack& tr = clip.tracks[t];
        if (tr.kind == kind && tr.points == edit.points &&
            (kind == TrackKind::stretch || (tr.axis == edit.axis && tr.has_pivot && tr.pivot == edit.pivot)))
            track = t;
    }
    if (track == clip.tracks.size()) {
        track = kind == TrackKind::stretch
                    ? add_stretch_track(clip, "stretch " + std::to_string(clip.tracks.size()), edit.points)
                    : add_twist_track(clip, "twist " + std::to_string(clip.tracks.size()), edit.points, edit.axis, edit.pivot);
    }
    Keyframe key;
    key.time = time;
    key.value = kind == TrackKind::stretch ? edit.displacement : glm::dvec3(glm::degrees(edit.angle), 0.0, 0.0);
    sffd::set_key(clip.tracks[track], key);
    clip.duration = std::max(clip.duration, time);
    group->add(clip_edit.finish(registry));
    group->add(state_edit.finish(registry));
    state.undo.push(std::move(group));
    if (state.unkeyed == e) state.unkeyed = ecs::null_entity, state.play_warned = false;
    say(state, log::str("key set at ", time, " s on track ", clip.tracks[track].name));
    return true;
}

bool delete_keys_at_time(ecs::Registry& registry, EditorState& state) {
    const ecs::Entity e = state.active_lattice;
    if (!registry.valid(e) || !registry.has<AnimationClip>(e) || !registry.has<AnimationState>(e)) return false;
    const double time = registry.get<AnimationState>(e).time;
    ComponentEdit<AnimationClip> clip_edit(registry, e, "delete key");
    bool removed = false;
    AnimationClip& clip = registry.patch<AnimationClip>(e);
    for (AnimationTrack& track : clip.tracks) removed |= sffd::delete_key(track, time);
    if (removed) state.undo.push(clip_edit.finish(registry));
    say(state, removed ? log::str("deleted keys at ", time, " s") : log::str("no key at ", time, " s"));
    return removed;
}

namespace {

// Replaces the active lattice by `next` (and clears its selection) as one undo step.
bool replace_lattice(ecs::Registry& registry, EditorState& state, Lattice next, const char* label) {
    const ecs::Entity e = state.active_lattice;
    auto group = std::make_unique<CommandGroup>(label);
    ComponentEdit<Lattice> lattice_edit(registry, e, label);
    ComponentEdit<picking::LatticeSelection> selection_edit(registry, e, label);
    registry.patch<Lattice>(e) = std::move(next);
    if (registry.has<picking::LatticeSelection>(e)) registry.patch<picking::LatticeSelection>(e).indices.clear();
    group->add(lattice_edit.finish(registry));
    group->add(selection_edit.finish(registry));
    state.undo.push(std::move(group));
    state.last_edit = {};
    return true;
}

// Point clouds deformed by `lattice` (Deformers lists it).
std::vector<ecs::Entity> clouds_of(ecs::Registry& registry, ecs::Entity lattice, bool first_only) {
    std::vector<ecs::Entity> out;
    registry.view<const SplatCloud, const Deformers>().each([&](ecs::Entity e, const SplatCloud&, const Deformers& d) {
        if (first_only ? (!d.lattices.empty() && d.lattices.front() == lattice)
                       : std::find(d.lattices.begin(), d.lattices.end(), lattice) != d.lattices.end())
            out.push_back(e);
    });
    return out;
}

}  // namespace

bool resample_lattice(ecs::Registry& registry, EditorState& state, glm::ivec3 divisions) {
    const Lattice* lattice = active_lattice(registry, state);
    if (!lattice) return false;
    if (divisions == lattice->divisions) return false;
    Lattice next = *lattice;
    const glm::ivec3 up = glm::max(divisions, lattice->divisions);
    if (up != lattice->divisions) {
        auto raised = ffd::raise_resolution(next, up);
        if (!raised) return say(state, "resample: " + raised.message()), false;
        next = std::move(*raised);
    }
    if (divisions != up) {
        auto lowered = ffd::lower_resolution(next, divisions);
        if (!lowered) return say(state, "resample: " + lowered.message()), false;
        next = std::move(*lowered);
    }
    replace_lattice(registry, state, std::move(next), "resample");
    say(state, log::str("lattice resampled to ", divisions.x, "x", divisions.y, "x", divisions.z, " divisions"));
    return true;
}

bool set_lattice_basis(ecs::Registry& registry, EditorState& state, LatticeBasis basis) {
    const Lattice* lattice = active_lattice(registry, state);
    if (!lattice || lattice->basis == basis) return false;
    Lattice next = *lattice;
    next.basis = basis;
    replace_lattice(registry, state, std::move(next), "basis");
    say(state, basis == LatticeBasis::bernstein ? "basis: Bernstein" : "basis: cubic B-spline");
    return true;
}

bool fit_lattice_to(ecs::Registry& registry, EditorState& state, bool to_selection) {
    const Lattice* lattice = active_lattice(registry, state);
    if (!lattice) return false;
    glm::dvec3 lo(-std::numeric_limits<double>::max()), hi(std::numeric_limits<double>::max());
    if (to_selection) {
        const auto sel = selection_of(registry, state.active_lattice);
        if (sel.size() < 2) return say(state, "fit to selection: select at least two control points"), false;
        lo = glm::dvec3(std::numeric_limits<double>::max()), hi = -lo;
        for (std::uint32_t i : sel) lo = glm::min(lo, lattice->current[i]), hi = glm::max(hi, lattice->current[i]);
    }
    std::vector<glm::vec3> points;
    glm::dvec3 origin(0.0);
    bool have_origin = false;
    for (ecs::Entity e : clouds_of(registry, state.active_lattice, false)) {
        const SplatCloud& cloud = registry.get<SplatCloud>(e);
        if (!have_origin) origin = cloud.origin, have_origin = true;
        for (const glm::vec3& p : cloud.positions) {
            const glm::dvec3 w = cloud.origin + glm::dvec3(p);
            if (glm::all(glm::greaterThanEqual(w, lo)) && glm::all(glm::lessThanEqual(w, hi)))
                points.push_back(glm::vec3(w - origin));
        }
    }
    if (points.empty()) return say(state, "fit: no points of the clouds this lattice deforms are in range"), false;
    auto fitted = ffd::fit_lattice(points, origin, lattice->divisions, lattice->basis);
    if (!fitted) return say(state, "fit: " + fitted.message()), false;
    replace_lattice(registry, state, std::move(*fitted), to_selection ? "fit to selection" : "fit to object");
    say(state, log::str("lattice fitted to ", points.size(), " points"));
    return true;
}

bool apply_lattice_as_rest(ecs::Registry& registry, EditorState& state) {
    const Lattice* lattice = active_lattice(registry, state);
    if (!lattice) return false;
    auto group = std::make_unique<CommandGroup>("apply as rest");
    ComponentEdit<Lattice> lattice_edit(registry, state.active_lattice, "apply as rest");
    Lattice next = *lattice;
    const std::vector<ecs::Entity> clouds = clouds_of(registry, state.active_lattice, true);
    for (std::size_t c = 0; c < clouds.size(); ++c) {
        ComponentEdit<SplatCloud> cloud_edit(registry, clouds[c], "bake");
        SplatCloud& cloud = registry.patch<SplatCloud>(clouds[c]);
        ffd::BakeTarget bake{&cloud.positions, cloud.normals.empty() ? nullptr : &cloud.normals,
                             cloud.axis_u.empty() ? nullptr : &cloud.axis_u, cloud.axis_v.empty() ? nullptr : &cloud.axis_v,
                             cloud.origin};
        Lattice scratch = *lattice;  // apply_as_rest resets the lattice: bake each cloud from the same one
        if (Status st = ffd::apply_as_rest(scratch, &bake); !st) {
            group->add(cloud_edit.finish(registry));
            group->undo(registry);
            return say(state, "apply as rest: " + st.message()), false;
        }
        next = std::move(scratch);
        group->add(cloud_edit.finish(registry));
    }
    if (clouds.empty()) {
        if (Status st = ffd::apply_as_rest(next); !st) return say(state, "apply as rest: " + st.message()), false;
    }
    registry.patch<Lattice>(state.active_lattice) = std::move(next);
    group->add(lattice_edit.finish(registry));
    state.undo.push(std::move(group));
    state.last_edit = {};
    say(state, log::str("applied as rest (", clouds.size(), " clouds baked)"));
    return true;
}

}  // namespace sffd::editor
