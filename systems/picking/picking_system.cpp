#include "systems/picking/picking_system.h"

#include <cmath>
#include <limits>

#include "systems/ffd/components.h"
#include "systems/picking/world_space.h"

namespace sffd::picking {

const char* pick_kind_name(PickKind kind) {
    switch (kind) {
        case PickKind::none: return "none";
        case PickKind::control_point: return "control_point";
        case PickKind::surface: return "surface";
        case PickKind::gaussian: return "gaussian";
    }
    return "none";
}

PickQuery query_from_ray(const Ray& ray) {
    PickQuery q;
    q.ray = {ray.origin, glm::normalize(ray.direction)};
    return q;
}

PickQuery query_at_pixel(const ScreenView& view, glm::dvec2 screen) {
    PickQuery q;
    q.ray = ray_through(view, screen);
    q.has_screen = true;
    q.screen = view;
    q.cursor = screen;
    return q;
}

PickingState& picking_state(ecs::Registry& registry) {
    if (auto* s = registry.try_resource<PickingState>()) return *s;
    return registry.set_resource<PickingState>();
}

namespace {

// Rule 1: the control point drawn nearest the cursor within the pixel tolerance (ties: nearer the eye).
PickHit control_point_near_cursor(ecs::Registry& registry, const PickingState& state, const PickQuery& q) {
    PickHit best;
    double best_px = std::numeric_limits<double>::infinity();
    double best_depth = std::numeric_limits<double>::infinity();
    for (auto [e, lattice] : registry.view<const Lattice>()) {
        const std::vector<glm::dvec3> points = control_points_world(registry, e);
        for (std::size_t i = 0; i < points.size(); ++i) {
            const auto p = project(q.screen, points[i]);
            if (!p) continue;
            const double px = glm::length(p->screen - q.cursor);
            if (px > q.tolerance_px) continue;
            if (px > best_px || (px == best_px && p->depth >= best_depth)) continue;
            if (!q.xray && q.surfaces && state.surface_between(q.ray.origin, points[i])) continue;
            best_px = px;
            best_depth = p->depth;
            best = {PickKind::control_point,
                    e,
                    std::uint32_t(i),
                    points[i],
                    glm::length(points[i] - q.ray.origin),
                    glm::dvec2(0.0)};
        }
    }
    return best;
}

}  // namespace

PickHit pick(ecs::Registry& registry, PickingState& state, const PickQuery& query) {
    const PickSettings* settings = registry.try_resource<PickSettings>();
    state.refresh(registry, settings ? *settings : PickSettings{});

    PickQuery q = query;
    q.ray.direction = glm::normalize(q.ray.direction);
    if (!std::isfinite(q.ray.direction.x) || !std::isfinite(q.ray.origin.x)) return {};

    if (q.control_points && q.has_screen) {
        if (PickHit hit = control_point_near_cursor(registry, state, q)) return hit;
    }
    std::optional<PickingState::RayHit> surface;
    if (q.surfaces) {
        const bool first = settings && settings->gaussians == GaussianPick::first_ellipsoid;
        surface = first ? state.intersect_surfaces(q.ray, std::numeric_limits<double>::infinity())
                        : state.most_visible_surface(q.ray, std::numeric_limits<double>::infinity());
    }
    if (q.control_points) {
        const double tfar = (surface && !q.xray) ? surface->t : std::numeric_limits<double>::infinity();
        if (const auto c = state.intersect_controls(q.ray, tfar)) {
            const std::vector<glm::dvec3> points = control_points_world(registry, c->entity);
            if (c->index < points.size()) {
                const glm::dvec3 p = points[c->index];
                return {PickKind::control_point,       c->entity,      c->index, p,
                        glm::length(p - q.ray.origin), glm::dvec2(0.0)};
            }
        }
    }
    if (surface && surface->gaussian)
        return {PickKind::gaussian, surface->entity,
                surface->index,     q.ray.origin + surface->t * q.ray.direction,
                surface->t,         glm::dvec2(0.0)};
    if (surface) {
        PickHit hit{PickKind::surface, surface->entity,
                    surface->index,    q.ray.origin + surface->t * q.ray.direction,
                    surface->t,        glm::dvec2(0.0)};
        hit.splat_coords =
            state.splat_coordinates(hit.entity, hit.index, hit.position).value_or(glm::dvec2(0.0));
        return hit;
    }
    return {};
}

std::uint64_t post_pick(ecs::Registry& registry, const PickQuery& query) {
    PickRequests* requests = registry.try_resource<PickRequests>();
    if (!requests) requests = &registry.set_resource<PickRequests>();
    const std::uint64_t id = requests->next_id++;
    requests->pending.push_back({id, query});
    return id;
}

const PickHit* find_pick_answer(const ecs::Registry& registry, std::uint64_t id) {
    const PickResults* results = registry.try_resource<PickResults>();
    if (!results) return nullptr;
    for (const PickAnswer& a : results->answers)
        if (a.id == id) return &a.hit;
    return nullptr;
}

void picking_system(ecs::Registry& registry, const FrameContext& frame) {
    PickRequests* requests = registry.try_resource<PickRequests>();
    if (!requests || requests->pending.empty()) return;
    PickResults* results = registry.try_resource<PickResults>();
    if (!results) results = &registry.set_resource<PickResults>();
    results->answers.clear();
    PickingState& state = picking_state(registry);
    for (const PickRequest& r : requests->pending)
        results->answers.push_back({r.id, pick(registry, state, r.query)});
    results->frame = frame.frame;
    results->serial += requests->pending.size();
    requests->pending.clear();
}

}  // namespace sffd::picking
