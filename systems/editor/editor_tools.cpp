// The editor's mouse gestures: picking, click and box selection, the brush, move/twist drags.
#include "systems/editor/editor_system_detail.h"

#include "systems/animation/evaluate.h"
#include "systems/animation/unkeyed_edit.h"
#include "systems/editor/unkeyed_undo.h"

namespace sffd::editor::detail {

void post_pick_at(ecs::Registry& registry, EditorState& state, const Camera& camera, glm::dvec2 cursor,
                  bool control_points, PendingPick action) {
    picking::PickQuery q = picking::query_at_pixel(screen_view(camera, state.viewport), cursor);
    q.tolerance_px = state.click_tolerance_px;
    q.xray = state.xray;
    q.control_points = control_points;
    q.surfaces = true;
    action.id = picking::post_pick(registry, q);
    state.pending_picks.push_back(std::move(action));
}

namespace {

void click_select(ecs::Registry& registry, EditorState& state, const picking::PickHit& hit,
                  std::uint8_t modifiers) {
    const picking::SelectMode mode = picking::select_mode(modifiers & mods::shift, modifiers & mods::ctrl);
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

// Runs in the picking phase (editor_pick_system): the visibility test refreshes picking's scenes with
// this frame's deformed clouds.
void box_select(ecs::Registry& registry, EditorState& state, const PendingPick& box) {
    if (!active_lattice(registry, state)) return;
    const picking::SelectMode mode =
        picking::select_mode(box.modifiers & mods::shift, box.modifiers & mods::ctrl);
    const std::vector<std::uint32_t> inside =
        picking::control_points_in_rect(registry, picking::picking_state(registry), state.active_lattice,
                                        box.view, picking::ScreenRect{box.from, box.to}, box.visible_only);
    picking::LatticeSelection current{selection_of(registry, state.active_lattice)};
    set_selection(registry, state, state.active_lattice, picking::select(current, inside, mode).indices,
                  "box select");
    say(state, log::str("box selected ", inside.size(), " control points"));
}

void brush_dab(ecs::Registry& registry, EditorState& state, const Camera& camera, glm::dvec2 cursor,
               picking::SelectMode mode) {
    if (!active_lattice(registry, state)) return;
    post_pick_at(registry, state, camera, cursor, false, {PendingPick::Action::brush, 0, 0, mode});
}

void brush_apply(ecs::Registry& registry, EditorState& state, const picking::PickHit& hit,
                 picking::SelectMode mode) {
    if (!active_lattice(registry, state)) return;
    if (hit.kind != picking::PickKind::surface && hit.kind != picking::PickKind::gaussian) return;
    const auto local = picking::surface_hit_in_lattice_space(registry, state.active_lattice, hit);
    if (!local) return;
    const auto picked = picking::brush_select(registry.get<Lattice>(state.active_lattice), *local, {});
    picking::LatticeSelection current{selection_of(registry, state.active_lattice)};
    set_selection(registry, state, state.active_lattice, picking::select(current, picked, mode).indices,
                  "brush");
}

void set_picked_pivot(EditorState& state, const picking::PickHit& hit) {
    if (!hit) return;
    state.picked_pivot = hit.position;
    state.has_picked_pivot = true;
    state.pivot_mode = PivotMode::picked_point;
    say(state, "pivot set to the picked surface point");
}

// Pivot and axis of a tool in world space.
glm::dvec3 tool_pivot(const ecs::Registry& registry, const EditorState& state,
                      std::span<const std::uint32_t> points) {
    if (state.pivot_mode == PivotMode::picked_point && state.has_picked_pivot) return state.picked_pivot;
    const Lattice* lattice = active_lattice(registry, state);
    if (!lattice) return glm::dvec3(0.0);
    return glm::dvec3(lattice_model(registry, state.active_lattice) *
                      glm::dvec4(centroid(*lattice, points), 1.0));
}

}  // namespace

bool animated_lattice(const ecs::Registry& registry, ecs::Entity e) {
    if (!registry.valid(e)) return false;
    const Lattice* lattice = registry.try_get<Lattice>(e);
    const AnimationClip* clip = registry.try_get<AnimationClip>(e);
    return lattice && clip && registry.has<AnimationState>(e) && validate_clip(*clip, lattice->rest.size());
}

std::vector<glm::dvec3> shown_pose(const ecs::Registry& registry, ecs::Entity e) {
    const Lattice& lattice = registry.get<Lattice>(e);
    if (animated_lattice(registry, e))
        if (const UnkeyedEdit* edit = registry.try_get<UnkeyedEdit>(e);
            edit && edit->points.size() == lattice.rest.size() &&
            shows_unkeyed_edit(*edit, registry.get<AnimationState>(e).time))
            return edit->points;
    return lattice.current;
}

void set_unkeyed_pose(ecs::Registry& registry, ecs::Entity e, UnkeyedEdit edit) {
    if (registry.has<UnkeyedEdit>(e)) registry.patch<UnkeyedEdit>(e) = std::move(edit);
    else registry.emplace<UnkeyedEdit>(e, std::move(edit));
}

// Applies the drag's current displacement / angle to the lattice, from the snapshot: into its current,
// or, animated, into its un-keyed edit (the animation phase then shows it, in this frame).
void apply_drag(ecs::Registry& registry, const Drag& drag) {
    if (!registry.valid(drag.lattice) || !registry.has<Lattice>(drag.lattice)) return;
    const glm::dmat4 model = lattice_model(registry, drag.lattice);
    const glm::dmat4 inverse = glm::inverse(model);
    std::vector<glm::dvec3> pose = drag.start_points;
    // The edited points at weight 1 and, with proportional editing, their neighbours at their falloff.
    const WeightedPoints moved =
        proportional_points(drag.points, drag.distance, drag.excluded, drag.proportional);
    if (drag.kind == Drag::Kind::move) {
        const glm::dvec3 d = glm::dvec3(inverse * glm::dvec4(drag.displacement_world, 0.0));
        stretch_points(drag.start_points, pose, moved.indices, moved.weights, d);
    } else if (drag.kind == Drag::Kind::scale) {
        const glm::dvec3 pivot = glm::dvec3(inverse * glm::dvec4(drag.pivot_world, 1.0));
        const glm::dmat3 linear = glm::dmat3(inverse) * drag.scale_world * glm::dmat3(model);
        scale_points(drag.start_points, pose, moved.indices, moved.weights, pivot, linear);
    } else {
        const glm::dvec3 pivot = glm::dvec3(inverse * glm::dvec4(drag.pivot_world, 1.0));
        const glm::dvec3 axis = glm::dvec3(inverse * glm::dvec4(drag.axis_world, 0.0));
        twist_points(drag.start_points, pose, moved.indices, moved.weights, pivot, axis, drag.angle);
    }
    if (drag.animated)
        return set_unkeyed_pose(registry, drag.lattice, UnkeyedEdit{drag.clip_time, std::move(pose)});
    Lattice& lattice = registry.patch<Lattice>(drag.lattice);
    if (lattice.current.size() == pose.size()) lattice.current = std::move(pose);
}

bool is_tool_drag(Drag::Kind kind) {
    return kind == Drag::Kind::move || kind == Drag::Kind::twist || kind == Drag::Kind::scale;
}

bool change_proportional_radius(ecs::Registry& registry, EditorState& state, double factor) {
    Drag& drag = state.drag;
    if (!is_tool_drag(drag.kind) || !drag.proportional.enabled) return false;
    drag.proportional.radius = clamp_proportional_radius(drag.proportional.radius * factor);
    state.proportional.radius = drag.proportional.radius;  // the next edit starts with it, as Blender's
    apply_drag(registry, drag);
    state.status = log::str("proportional ", falloff_name(drag.proportional.falloff), " radius ",
                            drag.proportional.radius);
    return true;
}

namespace {

void remember_edit(ecs::Registry& registry, EditorState& state, const Drag& drag) {
    const glm::dmat4 inverse = glm::inverse(lattice_model(registry, drag.lattice));
    LastEdit& e = state.last_edit;
    e = LastEdit{};
    e.lattice = drag.lattice;
    e.points = drag.points;
    const std::size_t moved =
        proportional_points(drag.points, drag.distance, drag.excluded, drag.proportional).indices.size();
    if (drag.kind == Drag::Kind::scale) {
        e.not_keyable = "a scale cannot be keyed (tracks key stretches and twists)";
    } else if (moved != drag.points.size()) {
        e.not_keyable = log::str("this proportional edit moved ", moved - drag.points.size(),
                                 " neighbours by their falloff, which a track cannot key");
    } else if (drag.kind == Drag::Kind::move) {
        e.kind = LastEdit::Kind::stretch;
        e.displacement = glm::dvec3(inverse * glm::dvec4(drag.displacement_world, 0.0));
    } else {
        e.kind = LastEdit::Kind::twist;
        e.angle = drag.angle;
        e.axis = glm::dvec3(inverse * glm::dvec4(drag.axis_world, 0.0));
        e.pivot = glm::dvec3(inverse * glm::dvec4(drag.pivot_world, 1.0));
    }
}

}  // namespace

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
    drag.kind = state.tool == Tool::move    ? Drag::Kind::move
                : state.tool == Tool::scale ? Drag::Kind::scale
                                            : Drag::Kind::twist;
    drag.camera = camera;
    drag.lattice = state.active_lattice;
    drag.animated = animated_lattice(registry, drag.lattice);
    if (drag.animated) {
        // An edit while the clip plays pauses it at the frame shown (README.md, "Edits and the
        // animation"): the edit then belongs to that clip time.
        AnimationState& clip_state = registry.patch<AnimationState>(drag.lattice);
        if (clip_state.playing) {
            pause(clip_state);
            say(state, "paused the clip to edit at " + log::str(clip_state.time) + " s");
        }
        drag.clip_time = clip_state.time;
        drag.before_unkeyed = ComponentEdit<UnkeyedEdit>::snapshot(registry, drag.lattice);
    }
    drag.start_points = shown_pose(registry, drag.lattice);
    if (!drag.animated) drag.before = *lattice;
    drag.pivot_world = tool_pivot(registry, state, drag.points);
    drag.axis_world = axis_direction(state.twist_axis, camera, state.custom_axis);
    drag.angle = 0.0;
    drag.displacement_world = glm::dvec3(0.0);
    drag.scale_world = glm::dmat3(1.0);
    drag.proportional = state.proportional;
    drag.distance.clear(), drag.excluded.clear();
    if (drag.proportional.enabled) {
        // World distances at the pose shown at press (Blender measures in world space); pinned points
        // (local scope) stay where they are.
        const glm::dmat4 model = lattice_model(registry, drag.lattice);
        std::vector<glm::dvec3> world(drag.start_points.size());
        for (std::size_t c = 0; c < world.size(); ++c)
            world[c] = glm::dvec3(model * glm::dvec4(drag.start_points[c], 1.0));
        drag.distance = nearest_edited_distance(world, drag.points);
        if (state.scope == ToolScope::local && state.pin_outer_layer)
            drag.excluded = outer_layer_mask(*lattice);
    }
    return true;
}

void finish_tool_drag(ecs::Registry& registry, EditorState& state, Drag& drag) {
    if (!registry.valid(drag.lattice) || !registry.has<Lattice>(drag.lattice)) return;
    const bool is_move = drag.kind == Drag::Kind::move;
    const char* label = is_move ? "stretch" : drag.kind == Drag::Kind::scale ? "scale" : "twist";
    // Animated: the step is the un-keyed edit's change (the moved points, and its time), the lattice's
    // current being the animation's; otherwise the lattice's change.
    std::unique_ptr<Command> change;
    if (drag.animated)
        change = unkeyed_edit_change(label, registry, drag.lattice, drag.before_unkeyed,
                                     ComponentEdit<UnkeyedEdit>::snapshot(registry, drag.lattice));
    else
        change = std::make_unique<ComponentChange<Lattice>>(label, drag.lattice, drag.before,
                                                            registry.get<Lattice>(drag.lattice));
    if (state.undo.push(std::move(change))) {
        remember_edit(registry, state, drag);
        say(state, is_move ? log::str("stretched ", drag.points.size(), " control points")
                   : drag.kind == Drag::Kind::scale
                       ? log::str("scaled ", drag.points.size(), " control points")
                       : log::str("twisted ", drag.points.size(), " control points by ",
                                  glm::degrees(drag.angle), " degrees"));
        if (drag.proportional.enabled)
            state.status += log::str(" (proportional ", falloff_name(drag.proportional.falloff), ", radius ",
                                     drag.proportional.radius, ")");
        if (state.auto_key) {
            const std::string edited = state.status;
            if (key_last_edit(registry, state)) say(state, edited + " (auto-key: " + state.status + ")");
        } else {
            state.unkeyed = drag.lattice;
            state.play_warned = false;
        }
    }
}

namespace {

glm::dvec3 move_displacement(const EditorState& state, const Drag& drag, glm::dvec2 cursor) {
    const Camera& cam = drag.camera;
    if (state.move_axis == AxisMode::view_plane)
        return drag_in_view_plane(cam, state.viewport, drag.pivot_world, drag.start, cursor);
    if (state.move_axis == AxisMode::view) {
        // Along the viewing direction: upward drag pushes away, one pixel = one pixel's size at the pivot.
        const double depth = glm::dot(drag.pivot_world - cam.eye, glm::normalize(cam.target - cam.eye));
        const double pixel =
            2.0 * depth * std::tan(glm::radians(double(cam.fov_y_degrees)) * 0.5) / state.viewport.height;
        return glm::normalize(cam.target - cam.eye) * ((drag.start.y - cursor.y) * pixel);
    }
    return drag_along_axis(cam, state.viewport, drag.pivot_world,
                           axis_direction(state.move_axis, cam, state.custom_axis), drag.start, cursor);
}

// Scale from the cursor's distance to the pivot's image (Blender's scale): the distance now over the
// distance at press; along the move axis when it is x, y, z or custom, uniform otherwise.
glm::dmat3 scale_from_cursor(const EditorState& state, const Drag& drag, glm::dvec2 cursor) {
    const glm::dvec2 c = glm::dvec2(project_to_pixel(drag.camera, state.viewport, drag.pivot_world));
    const double at_press = glm::length(drag.start - c);
    const double factor = at_press < 1.0 ? 1.0 : glm::length(cursor - c) / at_press;
    return scale_matrix(state.move_axis, drag.camera, state.custom_axis, factor);
}

}  // namespace

glm::dmat3 scale_matrix(AxisMode axis, const Camera& camera, const glm::dvec3& custom_axis, double factor) {
    if (axis == AxisMode::view_plane || axis == AxisMode::view) return glm::dmat3(factor);
    const glm::dvec3 a = glm::normalize(axis_direction(axis, camera, custom_axis));
    return glm::dmat3(1.0) + (factor - 1.0) * glm::outerProduct(a, a);
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
            drag.angle +=
                drag_angle(drag.camera, state.viewport, drag.pivot_world, drag.axis_world, drag.last, cursor);
            apply_drag(registry, drag);
            break;
        case Drag::Kind::scale:
            drag.scale_world = scale_from_cursor(state, drag, cursor);
            apply_drag(registry, drag);
            break;
        case Drag::Kind::brush:
            brush_dab(registry, state, camera, cursor,
                      drag.modifiers & mods::ctrl ? picking::SelectMode::remove : picking::SelectMode::add);
            break;
        case Drag::Kind::point_click:
        case Drag::Kind::point_box:
        case Drag::Kind::point_lasso:
        case Drag::Kind::point_brush:
        case Drag::Kind::point_sphere: point_move(registry, state, camera, cursor); break;
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
    if (e.modifiers & mods::alt) {  // pivot at a picked surface point (set_picked_pivot, after picking)
        post_pick_at(registry, state, camera, state.cursor, false, {PendingPick::Action::pivot});
        return;
    }
    if (state.mode == EditMode::points) return point_press(registry, state, camera, e);
    const bool plain = (e.modifiers & (mods::shift | mods::ctrl)) == 0;
    if (plain && (state.tool == Tool::move || state.tool == Tool::twist || state.tool == Tool::scale) &&
        begin_tool_drag(registry, state, camera, drag))
        return;
    if (state.tool == Tool::brush) {
        drag.kind = Drag::Kind::brush;
        brush_dab(registry, state, camera, state.cursor,
                  picking::select_mode(e.modifiers & mods::shift, e.modifiers & mods::ctrl));
        return;
    }
    drag.kind = Drag::Kind::pending_click;
}

void handle_release(ecs::Registry& registry, EditorState& state, Camera& camera, const InputEvent& e) {
    Drag& drag = state.drag;
    if (drag.kind == Drag::Kind::none || drag.button != e.button) return;
    switch (drag.kind) {
        case Drag::Kind::pending_click:
            post_pick_at(registry, state, camera, drag.start, true,
                         {PendingPick::Action::click_select, 0, drag.modifiers});
            break;
        case Drag::Kind::box:
            if (active_lattice(registry, state)) {
                PendingPick box{PendingPick::Action::box_select};
                box.modifiers = drag.modifiers;
                box.from = drag.start, box.to = state.cursor;
                box.view = screen_view(camera, state.viewport);
                box.visible_only = !state.xray;
                state.pending_picks.push_back(box);
            }
            break;
        case Drag::Kind::move:
        case Drag::Kind::scale:
        case Drag::Kind::twist: finish_tool_drag(registry, state, drag); break;
        case Drag::Kind::point_click:
        case Drag::Kind::point_box:
        case Drag::Kind::point_lasso:
        case Drag::Kind::point_brush:
        case Drag::Kind::point_sphere: point_release(registry, state, camera, e); break;
        default: break;
    }
    drag = Drag{};
}

void cancel_drag(ecs::Registry& registry, EditorState& state) {
    Drag& drag = state.drag;
    if (is_tool_drag(drag.kind) && registry.valid(drag.lattice) && registry.has<Lattice>(drag.lattice)) {
        if (!drag.animated) registry.patch<Lattice>(drag.lattice).current = drag.start_points;
        else if (drag.before_unkeyed) set_unkeyed_pose(registry, drag.lattice, *drag.before_unkeyed);
        else registry.remove<UnkeyedEdit>(drag.lattice);
    }
    if (is_point_drag(drag.kind)) cancel_point_drag(registry, state);
    drag = Drag{};
    say(state, "cancelled");
}

void apply_pending_picks(ecs::Registry& registry, EditorState& state) {
    std::vector<PendingPick> picks;
    picks.swap(state.pending_picks);
    for (const PendingPick& p : picks) {
        if (p.action >= PendingPick::Action::point_click) {  // point mode's (point_tools.cpp)
            apply_point_pick(registry, state, p);
            continue;
        }
        if (p.action == PendingPick::Action::box_select) {
            box_select(registry, state, p);
            continue;
        }
        // Not answered: the schedule ran no picking phase this frame (the gesture is dropped, as a click
        // on nothing would be).
        const picking::PickHit* hit = picking::find_pick_answer(registry, p.id);
        if (!hit) continue;
        switch (p.action) {
            case PendingPick::Action::click_select: click_select(registry, state, *hit, p.modifiers); break;
            case PendingPick::Action::brush: brush_apply(registry, state, *hit, p.mode); break;
            case PendingPick::Action::pivot: set_picked_pivot(state, *hit); break;
            default: break;
        }
    }
}

}  // namespace sffd::editor::detail
