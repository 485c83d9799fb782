// Selection operations: click modes, box select (with and without hidden points), and the surface brush
// checked against an independent evaluation of the basis (de Casteljau for Bernstein, the four cubic
// pieces of notes/ffd-math.md for B-splines).
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>

#include "runtime/ecs/registry.h"
#include "systems/picking/picking_system.h"
#include "systems/picking/selection.h"
#include "test_scenes.h"

namespace sffd::picking {
namespace {

using test::box_lattice;
using test::disc_grid;
using test::expected_pixel;
using test::top_camera;

using Indices = std::vector<std::uint32_t>;

TEST(Selection, ClickShiftClickCtrlClick) {
    EXPECT_EQ(select_mode(false, false), SelectMode::replace);
    EXPECT_EQ(select_mode(true, false), SelectMode::add);
    EXPECT_EQ(select_mode(false, true), SelectMode::remove);
    EXPECT_EQ(select_mode(true, true), SelectMode::remove);

    LatticeSelection sel;
    sel = select(sel, Indices{5}, SelectMode::replace);
    EXPECT_EQ(sel.indices, Indices{5});
    sel = select(sel, Indices{2}, SelectMode::replace);
    EXPECT_EQ(sel.indices, Indices{2});
    sel = select(sel, Indices{9, 1, 9}, SelectMode::add);
    EXPECT_EQ(sel.indices, (Indices{1, 2, 9}));
    sel = select(sel, Indices{2}, SelectMode::add);  // already selected: unchanged
    EXPECT_EQ(sel.indices, (Indices{1, 2, 9}));
    sel = select(sel, Indices{2, 7}, SelectMode::remove);
    EXPECT_EQ(sel.indices, (Indices{1, 9}));
    EXPECT_TRUE(is_selected(sel, 9));
    EXPECT_FALSE(is_selected(sel, 2));
    sel = select(sel, Indices{}, SelectMode::add);
    EXPECT_EQ(sel.indices, (Indices{1, 9}));
    sel = select(sel, Indices{}, SelectMode::replace);  // click into empty space
    EXPECT_TRUE(sel.indices.empty());
}

struct BoxScene {
    ecs::Registry reg;
    ecs::Entity lattice;
    Camera cam = top_camera(1.0, 1.0, 5.0);
    ScreenView view = make_screen_view(cam, {200, 200});
    BoxScene() {
        lattice = reg.create();
        reg.emplace<Lattice>(lattice, box_lattice({0, 0, 0}, {2, 2, 1}, {2, 2, 1}));
        // A sheet at z = 0.5 over [-0.3, 0.8]^2 hides some bottom-layer points from the eye.
        const ecs::Entity sheet = reg.create();
        reg.emplace<SplatCloud>(sheet, disc_grid(12, 0.1, 0.08, 0.5, {-0.3, -0.3}));
    }
    // Independent answers: inside the rectangle by the pinhole model; hidden when the segment from the
    // eye crosses z = 0.5 inside the sheet.
    Indices expected(glm::dvec2 lo, glm::dvec2 hi, bool visible_only) const {
        Indices out;
        const Lattice& l = reg.get<Lattice>(lattice);
        for (std::uint32_t i = 0; i < l.current.size(); ++i) {
            const glm::dvec3 p = l.current[i];
            const glm::dvec2 px = expected_pixel(cam, 200, p);
            if (px.x < lo.x || px.x > hi.x || px.y < lo.y || px.y > hi.y) continue;
            if (visible_only && p.z < 0.5) {
                const double s = (cam.eye.z - 0.5) / (cam.eye.z - p.z);
                const glm::dvec3 x = cam.eye + s * (p - cam.eye);
                if (x.x >= -0.3 && x.x <= 0.8 && x.y >= -0.3 && x.y <= 0.8) continue;
            }
            out.push_back(i);
        }
        return out;
    }
};

TEST(Selection, BoxSelectMatchesPinholeProjection) {
    BoxScene s;
    PickingState state;
    const ScreenRect rect{{110.0, 200.0}, {70.0, 0.0}};  // dragged from bottom-right to top-left
    const Indices all = control_points_in_rect(s.reg, state, s.lattice, s.view, rect, false);
    EXPECT_EQ(all, s.expected({70, 0}, {110, 200}, false));
    EXPECT_EQ(all.size(), 12u);  // the i = 0 and i = 1 columns

    const Indices visible = control_points_in_rect(s.reg, state, s.lattice, s.view, rect, true);
    EXPECT_EQ(visible, s.expected({70, 0}, {110, 200}, true));
    EXPECT_LT(visible.size(), all.size());                                 // the sheet really hides something
    EXPECT_FALSE(std::binary_search(visible.begin(), visible.end(), 0u));  // (0,0,0) is under the sheet

    // A rectangle around nothing.
    EXPECT_TRUE(control_points_in_rect(s.reg, state, s.lattice, s.view, {{0, 0}, {10, 10}}, false).empty());
}

// Independent Bernstein by de Casteljau's recursion.
double bernstein_dc(int n, int i, double x) {
    std::vector<double> b(std::size_t(n) + 1, 0.0);
    b[0] = 1.0;
    for (int d = 1; d <= n; ++d)
        for (int k = d; k >= 0; --k) b[k] = (1.0 - x) * b[k] + (k > 0 ? x * b[k - 1] : 0.0);
    return b[i];
}

// Independent cubic B-spline: the four pieces B0..B3 of the cell containing x.
double bspline_pieces(int divisions, int i, double s) {
    const double x = divisions * s;
    const int cell = std::min(int(std::floor(x)), divisions - 1);
    const double f = x - cell;
    switch (i - cell) {
        case -1: return (1 - f) * (1 - f) * (1 - f) / 6;
        case 0: return (3 * f * f * f - 6 * f * f + 4) / 6;
        case 1: return (-3 * f * f * f + 3 * f * f + 3 * f + 1) / 6;
        case 2: return f * f * f / 6;
        default: return 0.0;
    }
}

Indices expected_top(const Lattice& l, glm::dvec3 local, std::size_t k) {
    std::vector<double> w(l.size());
    for (int i = 0; i <= l.divisions.x; ++i)
        for (int j = 0; j <= l.divisions.y; ++j)
            for (int c = 0; c <= l.divisions.z; ++c) {
                const bool bern = l.basis == LatticeBasis::bernstein;
                const double wi = bern ? bernstein_dc(l.divisions.x, i, local.x)
                                       : bspline_pieces(l.divisions.x, i, local.x);
                const double wj = bern ? bernstein_dc(l.divisions.y, j, local.y)
                                       : bspline_pieces(l.divisions.y, j, local.y);
                const double wk = bern ? bernstein_dc(l.divisions.z, c, local.z)
                                       : bspline_pieces(l.divisions.z, c, local.z);
                w[(std::size_t(i) * (l.divisions.y + 1) + j) * (l.divisions.z + 1) + c] = wi * wj * wk;
            }
    Indices order(w.size());
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(), [&](auto a, auto b) { return w[a] > w[b]; });
    order.resize(k);
    return order;
}

TEST(Brush, BernsteinTopKMatchesIndependentWeights) {
    // A non-axis-aligned lattice, so local coordinates are not just a rescaling.
    Lattice l = box_lattice({0, 0, 0}, {1, 1, 1}, {3, 2, 4});
    l.origin = {1.0, -2.0, 0.5};
    l.axes = {glm::dvec3(2.0, 0.5, 0.0), glm::dvec3(-0.3, 1.5, 0.2), glm::dvec3(0.1, 0.0, 1.2)};
    const glm::dvec3 local{0.23, 0.71, 0.42};
    const glm::dvec3 x = l.origin + local.x * l.axes[0] + local.y * l.axes[1] + local.z * l.axes[2];
    const auto back = lattice_local_coordinates(l, x);
    ASSERT_TRUE(back);
    EXPECT_NEAR(back->x, local.x, 1e-12);
    EXPECT_NEAR(back->y, local.y, 1e-12);
    EXPECT_NEAR(back->z, local.z, 1e-12);

    EXPECT_EQ(brush_select(l, x, {.top_k = 6, .min_fraction = 0.0}), expected_top(l, local, 6));
    // The weights sum to one (partition of unity) and match de Casteljau one by one.
    const std::vector<double> w = control_point_weights(l, x);
    EXPECT_NEAR(std::accumulate(w.begin(), w.end(), 0.0), 1.0, 1e-12);
    EXPECT_NEAR(w[l.index(1, 1, 2)],
                bernstein_dc(3, 1, 0.23) * bernstein_dc(2, 1, 0.71) * bernstein_dc(4, 2, 0.42), 1e-14);

    // Fraction rule: every kept weight >= half the maximum, every dropped one below.
    const Indices half = brush_select(l, x, {.top_k = 0, .min_fraction = 0.5});
    const double wmax = *std::max_element(w.begin(), w.end());
    ASSERT_FALSE(half.empty());
    EXPECT_EQ(half.front(), expected_top(l, local, 1).front());
    for (std::uint32_t i = 0; i < w.size(); ++i)
        EXPECT_EQ(std::find(half.begin(), half.end(), i) != half.end(), w[i] >= 0.5 * wmax) << i;

    // Outside the lattice: no influence, nothing selected.
    EXPECT_TRUE(brush_select(l, l.origin - l.axes[0] * 0.1, {}).empty());
    // Malformed lattices (no cells; control points not matching the divisions; flat box): nothing.
    Lattice flat = l;
    flat.divisions.y = 0;
    EXPECT_TRUE(brush_select(flat, x, {}).empty());
    Lattice short_points = l;
    short_points.current.pop_back();
    EXPECT_TRUE(brush_select(short_points, x, {}).empty());
    Lattice degenerate = l;
    degenerate.axes[2] = degenerate.axes[0];
    EXPECT_FALSE(lattice_local_coordinates(degenerate, x));
    EXPECT_TRUE(brush_select(degenerate, x, {}).empty());
}

TEST(Brush, BsplineTopKMatchesIndependentWeights) {
    const Lattice l = box_lattice({0, 0, 0}, {1, 1, 1}, {5, 5, 5}, LatticeBasis::bspline);
    const glm::dvec3 local{0.37, 0.52, 0.81};
    EXPECT_EQ(brush_select(l, local, {.top_k = 8, .min_fraction = 0.0}), expected_top(l, local, 8));
    const std::vector<double> w = control_point_weights(l, local);
    EXPECT_NEAR(w[l.index(2, 2, 4)],
                bspline_pieces(5, 2, 0.37) * bspline_pieces(5, 2, 0.52) * bspline_pieces(5, 4, 0.81), 1e-14);
    // Local support: at most 4 x 4 x 4 non-zero weights.
    EXPECT_LE(std::count_if(w.begin(), w.end(), [](double v) { return v > 0.0; }), 64);
}

TEST(Brush, SurfaceHitSelectsMostInfluentialControlPoints) {
    ecs::Registry reg;
    const ecs::Entity lat = reg.create();
    reg.emplace<Lattice>(lat, box_lattice({0, 0, 0}, {1, 1, 1}, {2, 2, 2}));
    const ecs::Entity cloud = reg.create();
    reg.emplace<SplatCloud>(cloud, disc_grid(11, 0.1, 0.045, 0.35));  // splats at multiples of 0.1, z = 0.35
    PickingState state;
    // The ray starts inside the lattice box above the sheet, off the centre of splat (2, 7) and far from
    // every control point. The brush point is the hit point itself, (0.22, 0.68, 0.35), whose weights
    // have no ties among the top three.
    const PickHit hit = pick(reg, state, query_from_ray({{0.22, 0.68, 0.9}, {0, 0, -1}}));
    ASSERT_EQ(hit.kind, PickKind::surface);
    EXPECT_EQ(hit.index, 7u * 11u + 2u);
    const auto x = surface_hit_in_lattice_space(reg, lat, hit);
    ASSERT_TRUE(x);
    EXPECT_NEAR(glm::length(*x - glm::dvec3(0.22, 0.68, 0.35)), 0.0, 1e-6);
    const Indices top = brush_select(reg.get<Lattice>(lat), *x, {.top_k = 3, .min_fraction = 0.0});
    EXPECT_EQ(top, expected_top(reg.get<Lattice>(lat), {0.22, 0.68, 0.35}, 3));
    // The first one carries the largest weight of all 27.
    const std::vector<double> w = control_point_weights(reg.get<Lattice>(lat), *x);
    EXPECT_DOUBLE_EQ(w[top[0]], *std::max_element(w.begin(), w.end()));
}

}  // namespace
}  // namespace sffd::picking
