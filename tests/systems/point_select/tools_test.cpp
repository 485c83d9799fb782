// The screen and world tools against geometry whose answer is computed here: a grid of splats under a
// camera looking straight down (pinhole model in test_clouds.h), a sphere seen from outside (the visible
// cap is analytic), transformed and deformed clouds.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>

#include <glm/gtc/quaternion.hpp>

#include "runtime/app/frame_loop.h"
#include "runtime/ecs/registry.h"
#include "runtime/scene/lattice.h"
#include "runtime/scene/point_columns.h"
#include "systems/ffd/components.h"
#include "systems/gaussian/gaussian_system.h"
#include "systems/point_select/point_select.h"
#include "test_clouds.h"

namespace sffd::point_select {
namespace {

using test::pinhole;
using test::top_view;

// Camera of the grid tests: slightly off the grid's axes so no point projects onto a region border.
constexpr double kCx = 0.0131, kCy = -0.0077, kH = 2.0;

// The indices i of `points` (world) whose pinhole projection satisfies `inside`.
std::vector<std::uint32_t> expected(const std::vector<glm::dvec3>& points,
                                    const std::function<bool(glm::dvec2)>& inside) {
    std::vector<std::uint32_t> out;
    for (std::size_t i = 0; i < points.size(); ++i)
        if (inside(pinhole(kCx, kCy, kH, points[i]))) out.push_back(std::uint32_t(i));
    return out;
}

std::vector<glm::dvec3> world_of(const SplatCloud& c) {
    std::vector<glm::dvec3> out;
    for (const glm::vec3& p : c.positions) out.push_back(c.origin + glm::dvec3(p));
    return out;
}

struct Grid : ::testing::Test {
    ecs::Registry reg;
    ecs::Entity e = reg.create();
    PointSelectState state;
    SplatCloud cloud = test::grid_cloud(61, 47, -1.5, -1.15, 0.05, 0.03f);
    picking::ScreenView view = top_view(kCx, kCy, kH);
    void SetUp() override { reg.emplace<SplatCloud>(e, cloud); }
};

bool in_box(glm::dvec2 p, glm::dvec2 a, glm::dvec2 b) {
    return p.x >= std::min(a.x, b.x) && p.x <= std::max(a.x, b.x) && p.y >= std::min(a.y, b.y) &&
           p.y <= std::max(a.y, b.y);
}

TEST_F(Grid, RectangleSelectsExactlyTheProjectedPointsInside) {
    const glm::dvec2 a(100.3, 50.2), b(400.7, 300.1);
    const auto want = expected(world_of(cloud), [&](glm::dvec2 p) { return in_box(p, a, b); });
    ASSERT_GT(want.size(), 100u);
    for (bool visible : {true, false}) {
        EXPECT_EQ(points_in_region(reg, state, e, view, rect_region(a, b), {.visible_only = visible}), want);
        EXPECT_EQ(points_in_region(reg, state, e, view, rect_region(b, a), {.visible_only = visible}), want);
    }
    const SelectionDelta d = select_region(reg, state, e, view, rect_region(a, b), {});
    EXPECT_EQ(d.indices(), want);
    EXPECT_EQ(selected_points(reg, e), want);
    EXPECT_GT(state.stats().blocks_culled + state.stats().blocks_tested, 0u);
}

TEST_F(Grid, BrushCircleSelectsThePointsWithinItsRadius) {
    const glm::dvec2 c(320.4, 240.2);
    const double r = 57.3;
    const auto want = expected(world_of(cloud), [&](glm::dvec2 p) { return glm::length(p - c) <= r; });
    ASSERT_GT(want.size(), 20u);
    EXPECT_EQ(points_in_region(reg, state, e, view, circle_region(c, r), {}), want);
    // A stroke: stamps add up.
    select_region(reg, state, e, view, circle_region(c, r), {.mode = Mode::add});
    select_region(reg, state, e, view, circle_region(c + glm::dvec2(40, 0), r), {.mode = Mode::add});
    const auto both = expected(world_of(cloud), [&](glm::dvec2 p) {
        return glm::length(p - c) <= r || glm::length(p - c - glm::dvec2(40, 0)) <= r;
    });
    EXPECT_EQ(selected_points(reg, e), both);
}

TEST_F(Grid, LassoFollowsAConcavePath) {
    // An L: the union of [100, 300] x [80, 400] and [100, 520] x [300, 400], traced as a freehand path
    // (a vertex every 3 px, as a mouse drag gives).
    const std::vector<glm::dvec2> corners = {{100.5, 80.5},  {300.5, 80.5},  {300.5, 300.5},
                                             {520.5, 300.5}, {520.5, 400.5}, {100.5, 400.5}};
    std::vector<glm::dvec2> path;
    for (std::size_t k = 0; k < corners.size(); ++k) {
        const glm::dvec2 p = corners[k], q = corners[(k + 1) % corners.size()];
        const int steps = std::max(1, int(glm::length(q - p) / 3.0));
        for (int s = 0; s < steps; ++s) path.push_back(p + (q - p) * (double(s) / steps));
    }
    const auto want = expected(world_of(cloud), [&](glm::dvec2 p) {
        return in_box(p, corners[0], corners[2]) || in_box(p, {100.5, 300.5}, corners[4]);
    });
    ASSERT_GT(want.size(), 200u);
    EXPECT_EQ(points_in_region(reg, state, e, view, polygon_region(path), {.visible_only = false}), want);
}

TEST_F(Grid, PolygonOfClickedVerticesSelectsInsideTheTriangle) {
    const glm::dvec2 a(80.2, 400.3), b(560.7, 420.1), c(300.9, 60.4);
    auto side = [](glm::dvec2 p, glm::dvec2 q, glm::dvec2 x) {
        return (q.x - p.x) * (x.y - p.y) - (q.y - p.y) * (x.x - p.x);
    };
    const auto want = expected(world_of(cloud), [&](glm::dvec2 x) {
        const double s1 = side(a, b, x), s2 = side(b, c, x), s3 = side(c, a, x);
        return (s1 >= 0 && s2 >= 0 && s3 >= 0) || (s1 <= 0 && s2 <= 0 && s3 <= 0);
    });
    ASSERT_GT(want.size(), 200u);
    EXPECT_EQ(points_in_region(reg, state, e, view, polygon_region({a, b, c}), {}), want);
    EXPECT_TRUE(points_in_region(reg, state, e, view, polygon_region({a, b}), {}).empty());
}

TEST_F(Grid, WholeFootprintNeedsTheDiscInside) {
    const glm::dvec2 a(100.3, 50.2), b(400.7, 300.1);
    const double rpx = 0.03 * (test::kHeight * 0.5) / kH;  // disc radius at depth kH: 3.6 px
    const auto want = expected(world_of(cloud),
                               [&](glm::dvec2 p) { return in_box(p - rpx, a, b) && in_box(p + rpx, a, b); });
    const auto centre = points_in_region(reg, state, e, view, rect_region(a, b), {});
    const auto whole =
        points_in_region(reg, state, e, view, rect_region(a, b), {.footprint = Footprint::whole});
    EXPECT_EQ(whole, want);
    EXPECT_LT(whole.size(), centre.size());
}

TEST_F(Grid, ClickPicksThePointUnderTheCursor) {
    const std::vector<glm::dvec3> w = world_of(cloud);
    const std::uint32_t target = 47 * 10 + 5 + 61 * 20;  // some point near the middle
    const glm::dvec2 at = pinhole(kCx, kCy, kH, w[target]) + glm::dvec2(0.9, -0.7);
    EXPECT_EQ(point_under_cursor(reg, state, e, view, at), target);
    EXPECT_EQ(point_under_cursor(reg, state, e, view, at, {.visible_only = false}), target);
    select_click(reg, state, e, view, at, Mode::set);
    EXPECT_EQ(selected_points(reg, e), std::vector<std::uint32_t>{target});
    // Past the grid's last column (x = 1.5; 118 px further on screen) nothing is hit, and a plain click
    // there clears the selection.
    const glm::dvec2 off = pinhole(kCx, kCy, kH, {2.5, 0.0, 0.0});
    EXPECT_FALSE(point_under_cursor(reg, state, e, view, off).has_value());
    select_click(reg, state, e, view, off, Mode::set);
    EXPECT_TRUE(selected_points(reg, e).empty());
}

TEST_F(Grid, HiddenAndDeletedPointsAreNeverSelected) {
    PointFlags& f = reg.emplace<PointFlags>(e);
    f.bits.assign(cloud.size(), 0);
    for (std::size_t i = 0; i < cloud.size(); i += 7) f.bits[i] = kPointHidden;
    for (std::size_t i = 3; i < cloud.size(); i += 11) f.bits[i] |= kPointDeleted;
    f.bits[14] |= kPointSelected;  // a stray bit on a hidden point
    auto gone = [&](std::uint32_t i) { return i % 7 == 0 || (i >= 3 && (i - 3) % 11 == 0); };
    const glm::dvec2 a(0, 0), b(test::kWidth, test::kHeight);
    for (const auto& sel : {points_in_region(reg, state, e, view, rect_region(a, b), {}),
                            points_in_region(reg, state, e, view, circle_region({320, 240}, 500), {})})
        for (std::uint32_t i : sel) EXPECT_FALSE(gone(i)) << i;
    select_all(reg, e);
    for (std::uint32_t i = 0; i < cloud.size(); ++i)
        EXPECT_EQ((reg.get<PointFlags>(e).bits[i] & kPointSelected) != 0, !gone(i)) << i;
    invert_selection(reg, e);
    EXPECT_TRUE(selected_points(reg, e).empty());
    for (std::uint8_t bits : reg.get<PointFlags>(e).bits) EXPECT_EQ(bits & kPointSelected, 0);
    // A click on a hidden point's centre finds nothing (its neighbours' discs, 3.6 px, end short of it at
    // 6 px); on a visible one's it finds that one.
    const std::uint32_t hidden = 7 * 300;
    const glm::dvec2 at = pinhole(kCx, kCy, kH, world_of(cloud)[hidden]);
    EXPECT_FALSE(point_under_cursor(reg, state, e, view, at, {.tolerance_px = 0.0}).has_value());
    const glm::dvec2 at_next = pinhole(kCx, kCy, kH, world_of(cloud)[hidden + 1]);
    EXPECT_EQ(point_under_cursor(reg, state, e, view, at_next, {.tolerance_px = 0.0}), hidden + 1);
}

// A sphere seen from (0, 0, 4): the visible cap is z > 1/4 (where the line of sight is tangent).
TEST(PointSelectSphere, VisibleOnlyTakesTheFrontCapXrayTakesAll) {
    ecs::Registry reg;
    const ecs::Entity e = reg.create();
    const SplatCloud cloud = test::sphere_cloud(4000, 0.07f);
    reg.emplace<SplatCloud>(e, cloud);
    Camera cam;
    cam.eye = {0, 0, 4}, cam.target = {0, 0, 0}, cam.fov_y_degrees = 40.0f;
    const picking::ScreenView view = picking::make_screen_view(cam, {400, 400});
    PointSelectState state;
    const ScreenRegion all = rect_region({0, 0}, {400, 400});
    const auto xray = points_in_region(reg, state, e, view, all, {.visible_only = false});
    EXPECT_EQ(xray.size(), cloud.size());
    const auto visible = points_in_region(reg, state, e, view, all, {});
    std::size_t front = 0;
    for (std::uint32_t i = 0; i < cloud.size(); ++i) {
        const float z = cloud.positions[i].z;
        const bool got = std::binary_search(visible.begin(), visible.end(), i);
        if (z > 0.25f + 0.15f) {
            EXPECT_TRUE(got) << i << " z " << z;
        }
        if (z < 0.25f - 0.15f) {
            EXPECT_FALSE(got) << i << " z " << z;
        }
        front += z > 0.25f;
    }
    EXPECT_NEAR(double(visible.size()), double(front), 0.1 * double(front));
    // The click takes the front point, never one behind it.
    const auto hit = point_under_cursor(reg, state, e, view, {200.3, 200.6});
    ASSERT_TRUE(hit.has_value());
    EXPECT_GT(cloud.positions[*hit].z, 0.9f);
}

TEST(PointSelectTransform, TheCloudTransformPlacesThePoints) {
    ecs::Registry reg;
    const ecs::Entity e = reg.create();
    SplatCloud cloud = test::grid_cloud(41, 41, -1.0, -1.0, 0.05, 0.03f);
    cloud.origin = {1000.0, -500.0, 0.0};  // far from the world origin, as scans are
    reg.emplace<SplatCloud>(e, cloud);
    Transform t;
    t.rotation = glm::angleAxis(glm::radians(30.0), glm::dvec3(0, 0, 1));
    t.scale = glm::dvec3(0.8);
    t.translation = -(t.rotation * (0.8 * cloud.origin)) + glm::dvec3(0.3, -0.2, -0.3);  // near the camera
    reg.emplace<Transform>(e, t);
    // By hand: world = translation + R (scale * (origin + p)).
    std::vector<glm::dvec3> w;
    const double c = std::cos(glm::radians(30.0)), s = std::sin(glm::radians(30.0));
    for (const glm::vec3& p : cloud.positions) {
        const glm::dvec3 q = 0.8 * (cloud.origin + glm::dvec3(p));
        w.push_back(t.translation + glm::dvec3(c * q.x - s * q.y, s * q.x + c * q.y, q.z));
    }
    PointSelectState state;
    const glm::dvec2 a(150.2, 100.4), b(420.6, 330.8);
    const auto want = expected(w, [&](glm::dvec2 p) { return in_box(p, a, b); });
    ASSERT_GT(want.size(), 100u);
    EXPECT_EQ(points_in_region(reg, state, e, top_view(kCx, kCy, kH), rect_region(a, b), {}), want);
    // The sphere tool in world units, through the same Transform.
    const glm::dvec3 centre = w[820] + glm::dvec3(0.011, -0.013, 0.0);
    std::vector<std::uint32_t> near;
    for (std::uint32_t i = 0; i < w.size(); ++i)
        if (glm::length(w[i] - centre) <= 0.17) near.push_back(i);
    EXPECT_EQ(points_in_sphere(reg, state, e, centre, 0.17), near);
}

// A lattice whose control points are stretched by 2 along x maps x' = 2x: the tools see the moved points.
Lattice stretch_lattice() {
    Lattice l = make_lattice({-2.0, -2.0, -1.0},
                             {glm::dvec3(4, 0, 0), glm::dvec3(0, 4, 0), glm::dvec3(0, 0, 2)}, {1, 1, 1});
    for (glm::dvec3& p : l.current) p.x *= 2.0;
    return l;
}

TEST(PointSelectDeformed, SplatsAreSelectedWhereTheDeformationPutsThem) {
    ecs::Registry reg;
    const ecs::Entity lattice = reg.create();
    reg.emplace<Lattice>(lattice, stretch_lattice());
    const ecs::Entity e = reg.create();
    const SplatCloud cloud = test::grid_cloud(41, 41, -1.0, -1.0, 0.05, 0.03f);
    reg.emplace<SplatCloud>(e, cloud);
    reg.emplace<Deformers>(e, Deformers{{lattice}});
    std::vector<glm::dvec3> w = world_of(cloud);
    for (glm::dvec3& p : w) p.x *= 2.0;
    PointSelectState state;  // no deformation phase has run: picking's own CPU deformation is used
    const glm::dvec2 a(350.2, 100.4), b(620.6, 330.8);
    const auto want = expected(w, [&](glm::dvec2 p) { return in_box(p, a, b); });
    const auto rest = expected(world_of(cloud), [&](glm::dvec2 p) { return in_box(p, a, b); });
    ASSERT_NE(want, rest);
    EXPECT_EQ(points_in_region(reg, state, e, top_view(kCx, kCy, kH), rect_region(a, b), {}), want);
}

TEST(PointSelectDeformed, GaussiansAreSelectedFromTheDeformationPhaseOutput) {
    ecs::Registry reg;
    const ecs::Entity lattice = reg.create();
    reg.emplace<Lattice>(lattice, stretch_lattice());
    const ecs::Entity e = reg.create();
    const SplatCloud grid = test::grid_cloud(41, 41, -1.0, -1.0, 0.05, 0.03f);
    reg.emplace<GaussianCloud>(e, test::gaussians_of(grid, 0.012f));
    reg.emplace<Deformers>(e, Deformers{{lattice}});
    gaussian_deform_system(reg, FrameContext{});
    std::vector<glm::dvec3> w = world_of(grid);
    for (glm::dvec3& p : w) p.x *= 2.0;
    PointSelectState state;
    const glm::dvec2 a(350.2, 100.4), b(620.6, 330.8);
    const auto want = expected(w, [&](glm::dvec2 p) { return in_box(p, a, b); });
    ASSERT_NE(want, expected(world_of(grid), [&](glm::dvec2 p) { return in_box(p, a, b); }));
    EXPECT_EQ(points_in_region(reg, state, e, top_view(kCx, kCy, kH), rect_region(a, b), {}), want);
    // Selections are indices: they stay on the same Gaussians when the lattice moves back.
    select_region(reg, state, e, top_view(kCx, kCy, kH), rect_region(a, b), {});
    reg.patch<Lattice>(lattice).current = reg.get<Lattice>(lattice).rest;
    gaussian_deform_system(reg, FrameContext{});
    EXPECT_EQ(selected_points(reg, e), want);
    const auto rest = expected(world_of(grid), [&](glm::dvec2 p) { return in_box(p, a, b); });
    EXPECT_EQ(points_in_region(reg, state, e, top_view(kCx, kCy, kH), rect_region(a, b), {}), rest);
}

}  // namespace
}  // namespace sffd::point_select
