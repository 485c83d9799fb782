// The editor's keyboard input (shortcuts, typed values), the adaptive render quality and the input system.
#include "systems/editor/editor_system_detail.h"
#include "systems/editor/pending_edits.h"

#include "systems/editor/material_edit.h"
#include "systems/ffd/preview_budget.h"

namespace sffd::editor {

namespace detail {

namespace {

void set_axis(EditorState& state, AxisMode mode) {
    if (state.tool == Tool::twist) {
        state.twist_axis = mode;
    } else {
        state.move_axis = state.move_axis == mode ? AxisMode::view_plane : mode;  // pressing again frees it
        if (mode != AxisMode::view) state.twist_axis = mode;
    }
    say(state,
        log::str("axis: ", axis_mode_name(state.tool == Tool::twist ? state.twist_axis : state.move_axis)));
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

// The scale by three factors along the world axes.
glm::dmat3 diagonal(const double (&v)[3]) {
    return glm::dmat3(glm::dvec3(v[0], 0.0, 0.0), glm::dvec3(0.0, v[1], 0.0), glm::dvec3(0.0, 0.0, v[2]));
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
    const char* verb = t.tool == Tool::twist ? "twist " : t.tool == Tool::scale ? "scale " : "move ";
    return std::string(verb) + axis_mode_name(axis) + ": " + t.text + "_  (Enter applies, Esc cancels)";
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
    const bool along =
        axis == AxisMode::x || axis == AxisMode::y || axis == AxisMode::z || axis == AxisMode::custom;
    if (t.tool == Tool::scale) {
        const Camera* camera = camera_of(registry, state);
        if (n == 1 && camera)
            apply_scale(registry, state, scale_matrix(axis, *camera, state.custom_axis, v[0]));
        else if (n == 3) apply_scale(registry, state, diagonal(v));
        else
            say(state, "typed scale '" + t.text +
                           "': give one factor (along x, y or z after the axis key) or sx sy sz");
        return;
    }
    if (n == 1 && along) {
        const Camera* camera = camera_of(registry, state);
        if (camera) apply_stretch(registry, state, axis_direction(axis, *camera, state.custom_axis) * v[0]);
    } else if (n == 3) {
        apply_stretch(registry, state, {v[0], v[1], v[2]});
    } else {
        say(state,
            "typed move '" + t.text + "': give one distance after x, y or z, or three values dx dy dz");
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

// A replayed slider gesture (`set material.<field> <value>`); the parser accepted only known fields.
void handle_set(ecs::Registry& registry, EditorState& state, const InputEvent& e) {
    if (is_point_field(e.key)) return handle_point_field(state, e);
    if (is_proportional_field(e.key)) {
        set_proportional_field(state.proportional, e.key, e.value);
        const ProportionalSettings& p = state.proportional;
        return say(state, log::str("proportional editing ", p.enabled ? "on" : "off", " (",
                                   falloff_name(p.falloff), ", radius ", p.radius, ")"));
    }
    const std::optional<MaterialFieldInfo> field = material_field(e.key);
    const ecs::Entity target = material_target(registry, state);
    if (!field || !set_material_value(registry, state, target, field->field, static_cast<float>(e.value)))
        log::warn("editor: 'set ", e.key, "': no cloud with a material in the scene");
}

void handle_text(ecs::Registry& registry, EditorState& state, const std::string& text) {
    // Numeric entry: "dx dy dz" (commas allowed) for move, "degrees" for twist.
    state.typed = {};
    double v[3] = {0, 0, 0};
    const int n = scan_numbers(text, v);  // the leading numbers; what follows them is not checked here
    if (state.tool == Tool::twist && n >= 1) apply_twist(registry, state, v[0]);
    else if (state.tool == Tool::move && n == 3) apply_stretch(registry, state, {v[0], v[1], v[2]});
    else if (state.tool == Tool::scale && n == 1) apply_scale(registry, state, glm::dmat3(v[0]));
    else if (state.tool == Tool::scale && n == 3) apply_scale(registry, state, diagonal(v));
    else
        say(state, "numeric entry '" + text +
                       "': move takes 'dx dy dz', twist takes 'degrees', scale takes 'factor' or 'sx sy sz'");
}

void handle_key(ecs::Registry& registry, EditorState& state, const InputEvent& e) {
    const bool ctrl = e.modifiers & mods::ctrl, shift = e.modifiers & mods::shift;
    const std::string& k = e.key;
    if (state.drag.kind != Drag::Kind::none) {
        if (k == "escape") cancel_drag(registry, state);
        // Proportional radius while dragging (Blender's transform keys): PageUp larger, PageDown smaller.
        else if (k == "pageup") change_proportional_radius(registry, state, proportional_radius_step);
        else if (k == "pagedown") change_proportional_radius(registry, state, 1.0 / proportional_radius_step);
        return;  // no other shortcuts mid-gesture
    }
    if (k == "tab" && ctrl && !shift) return toggle_edit_mode(registry, state);  // point_mode.h
    if (state.typed.active && handle_typed_key(registry, state, e)) return;
    // Point mode's keys first (point_mode.h); what it leaves is every mode's (undo, save, lattices, view).
    if (state.mode == EditMode::points && handle_point_key(registry, state, e)) return;
    if (handle_lattice_key(registry, state, e))
        return;  // add/remove/refit/order/export/import (lattice_manage.h)
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
    else if (k == "g" || k == "w" || k == "r" || (k == "s" && !shift)) {
        state.tool = k == "r" ? Tool::twist : k == "s" ? Tool::scale : Tool::move;
        state.typed = TypedEntry{true, state.tool, {}};
        say(state, std::string("tool: ") + tool_name(state.tool) +
                       " (drag, or type a value: x/y/z axis, number, Enter)");
    } else if (k == "b") state.tool = Tool::brush, say(state, "tool: brush");
    else if (k == "x") set_axis(state, AxisMode::x);
    else if (k == "y") set_axis(state, AxisMode::y);
    else if (k == "z") set_axis(state, AxisMode::z);
    else if (k == "v") set_axis(state, AxisMode::view);
    else if (k == "c") set_axis(state, AxisMode::custom);
    else if (k == "a") select_all(registry, state);
    else if (k == "escape") clear_selection(registry, state);
    else if (k == "f") frame_selection(registry, state);
    else if (k == "p")
        state.pin_outer_layer = !state.pin_outer_layer,
        say(state, state.pin_outer_layer ? "outer layer pinned" : "outer layer unpinned");
    else if (k == "l")
        state.scope = state.scope == ToolScope::local ? ToolScope::global : ToolScope::local,
        say(state,
            state.scope == ToolScope::local ? "scope: local (selection)" : "scope: global (all points)");
    else if (k == "t" && shift)
        state.lattice_cage_only = !state.lattice_cage_only,
        say(state, state.lattice_cage_only ? "lattice: outer cage only" : "lattice: all points and cells");
    else if (k == "t") state.xray = !state.xray, say(state, state.xray ? "x-ray on" : "x-ray off");
    else if (k == "o" && shift) cycle_falloff(state);
    else if (k == "o") toggle_proportional(state);
    else if (k == "period")  // Blender's pivot key
        state.pivot_mode =
            state.pivot_mode == PivotMode::centroid ? PivotMode::picked_point : PivotMode::centroid,
        say(state,
            state.pivot_mode == PivotMode::centroid ? "pivot: selection centroid" : "pivot: picked point");
    else if (k == "home") reset_lattice(registry, state);
    else if (k == "k" && shift) delete_keys_at_time(registry, state);
    else if (k == "k") key_last_edit(registry, state);
    else if (k == "space") toggle_play(registry, state);
    else if (k == "n")
        state.auto_key = !state.auto_key,
        say(state, state.auto_key ? "auto-key on: edits are keyed at the clip time" : "auto-key off");
    else if (k == "left") scrub_to(registry, state, clip_time(registry, state) - 1.0 / 24.0);
    else if (k == "right") scrub_to(registry, state, clip_time(registry, state) + 1.0 / 24.0);
    else if (k == "f12") state.request_screenshot = true;
}

}  // namespace

AnimationState* animation_state(ecs::Registry& registry, const EditorState& state) {
    return registry.valid(state.active_lattice) ? registry.try_get<AnimationState>(state.active_lattice)
                                                : nullptr;
}

namespace {

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
                  k == Drag::Kind::twist || k == Drag::Kind::brush || k == Drag::Kind::scale;
    registry.view<AnimationState>().each([&](ecs::Entity, AnimationState& a) { moving |= a.playing; });
    if (const Camera* cam = camera_of(registry, state)) {
        const Camera& l = state.last_camera;
        moving |= cam->eye != l.eye || cam->target != l.target || cam->up != l.up ||
                  cam->fov_y_degrees != l.fov_y_degrees;
        state.last_camera = *cam;
    }
    state.still_frames = moving ? 0 : std::min(state.still_frames + 1, 1 << 20);
    const auto rest = render::Quality(state.rest_quality);
    state.previewing = state.preview_while_moving && rest != render::Quality::preview &&
                       state.still_frames < state.refine_after;
    settings->quality = state.previewing ? render::Quality::preview : rest;
    settings->preview_divider = state.previewing && state.half_resolution_preview ? 2 : 1;
    // The selected points tinted in point mode only (Blender shows vertex selection in edit mode); the
    // weights overlay when View > Weights (or `set view.weights 1`) asks for it.
    settings->show_selection = state.mode == EditMode::points;
    settings->show_weights = state.show_weights;
    set_preview_active(registry, state.previewing);  // the point budget of large clouds while moving
}

}  // namespace

}  // namespace detail

using namespace detail;

void editor_input_system(ecs::Registry& registry, const FrameContext& frame) {
    EditorState* state = registry.try_resource<EditorState>();
    if (!state) return;
    // What the panels posted in the last frame's present phase (pending_edits.h): they came before this
    // frame's events.
    apply_pending_edits(registry, *state);
    update_scene_bounds_cache(registry);  // the overlay and the panels read the scene's box every frame
    Camera* camera = camera_of(registry, *state);
    state->pending_picks.clear();  // a pick the last frame's picking phase did not answer is dropped
    std::vector<InputEvent> fresh;
    if (state->replay) fresh = state->replay->take(frame.frame);
    for (InputEvent& e : state->events) fresh.push_back(std::move(e));
    state->events.clear();
    for (InputEvent& e : fresh) e.frame = frame.frame;
    // Recorded as they arrive, so a replay of the recording defers the same events.
    if (state->record) state->recorded.insert(state->recorded.end(), fresh.begin(), fresh.end());
    std::vector<InputEvent> events = std::move(state->deferred);
    state->deferred.clear();
    events.insert(events.end(), std::make_move_iterator(fresh.begin()), std::make_move_iterator(fresh.end()));
    std::size_t handled = 0;
    for (; handled < events.size(); ++handled) {
        const InputEvent& e = events[handled];
        // After a gesture that posted a pick, the next events wait for the next frame (they may depend
        // on what the pick selects), except the moves of a brush drag: each posts its own dab, and dabs
        // only add to or remove from the selection.
        if (!state->pending_picks.empty() &&
            !(e.kind == InputKind::move &&
              (state->drag.kind == Drag::Kind::brush || state->drag.kind == Drag::Kind::point_brush)))
            break;
        camera = camera_of(registry, *state);  // undo may have touched components: look it up again
        if (!camera) {
            handled = events.size();  // no view to interpret them in: dropped
            break;
        }
        switch (e.kind) {
            case InputKind::move:
                state->cursor = e.position;
                handle_move(registry, *state, *camera, e.position);
                break;
            case InputKind::press: handle_press(registry, *state, *camera, e); break;
            case InputKind::release: handle_release(registry, *state, *camera, e); break;
            case InputKind::scroll:
                // While a tool drag with proportional editing runs, the wheel sizes the radius (Blender:
                // wheel up smaller, down larger); otherwise it zooms.
                if (!change_proportional_radius(registry, *state,
                                                std::pow(proportional_radius_step, -e.scroll)))
                    zoom(*camera, e.scroll);
                break;
            case InputKind::key: handle_key(registry, *state, e); break;
            case InputKind::text: handle_text(registry, *state, e.key); break;
            case InputKind::set: handle_set(registry, *state, e); break;
        }
    }
    if (state->request_frame_selection) {
        state->request_frame_selection = false;
        frame_selection(registry, *state);
    }
    state->deferred.assign(std::make_move_iterator(events.begin() + std::ptrdiff_t(handled)),
                           std::make_move_iterator(events.end()));
    events.resize(handled);
    adapt_quality(registry, *state, std::any_of(events.begin(), events.end(), [](const InputEvent& e) {
                      return e.kind == InputKind::scroll;
                  }));
}

void editor_pick_system(ecs::Registry& registry, const FrameContext&) {
    if (EditorState* state = registry.try_resource<EditorState>()) apply_pending_picks(registry, *state);
}

}  // namespace sffd::editor
