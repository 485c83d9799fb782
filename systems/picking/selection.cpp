#include "systems/picking/selection.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "runtime/scene/components.h"
#include "systems/gaussian/components.h"
#include "systems/picking/world_space.h"

namespace sffd::picking {

SelectMode select_mode(bool shift, bool ctrl) {
    if (ctrl) return SelectMode::remove;
    return shift ? SelectMode::add : SelectMode::replace;
}

LatticeSelection select(const LatticeSelection& current, std::span<const std::uint32_t> picked,
                        SelectMode mode) {
    std::vector<std::uint32_t> p(picked.begin(), picked.end());
    std::sort(p.begin(), p.end());
    p.erase(std::unique(p.begin(), p.end()), p.end());
    LatticeSelection out;
    switch (mode) {
        case SelectMode::replace: out.indices = std::move(p); break;
        case SelectMode::add:
            std::set_union(current.indices.begin(), current.indices.end(), p.begin(), p.end(),
                           std::back_inserter(out.indices));
            break;
        case SelectMode::remove:
            std::set_difference(current.indices.begin(), current.indices.end(), p.begin(), p.end(),
                                std::back_inserter(out.indices));
            break;
    }
    return out;
}

bool is_selected(const LatticeSelection& selection, std::uint32_t index) {
    return std::binary_search(selection.indices.begin(), selection.indices.end(), index);
}

std::vector<std::uint32_t> control_points_in_rect(std::span<const glm::dvec3> world_points,
                                                  const ScreenView& view, ScreenRect rect,
                                                  const std::function<bool(const glm::dvec3&)>& visible) {
    const glm::dvec2 lo = glm::min(rect.a, rect.b), hi = glm::max(rect.a, rect.b);
    std::vector<std::uint32_t> out;
    for (std::size_t i = 0; i < world_points.size(); ++i) {
        const auto p = project(view, world_points[i]);
        if (!p || p->screen.x < lo.x || p->screen.y < lo.y || p->screen.x > hi.x || p->screen.y > hi.y)
            continue;
        if (visible && !visible(world_points[i])) continue;
        out.push_back(std::uint32_t(i));
    }
    return out;
}

std::vector<std::uint32_t> control_points_in_rect(ecs::Registry& registry, PickingState& state,
                                                  ecs::Entity lattice, const ScreenView& view,
                                                  ScreenRect rect, bool visible_only) {
    const std::vector<glm::dvec3> points = control_points_world(registry, lattice);
    if (!visible_only) return control_points_in_rect(points, view, rect);
    const PickSettings* settings = registry.try_resource<PickSettings>();
    state.refresh(registry, settings ? *settings : PickSettings{});
    return control_points_in_rect(
        points, view, rect, [&](const glm::dvec3& p) { return !state.surface_between(view.camera.eye, p); });
}

std::optional<glm::dvec3> lattice_local_coordinates(const Lattice& lattice, const glm::dvec3& point) {
    const glm::dmat3 m(lattice.axes[0], lattice.axes[1], lattice.axes[2]);  // columns S, T, U
    const double det = glm::determinant(m);
    const double scale =
        glm::length(lattice.axes[0]) * glm::length(lattice.axes[1]) * glm::length(lattice.axes[2]);
    if (!(std::abs(det) > 1e-12 * scale)) return std::nullopt;
    return glm::inverse(m) * (point - lattice.origin);
}

namespace {

// Small local basis (systems/ffd owns the deformer's; this one only ranks influence for the brush).
// Bernstein B(d,i,x) = C(d,i) (1−x)^(d−i) x^i.
double bernstein(int degree, int i, double x) {
    double binom = 1.0;
    for (int k = 1; k <= i; ++k) binom = binom * double(degree - i + k) / double(k);
    return binom * std::pow(1.0 - x, degree - i) * std::pow(x, i);
}

// Uniform cubic B-spline centred at 0, support (−2, 2) (notes/ffd-math.md, B-spline section).
double cubic_bspline(double x) {
    x = std::abs(x);
    if (x < 1.0) return (4.0 - 6.0 * x * x + 3.0 * x * x * x) / 6.0;
    if (x < 2.0) return (2.0 - x) * (2.0 - x) * (2.0 - x) / 6.0;
    return 0.0;
}

std::vector<double> axis_weights(LatticeBasis basis, int divisions, double x) {
    std::vector<double> w(std::size_t(divisions) + 1);
    for (int i = 0; i <= divisions; ++i)
        w[i] =
            basis == LatticeBasis::bernstein ? bernstein(divisions, i, x) : cubic_bspline(divisions * x - i);
    return w;
}

}  // namespace

std::vector<double> control_point_weights(const Lattice& lattice, const glm::dvec3& point) {
    // A malformed lattice (no cells, or control points not matching the divisions) has no weights.
    if (glm::any(glm::lessThan(lattice.divisions, glm::ivec3(1))) || lattice.current.size() != lattice.size())
        return std::vector<double>(lattice.current.size(), 0.0);
    std::vector<double> out(lattice.size(), 0.0);
    const auto local = lattice_local_coordinates(lattice, point);
    if (!local) return out;
    for (int a = 0; a < 3; ++a)
        if (!((*local)[a] >= 0.0 && (*local)[a] <= 1.0)) return out;
    const auto ws = axis_weights(lattice.basis, lattice.divisions.x, local->x);
    const auto wt = axis_weights(lattice.basis, lattice.divisions.y, local->y);
    const auto wu = axis_weights(lattice.basis, lattice.divisions.z, local->z);
    for (int i = 0; i <= lattice.divisions.x; ++i)
        for (int j = 0; j <= lattice.divisions.y; ++j)
            for (int k = 0; k <= lattice.divisions.z; ++k)
                out[lattice.index(i, j, k)] = ws[i] * wt[j] * wu[k];
    return out;
}

std::vector<std::uint32_t> brush_select(const Lattice& lattice, const glm::dvec3& point,
                                        const BrushOptions& options) {
    const std::vector<double> w = control_point_weights(lattice, point);
    const double max_w = w.empty() ? 0.0 : *std::max_element(w.begin(), w.end());
    if (!(max_w > 0.0)) return {};
    std::vector<std::uint32_t> order(w.size());
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(),
                     [&](std::uint32_t a, std::uint32_t b) { return w[a] > w[b]; });
    std::vector<std::uint32_t> out;
    for (std::uint32_t i : order) {
        if (options.top_k && out.size() >= options.top_k) break;
        if (w[i] < options.min_fraction * max_w || !(w[i] > 0.0)) break;
        out.push_back(i);
    }
    return out;
}

