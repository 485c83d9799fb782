// Point mode's mouse gestures (point_mode.h): click, box, lasso, polygon, brush, sphere and colour, posted
// in the input phase and applied after this frame's deformation and picking (editor_pick_system), as the
// lattice's box select and brush are: every tool then sees the points the frame shows.
#include "systems/editor/editor_system_detail.h"

#include "systems/editor/point_mode.h"

namespace sffd::editor::detail {

namespace {

constexpr double polygon_close_px = 8.0;  // a click this near the first corner closes the polygon

PendingPick point_pick(const EditorState& state, const Camera& camera, PendingPick::Action action,
                       PointMode mode) {
    PendingPick p{action};
    p.view = screen_view(camera, state.viewport);
    p.visible_only = !state.xray;
    p.point_mode = mode;
    return p;
}

void post_brush_dab(EditorState& state, const Camera& camera, glm::dvec2 cursor, PointMode mode) {
    PendingPick p = point_pick(state, camera, PendingPick::Action::point_brush, mode);
    p.region = point_select::circle_region(cursor, state.points.settings.brush_radius_px);
    state.pending_picks.push_back(std::move(p));
}

// The world distance from the sphere's centre to where the cursor's ray meets the plane through the
// centre facing the camera.
double sphere_radius_at(const Camera& camera, const Viewport& viewport, const glm::dvec3& centre,
                        glm::dvec2 cursor) {
    const Ray ray = pixel_ray(camera, viewport, cursor);
    const glm::dvec3 n = glm::normalize(camera.target - camera.eye);
    const double along = glm::dot(ray.direction, n);
    if (std::abs(along) < 1e-12) return 0.0;
    const double t = glm::dot(centre - ray.origin, n) / along;
    return glm::length(ray.origin + t * ray.direction - centre);
}

void add_to_stroke(EditorState& state, std::vector<PointSelectionChange::Part> dab) {
    auto& stroke = state.points.stroke;
    for (auto& [e, delta] : dab) {
        if (delta.empty()) continue;
        auto it = std::find_if(stroke.begin(), stroke.end(), [&](const auto& s) { return s.first == e; });
        if (it == stroke.end()) stroke.emplace_back(e, std::move(delta));
        else it->second = point_select::compose(it->second, delta);
    }
}

}  // namespace

bool is_point_drag(Drag::Kind kind) {
    return kind == Drag::Kind::point_click || kind == Drag::Kind::point_box ||
           kind == Drag::Kind::point_lasso || kind == Drag::Kind::point_brush ||
           kind == Drag::Kind::point_sphere;
}

void point_press(ecs::Registry& registry, EditorState& state, const Camera& camera, const InputEvent& e) {
    PointEditing& p = state.points;
    Drag& drag = state.drag;
    drag.camera = camera;  // the sphere's radius is measured in the view of the press
    const PointMode mode = point_mode_for(e.modifiers, p.settings.mode);
    switch (p.settings.tool) {
        case PointTool::select:
        case PointTool::colour: drag.kind = Drag::Kind::point_click; break;
        case PointTool::lasso:
            drag.kind = Drag::Kind::point_lasso;
            p.path = {state.cursor};
            break;
        case PointTool::polygon:
            // Clicks, not a drag: each press adds a corner; near the first one (or Enter) closes it.
            if (p.path.empty()) p.gesture_mode = mode;
            if (p.path.size() >= 3 && glm::length(state.cursor - p.path.front()) <= polygon_close_px) {
                InputEvent enter;
                enter.kind = InputKind::key;
                enter.key = "enter";
                handle_point_key(registry, state, enter);
            } else {
                p.path.push_back(state.cursor);
                say(state, log::str("polygon: ", p.path.size(),
                                    " corners (Enter or a click on the first closes, Backspace, Esc)"));
            }
            drag = Drag{};
            break;
        case PointTool::brush:
            drag.kind = Drag::Kind::point_brush;
            p.stroke.clear();
            post_brush_dab(state, camera, state.cursor, mode);
            break;
        case PointTool::sphere: {
            drag.kind = Drag::Kind::point_sphere;
            p.has_centre = false;
            p.dragged_radius = 0.0;
            post_pick_at(registry, state, camera, state.cursor, false,
                         point_pick(state, camera, PendingPick::Action::point_sphere, mode));
            break;
        }
    }
}

void point_move(ecs::Registry&, EditorState& state, const Camera& camera, glm::dvec2 cursor) {
    PointEditing& p = state.points;
    Drag& drag = state.drag;
    switch (drag.kind) {
        case Drag::Kind::point_click:
            if (p.settings.tool == PointTool::select && glm::length(cursor - drag.start) > drag_threshold_px)
                drag.kind = Drag::Kind::point_box;
            break;
        case Drag::Kind::point_lasso:
            if (p.path.empty() || glm::length(cursor - p.path.back()) >= 1.0) p.path.push_back(cursor);
            break;
        case Drag::Kind::point_brush: {
            const PointMode mode = point_mode_for(drag.modifiers, p.settings.mode);
            post_brush_dab(state, camera, cursor,
                           mode == PointMode::remove ? PointMode::remove : PointMode::add);
            break;
        }
        case Drag::Kind::point_sphere:
            if (p.has_centre)
                p.dragged_radius = sphere_radius_at(drag.camera, state.viewport, p.centre, cursor);
            break;
        default: break;
    }
}

void point_release(ecs::Registry& registry, EditorState& state, const Camera& camera, const InputEvent&) {
    PointEditing& p = state.points;
    Drag& drag = state.drag;
    const PointMode mode = point_mode_for(drag.modifiers, p.settings.mode);
    switch (drag.kind) {
        case Drag::Kind::point_click: {
            const bool colour = p.settings.tool == PointTool::colour;
            PendingPick pick = point_pick(
                state, camera, colour ? PendingPick::Action::point_colour : PendingPick::Action::point_click,
                mode);
            pick.from = drag.start;
            post_pick_at(registry, state, camera, drag.start, false, std::move(pick));
            break;
        }
        case Drag::Kind::point_box: {
            PendingPick pick = point_pick(state, camera, PendingPick::Action::point_region, mode);
            pick.region = point_select::rect_region(drag.start, state.cursor);
            state.pending_picks.push_back(std::move(pick));
            break;
        }
        case Drag::Kind::point_lasso: {
            std::vector<glm::dvec2> path = std::move(p.path);
            p.path.clear();
            if (path.size() < 3) {
                say(state, "lasso: drag a path around the points");
                break;
            }
            PendingPick pick = point_pick(state, camera, PendingPick::Action::point_region, mode);
            pick.region = point_select::polygon_region(std::move(path));
            state.pending_picks.push_back(std::move(pick));
            break;
        }
        case Drag::Kind::point_brush:
            push_selection_step(registry, state, "brush select points", std::move(p.stroke));
            p.stroke.clear();
            break;
        case Drag::Kind::point_sphere: {
            if (!p.has_centre) {
                say(state, "sphere: press on the surface for the centre");
                break;
            }
            if (p.dragged_radius > 0.0) p.settings.sphere_radius = p.dragged_radius;
            const double radius = p.settings.sphere_radius;
            std::vector<PointSelectionChange::Part> parts;
            for (ecs::Entity e : point_clouds(registry))
                parts.emplace_back(e, point_select::select_sphere(registry, p.select, e, p.centre, radius,
                                                                  point_select::Mode(int(mode))));
            push_selection_step(registry, state, log::str("sphere select points (radius ", radius, ")"),
                                std::move(parts));
            p.has_centre = false;
            break;
        }
        default: break;
    }
}

void cancel_point_drag(ecs::Registry& registry, EditorState& state) {
    PointEditing& p = state.points;
    if (state.drag.kind == Drag::Kind::point_brush)  // the dabs are applied: toggle them back
        for (const auto& [e, delta] : p.stroke) point_select::apply_delta(registry, e, delta);
    p.stroke.clear();
    p.has_centre = false;
    if (state.drag.kind == Drag::Kind::point_lasso) p.path.clear();
}

namespace {

void point_click(ecs::Registry& registry, EditorState& state, const PendingPick& pick,
                 const picking::PickHit* hit) {
    point_select::PointSelectState& sel = state.points.select;
    const auto mode = point_select::Mode(int(pick.point_mode));
    const point_select::ClickOptions options{pick.visible_only, state.click_tolerance_px};
    const std::vector<ecs::Entity> clouds = point_clouds(registry);
    // The cloud in front under the cursor (picking's ray), else the first with a point near the cursor.
    ecs::Entity target = ecs::null_entity;
    if (hit && (hit->kind == picking::PickKind::surface || hit->kind == picking::PickKind::gaussian))
        target = hit->entity;
    if (!target)
        for (ecs::Entity e : clouds)
            if (point_select::point_under_cursor(registry, sel, e, pick.view, pick.from, options)) {
                target = e;
                break;
            }
    std::vector<PointSelectionChange::Part> parts;
    for (ecs::Entity e : clouds) {
        if (e == target)
            parts.emplace_back(
                e, point_select::select_click(registry, sel, e, pick.view, pick.from, mode, options));
        else if (mode == point_select::Mode::set)
            parts.emplace_back(e, point_select::select_none(registry, e));
    }
    push_selection_step(registry, state, "click select points", std::move(parts));
}

void colour_select(ecs::Registry& registry, EditorState& state, const PendingPick& pick,
                   const picking::PickHit* hit) {
    if (!hit || (hit->kind != picking::PickKind::surface && hit->kind != picking::PickKind::gaussian))
        return say(state, "colour: no point under the cursor");
    const std::optional<glm::vec3> colour = point_select::point_colour(registry, hit->entity, hit->index);
    if (!colour) return say(state, "colour: no point under the cursor");
    const double tolerance = state.points.settings.colour_tolerance;
    std::vector<PointSelectionChange::Part> parts;
    for (ecs::Entity e : point_clouds(registry))
        parts.emplace_back(e, point_select::select_by_colour(registry, e, *colour, tolerance,
                                                             point_select::Mode(int(pick.point_mode))));
    push_selection_step(registry, state,
                        log::str("colour select points (", colour->x, " ", colour->y, " ", colour->z,
                                 " within ", tolerance, ")"),
                        std::move(parts));
}

}  // namespace

void apply_point_pick(ecs::Registry& registry, EditorState& state, const PendingPick& pick) {
    const picking::PickHit* hit = pick.id ? picking::find_pick_answer(registry, pick.id) : nullptr;
    switch (pick.action) {
        case PendingPick::Action::point_click: point_click(registry, state, pick, hit); break;
        case PendingPick::Action::point_colour: colour_select(registry, state, pick, hit); break;
        case PendingPick::Action::point_sphere:
            if (hit && *hit) {
                state.points.has_centre = true;
                state.points.centre = hit->position;
                say(state, "sphere: drag the radius (release selects)");
            }
            break;
        case PendingPick::Action::point_region: {
            const char* label = pick.region.shape == point_select::ScreenRegion::Shape::rect
                                    ? "box select points"
                                : state.points.settings.tool == PointTool::polygon ? "polygon select points"
                                                                                   : "lasso select points";
            push_selection_step(
                registry, state, label,
                points_select_region(registry, state, pick.view, pick.region, pick.point_mode));
            break;
        }
        case PendingPick::Action::point_brush:
            if (state.drag.kind == Drag::Kind::point_brush)
                add_to_stroke(state,
                              points_select_region(registry, state, pick.view, pick.region, pick.point_mode));
            break;
        default: break;
    }
}

}  // namespace sffd::editor::detail
