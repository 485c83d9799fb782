// Picking components and resources: plain data. Owned by the picking system (systems/picking); the
// editor (systems/editor) posts PickRequests and writes LatticeSelection, reads PickResults.
//
//   const std::uint64_t id = picking::post_pick(registry, picking::query_at_pixel(view, {320.5, 240.5}));
//   ... the picking phase runs picking_system() ...
//   if (const picking::PickHit* hit = picking::find_pick_answer(registry, id)) ...
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/ecs/entity.h"
#include "systems/picking/screen_view.h"

namespace sffd::picking {

enum class PickKind : std::uint8_t { none, control_point, surface, gaussian };
const char* pick_kind_name(PickKind kind);  // "none", "control_point", "surface", "gaussian"

// One pick's answer. `entity` is the lattice entity (control point), the point-cloud entity (surface)
// or the Gaussian-cloud entity (gaussian); `index` is the control point's flat index
// (i*(m+1)+j)*(n+1)+k, the splat's index or the Gaussian's index in its cloud. For a Gaussian,
// `position` is where the ray enters its pickable ellipsoid (systems/picking/gaussian_source.h).
struct PickHit {
    PickKind kind = PickKind::none;
    ecs::Entity entity = ecs::null_entity;
    std::uint32_t index = 0;
    glm::dvec3 position{0.0};  // world-space hit point (the control point itself for control points)
    double distance = 0.0;     // from the ray origin to `position`, world units
    // Surface hits: where on the splat, position = centre + x axis_u + y axis_v of the picked (deformed,
    // world-space) splat, x² + y² <= 1. The brush maps it back through the authored axes.
    glm::dvec2 splat_coords{0.0};

    explicit operator bool() const { return kind != PickKind::none; }
};

// What to pick. Either an explicit world ray (has_screen = false: only the geometry along the ray
// counts, control points are spheres of PickSettings radius), or a ray through a screen point of a
// ScreenView (has_screen = true: additionally, a control point whose projection lies within
// `tolerance_px` of the cursor wins over the surface, as the lattice is drawn over the model).
struct PickQuery {
    Ray ray;
    bool has_screen = false;
    ScreenView screen;
    glm::dvec2 cursor{0.0};      // screen point the ray goes through (pixels, y down)
    double tolerance_px = 6.0;   // control points within this many pixels of the cursor win
    bool xray = false;           // control points hidden behind the surface can be picked
    bool control_points = true;  // consider lattice control points
    bool surfaces = true;        // consider splat surfaces
};

PickQuery query_from_ray(const Ray& ray);
PickQuery query_at_pixel(const ScreenView& view, glm::dvec2 screen);

// One pick for the picking phase; `id` (never 0) names its answer.
struct PickRequest {
    std::uint64_t id = 0;
    PickQuery query;
};

// Resource: the picks posted (post_pick) since the last picking phase, which answers them in order and
// empties `pending`. Several gestures of one frame may each post one.
struct PickRequests {
    std::vector<PickRequest> pending;
    std::uint64_t next_id = 1;
};

struct PickAnswer {
    std::uint64_t id = 0;  // the request's
    PickHit hit;
};

// Resource: the answers of the last picking phase that had requests, in request order (find_pick_answer).
struct PickResults {
    std::vector<PickAnswer> answers;
    std::uint64_t frame = 0;   // the frame that answered them
    std::uint64_t serial = 0;  // picks answered so far
};

// Resource: picking tunables.
// Which Gaussian a ray picks (systems/picking/gaussian_source.h for the ellipsoids):
//   most_visible     the one contributing most to the pixel (largest 3DGS blending weight α T along the
//                    ray; a faint floater in front of an opaque Gaussian is passed over, as on screen);
//   first_ellipsoid  the first ellipsoid the ray enters (every Gaussian drawn with alpha >= 1/255 counts).
enum class GaussianPick : std::uint8_t { most_visible, first_ellipsoid };

struct PickSettings {
    // Control-point sphere radius for explicit rays, as a fraction of the lattice's smallest cell edge.
    double control_point_radius_fraction = 0.08;
    GaussianPick gaussians = GaussianPick::most_visible;
};

// On a lattice entity: the selected control points, as sorted unique flat indices. Changed only
// through the selection functions in selection.h (the editor records them for undo).
struct LatticeSelection {
    std::vector<std::uint32_t> indices;
};

}  // namespace sffd::picking