std::optional<glm::dvec3> surface_hit_in_lattice_space(const ecs::Registry& registry, ecs::Entity lattice,
                                                       const PickHit& hit) {
    if (!registry.valid(hit.entity) || !registry.valid(lattice)) return std::nullopt;
    if (hit.kind == PickKind::gaussian) {
        // A Gaussian brushes from its authored centre (the ellipsoid is a blob, not a surface patch).
        const GaussianCloud* g = registry.try_get<GaussianCloud>(hit.entity);
        if (!g || hit.index >= g->size()) return std::nullopt;
        const glm::dvec4 world = model_matrix(registry.try_get<Transform>(hit.entity)) *
                                 glm::dvec4(g->origin + glm::dvec3(g->positions[hit.index]), 1.0);
        return glm::dvec3(glm::inverse(model_matrix(registry.try_get<Transform>(lattice))) * world);
    }
    if (hit.kind != PickKind::surface) return std::nullopt;
    const SplatCloud* cloud = registry.try_get<SplatCloud>(hit.entity);
    if (!cloud || hit.index >= cloud->size()) return std::nullopt;
    glm::dvec3 rest = cloud->origin + glm::dvec3(cloud->positions[hit.index]);
    // The hit point's place on the splat, carried back through the authored axes (first order: the
    // deformed axes are J times the authored ones).
    if (cloud->axis_u.size() == cloud->size() && cloud->axis_v.size() == cloud->size())
        rest += hit.splat_coords.x * glm::dvec3(cloud->axis_u[hit.index]) +
                hit.splat_coords.y * glm::dvec3(cloud->axis_v[hit.index]);
    const glm::dvec4 world = model_matrix(registry.try_get<Transform>(hit.entity)) * glm::dvec4(rest, 1.0);
    return glm::dvec3(glm::inverse(model_matrix(registry.try_get<Transform>(lattice))) * world);
}

}  // namespace sffd::picking
