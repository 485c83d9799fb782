// Picking against known geometry: rays at known control points and splats, occlusion, x-ray, screen
// tolerance, lazy refresh after the data moved, geometry-id -> entity mapping across entity reuse.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "runtime/ecs/registry.h"
#include "systems/picking/components.h"
#include "systems/picking/picking_state.h"
#include "systems/picking/picking_system.h"
#include "test_scenes.h"

namespace sffd::picking {
namespace {

using test::box_lattice;
using test::disc_grid;
using test::expected_pixel;
using test::top_camera;

Ray down_from(double x, double y, double z = 10.0) { return {{x, y, z}, {0.0, 0.0, -1.0}}; }

void expect_near(const glm::dvec3& a, const glm::dvec3& b, double eps) {
    EXPECT_NEAR(a.x, b.x, eps);
    EXPECT_NEAR(a.y, b.y, eps);
    EXPECT_NEAR(a.z, b.z, eps);
}

TEST(Picking, RayAtControlPointReturnsItsIndex) {
    ecs::Registry reg;
    const ecs::Entity lat = reg.create();
    reg.emplace<Lattice>(lat, box_lattice({0, 0, 0}, {2, 2, 2}, {2, 2, 2}));
    PickingState state;

    // Straight down through x=1, y=2: the first control point met is (1, 2, 2) = P[1][2][2].
    const PickHit hit = pick(reg, state, query_from_ray(down_from(1.0, 2.0)));
    ASSERT_EQ(hit.kind, PickKind::control_point);
    EXPECT_EQ(hit.entity, lat);
    EXPECT_EQ(hit.index, reg.get<Lattice>(lat).index(1, 2, 2));
    expect_near(hit.position, {1, 2, 2}, 1e-12);
    EXPECT_NEAR(hit.distance, 8.0, 1e-12);

    // Within the sphere radius (0.08 of a unit cell) still hits; beyond it, nothing.
    EXPECT_EQ(pick(reg, state, query_from_ray(down_from(1.05, 2.0))).index, 17u);
    EXPECT_EQ(pick(reg, state, query_from_ray(down_from(1.2, 2.0))).kind, PickKind::none);
    // From below, the k = 0 layer comes first.
    const PickHit below = pick(reg, state, query_from_ray({{0.0, 1.0, -5.0}, {0.0, 0.0, 1.0}}));
    EXPECT_EQ(below.index, reg.get<Lattice>(lat).index(0, 1, 0));
}

TEST(Picking, DiscCloudOnPlaneReturnsSplatAndHitPosition) {
    ecs::Registry reg;
    const ecs::Entity cloud = reg.create();
    reg.emplace<SplatCloud>(cloud, disc_grid(10, 1.0, 0.4, 0.0));
    PickingState state;

    const PickHit hit = pick(reg, state, query_from_ray(down_from(3.1, 4.2)));
    ASSERT_EQ(hit.kind, PickKind::surface);
    EXPECT_EQ(hit.entity, cloud);
    EXPECT_EQ(hit.index, 4u * 10u + 3u);
    expect_near(hit.position, {3.1, 4.2, 0.0}, 1e-5);
    EXPECT_NEAR(hit.distance, 10.0, 1e-5);

    // Between four discs (0.71 from every centre, radius 0.4): nothing.
    EXPECT_EQ(pick(reg, state, query_from_ray(down_from(3.5, 4.5))).kind, PickKind::none);

    // Oblique ray from (0, 0, 10) to (6.2, 7.1, 0).
    const glm::dvec3 target{6.2, 7.1, 0.0};
    const PickHit oblique = pick(reg, state, query_from_ray({{0, 0, 10}, target - glm::dvec3(0, 0, 10)}));
    EXPECT_EQ(oblique.index, 7u * 10u + 6u);
    expect_near(oblique.position, target, 1e-5);
    EXPECT_NEAR(oblique.distance, glm::length(target - glm::dvec3(0, 0, 10)), 1e-5);
}

TEST(Picking, EllipticalSplatIsTrimmedToItsEllipse) {
    ecs::Registry reg;
    const ecs::Entity cloud = reg.create();
    SplatCloud c = disc_grid(1, 1.0, 1.0, 0.0);
    c.axis_u[0] = {1.0f, 0.0f, 0.0f};
    c.axis_v[0] = {0.0f, 0.1f, 0.0f};
    reg.emplace<SplatCloud>(cloud, std::move(c));
    PickingState state;
    EXPECT_EQ(pick(reg, state, query_from_ray(down_from(0.9, 0.0))).kind, PickKind::surface);
    EXPECT_EQ(pick(reg, state, query_from_ray(down_from(0.0, 0.09))).kind, PickKind::surface);
    // Inside the bounding circle (radius 1) but outside the ellipse.
    EXPECT_EQ(pick(reg, state, query_from_ray(down_from(0.0, 0.5))).kind, PickKind::none);
    EXPECT_EQ(pick(reg, state, query_from_ray(down_from(0.6, 0.09))).kind, PickKind::none);
}

TEST(Picking, SurfaceInFrontHidesControlPointUnlessXray) {
    ecs::Registry reg;
    const ecs::Entity cloud = reg.create();
    reg.emplace<SplatCloud>(cloud, disc_grid(21, 0.1, 0.08, 0.0));  // covers [0, 2]^2 at z = 0
    const ecs::Entity lat = reg.create();
    reg.emplace<Lattice>(lat, box_lattice({0.5, 0.5, -3.0}, {1.5, 1.5, -0.5}, {1, 1, 1}));  // below it
    PickingState state;

    PickQuery q = query_from_ray(down_from(0.5, 0.5));
    const PickHit hidden = pick(reg, state, q);
    ASSERT_EQ(hidden.kind, PickKind::surface);
    EXPECT_EQ(hidden.entity, cloud);
    EXPECT_EQ(hidden.index, 5u * 21u + 5u);

    q.xray = true;
    const PickHit xray = pick(reg, state, q);
    ASSERT_EQ(xray.kind, PickKind::control_point);
    EXPECT_EQ(xray.entity, lat);
    EXPECT_EQ(xray.index, reg.get<Lattice>(lat).index(0, 0, 1));  // (0.5, 0.5, -0.5), the nearer one
    EXPECT_NEAR(xray.distance, 10.5, 1e-12);

    // Through the screen: the cursor 3 px from the hidden point's projection (towards the image centre,
    // away from P[0][0][0], whose projection lies 2.9 px further out).
    const Camera cam = top_camera(1.0, 1.0, 5.0);
    const ScreenView view = make_screen_view(cam, {200, 200});
    const glm::dvec2 px = expected_pixel(cam, 200, {0.5, 0.5, -0.5}) + glm::dvec2(-3.0, 0.0);
    PickQuery sq = query_at_pixel(view, px);
    EXPECT_EQ(pick(reg, state, sq).kind, PickKind::surface);
    sq.xray = true;
    const PickHit sx = pick(reg, state, sq);
    EXPECT_EQ(sx.kind, PickKind::control_point);
    EXPECT_EQ(sx.index, reg.get<Lattice>(lat).index(0, 0, 1));
}

TEST(Picking, NearerOfTwoSurfacesWins) {
    ecs::Registry reg;
    const ecs::Entity low = reg.create();
    reg.emplace<SplatCloud>(low, disc_grid(10, 1.0, 0.4, 0.0));
    const ecs::Entity high = reg.create();
    reg.emplace<SplatCloud>(high, disc_grid(10, 1.0, 0.4, 1.0));
    PickingState state;

    const PickHit from_above = pick(reg, state, query_from_ray(down_from(2.0, 3.0)));
    EXPECT_EQ(from_above.entity, high);
    EXPECT_EQ(from_above.index, 32u);
    EXPECT_NEAR(from_above.distance, 9.0, 1e-5);
    const PickHit from_below = pick(reg, state, query_from_ray({{2.0, 3.0, -10.0}, {0, 0, 1}}));
    EXPECT_EQ(from_below.entity, low);
    EXPECT_NEAR(from_below.distance, 10.0, 1e-5);
}

TEST(Picking, ControlPointDrawnOverSurfaceWinsWithinTolerance) {
    ecs::Registry reg;
    const ecs::Entity cloud = reg.create();
    reg.emplace<SplatCloud>(cloud, disc_grid(21, 0.1, 0.08, 0.0));
    const ecs::Entity lat = reg.create();
    // Bottom layer 0.01 above the surface (visible), top layer far up (projects far from the cursor).
    reg.emplace<Lattice>(lat, box_lattice({0.5, 0.5, 0.01}, {1.5, 1.5, 3.0}, {1, 1, 1}));
    const Camera cam = top_camera(1.0, 1.0, 5.0);
    const ScreenView view = make_screen_view(cam, {200, 200});
    PickingState state;

    const glm::dvec2 p0 = expected_pixel(cam, 200, {0.5, 0.5, 0.01});
    const PickHit near_hit = pick(reg, state, query_at_pixel(view, p0 + glm::dvec2(4.0, 0.0)));
    ASSERT_EQ(near_hit.kind, PickKind::control_point);
    EXPECT_EQ(near_hit.entity, lat);
    EXPECT_EQ(near_hit.index, 0u);
    expect_near(near_hit.position, {0.5, 0.5, 0.01}, 1e-12);

    // 12 px away (tolerance 6): the surface under the cursor.
    const PickHit far_hit = pick(reg, state, query_at_pixel(view, p0 + glm::dvec2(12.0, 0.0)));
    EXPECT_EQ(far_hit.kind, PickKind::surface);
    EXPECT_NEAR(far_hit.position.z, 0.0, 1e-5);

    // A tolerance of 3 px turns the 4 px case into a surface hit.
    PickQuery tight = query_at_pixel(view, p0 + glm::dvec2(4.0, 0.0));
    tight.tolerance_px = 3.0;
    EXPECT_EQ(pick(reg, state, tight).kind, PickKind::surface);
}

TEST(Picking, StaleSceneIsRefreshedOnceAndOnlyWhenPicked) {
    ecs::Registry reg;
    const ecs::Entity cloud = reg.create();
    reg.emplace<SplatCloud>(cloud, disc_grid(10, 1.0, 0.4, 0.0));
    PickingState state;
    EXPECT_NEAR(pick(reg, state, query_from_ray(down_from(2.0, 2.0))).distance, 10.0, 1e-5);
    const auto commits = state.stats().surface_commits;

    // Nothing changed: no commit.
    EXPECT_NEAR(pick(reg, state, query_from_ray(down_from(2.0, 2.0))).distance, 10.0, 1e-5);
    EXPECT_EQ(state.stats().surface_commits, commits);

    // Move the splats up by 1; without a pick nothing is refreshed.
    for (glm::vec3& p : reg.patch<SplatCloud>(cloud).positions) p.z += 1.0f;
    reg.set_resource<PickRequests>();  // present but nothing pending
    picking_system(reg, FrameContext{});
    EXPECT_EQ(state.stats().surface_commits, commits);

    EXPECT_NEAR(pick(reg, state, query_from_ray(down_from(2.0, 2.0))).distance, 9.0, 1e-5);
    EXPECT_EQ(state.stats().surface_commits, commits + 1);
    EXPECT_EQ(state.stats().geometries_updated, 1u);
    EXPECT_NEAR(pick(reg, state, query_from_ray(down_from(2.0, 2.0))).distance, 9.0, 1e-5);
    EXPECT_EQ(state.stats().surface_commits, commits + 1);
}

TEST(Picking, GeometryIdsFollowEntitiesAcrossDestroyAndCreate) {
    ecs::Registry reg;
    const ecs::Entity a = reg.create();
    reg.emplace<SplatCloud>(a, disc_grid(2, 1.0, 0.4, 0.0));
    const ecs::Entity b = reg.create();
    reg.emplace<SplatCloud>(b, disc_grid(2, 1.0, 0.4, 0.0, {5.0, 0.0}));
    PickingState state;
    EXPECT_EQ(pick(reg, state, query_from_ray(down_from(1.0, 1.0))).entity, a);
    EXPECT_EQ(pick(reg, state, query_from_ray(down_from(6.0, 1.0))).entity, b);

    reg.destroy(a);
    EXPECT_EQ(pick(reg, state, query_from_ray(down_from(1.0, 1.0))).kind, PickKind::none);
    EXPECT_EQ(state.surface_geometry_count(), 1u);

    const ecs::Entity c = reg.create();
    ASSERT_EQ(c.index, a.index);  // the registry reuses the slot with a new generation
    ASSERT_NE(c.generation, a.generation);
    reg.emplace<SplatCloud>(c, disc_grid(3, 1.0, 0.4, 2.0));
    const PickHit hc = pick(reg, state, query_from_ray(down_from(1.0, 1.0)));
    EXPECT_EQ(hc.entity, c);
    EXPECT_EQ(hc.index, 4u);
    EXPECT_NEAR(hc.distance, 8.0, 1e-5);
    EXPECT_EQ(pick(reg, state, query_from_ray(down_from(6.0, 1.0))).entity, b);
    EXPECT_EQ(state.surface_geometry_count(), 2u);

    // Removing the component (entity alive) also drops the geometry.
    reg.remove<SplatCloud>(b);
    EXPECT_EQ(pick(reg, state, query_from_ray(down_from(6.0, 1.0))).kind, PickKind::none);
    EXPECT_EQ(state.surface_geometry_count(), 1u);
}

TEST(Picking, TransformsPlaceCloudsAndLattices) {
    ecs::Registry reg;
    const ecs::Entity cloud = reg.create();
    reg.emplace<SplatCloud>(cloud, disc_grid(4, 1.0, 0.4, 0.0));
    Transform t;
    t.translation = {10.0, 0.0, 0.0};
    t.scale = glm::dvec3(2.0);
    reg.emplace<Transform>(cloud, t);
    PickingState state;
    // Splat (1, 2) sits at world (10 + 2, 4, 0); splat radius 0.8 after scaling.
    const PickHit hit = pick(reg, state, query_from_ray(down_from(12.7, 4.0)));
    EXPECT_EQ(hit.index, 2u * 4u + 1u);
    // Moving the transform refreshes the geometry.
    reg.patch<Transform>(cloud).translation.x = 20.0;
    EXPECT_EQ(pick(reg, state, query_from_ray(down_from(12.7, 4.0))).kind, PickKind::none);
    EXPECT_EQ(pick(reg, state, query_from_ray(down_from(22.0, 4.0))).index, 9u);
}

TEST(Picking, FarFromOriginKeepsPrecision) {
    ecs::Registry reg;
    const ecs::Entity cloud = reg.create();
    const glm::dvec3 origin{1e6, -2e6, 5e5};
    reg.emplace<SplatCloud>(cloud, disc_grid(10, 0.01, 0.004, origin.z, {origin.x, origin.y}, origin));
    PickingState state;
    const PickHit hit =
        pick(reg, state, query_from_ray(down_from(origin.x + 0.031, origin.y + 0.042, origin.z + 1.0)));
    ASSERT_EQ(hit.kind, PickKind::surface);
    EXPECT_EQ(hit.index, 43u);
    expect_near(hit.position, origin + glm::dvec3(0.031, 0.042, 0.0), 1e-5);
}

TEST(Picking, HostileDataIsSkippedNotCrashed) {
    ecs::Registry reg;
    const ecs::Entity cloud = reg.create();
    SplatCloud c = disc_grid(4, 1.0, 0.4, 0.0);
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    c.positions[0] = {nan, 0.0f, 0.0f};        // splat 0: NaN centre
    c.positions[1].z = inf;                    // splat 1: infinite centre
    c.axis_u[2] = c.axis_v[2] = glm::vec3(0);  // splat 2: zero size
    c.normals[3] = glm::vec3(0);               // splat 3: no normal
    c.axis_u[5] = {nan, nan, nan};             // splat 5: NaN axis
    reg.emplace<SplatCloud>(cloud, std::move(c));
    const ecs::Entity lat = reg.create();
    Lattice bad = box_lattice({0, 0, 5}, {1, 1, 6}, {1, 1, 1});
    bad.current[3] = glm::dvec3(std::numeric_limits<double>::quiet_NaN());
    reg.emplace<Lattice>(lat, bad);
    PickingState state;
    EXPECT_EQ(pick(reg, state, query_from_ray(down_from(2.0, 2.0))).index, 10u);  // healthy splats still pick
    EXPECT_EQ(pick(reg, state, query_from_ray(down_from(2.0, 0.0))).kind,
              PickKind::none);  // zero-size splat 2
    EXPECT_EQ(pick(reg, state, query_from_ray(down_from(0.0, 0.0))).kind,
              PickKind::control_point);  // P[0][0][1]
    // A NaN or zero ray answers "nothing".
    EXPECT_EQ(pick(reg, state, query_from_ray({{0, 0, 10}, {0, 0, 0}})).kind, PickKind::none);
    EXPECT_EQ(pick(reg, state, query_from_ray({{std::nan(""), 0, 10}, {0, 0, -1}})).kind, PickKind::none);
}

TEST(PickingSystem, AnswersPendingRequestOnce) {
    ecs::Registry reg;
    const ecs::Entity cloud = reg.create();
    reg.emplace<SplatCloud>(cloud, disc_grid(10, 1.0, 0.4, 0.0));

    picking_system(reg, FrameContext{});  // no request: nothing happens, no state is created
    EXPECT_EQ(reg.try_resource<PickingState>(), nullptr);
    EXPECT_EQ(reg.try_resource<PickResults>(), nullptr);

    const Camera cam = top_camera(4.5, 4.5, 10.0);
    const ScreenView view = make_screen_view(cam, {100, 100});
    const std::uint64_t id = post_pick(reg, query_at_pixel(view, expected_pixel(cam, 100, {3.0, 6.0, 0.0})));
    EXPECT_EQ(find_pick_answer(reg, id), nullptr) << "not answered before the picking phase";
    picking_system(reg, FrameContext{7, 0.0, 0.0});
    const PickResults& results = reg.resource<PickResults>();
    EXPECT_TRUE(reg.resource<PickRequests>().pending.empty());
    EXPECT_EQ(results.serial, 1u);
    EXPECT_EQ(results.frame, 7u);
    const PickHit* hit = find_pick_answer(reg, id);
    ASSERT_NE(hit, nullptr);
    EXPECT_EQ(hit->kind, PickKind::surface);
    EXPECT_EQ(hit->index, 63u);
    expect_near(hit->position, {3.0, 6.0, 0.0}, 1e-4);

    picking_system(reg, FrameContext{8, 0.0, 0.0});  // answered: not again
    EXPECT_EQ(reg.resource<PickResults>().serial, 1u);
    EXPECT_EQ(reg.resource<PickResults>().frame, 7u);
}

// Several gestures of one frame each post a pick: one phase answers all of them, each under its own id.
TEST(PickingSystem, AnswersEveryPickOfAFrameUnderItsId) {
    ecs::Registry reg;
    const ecs::Entity cloud = reg.create();
    reg.emplace<SplatCloud>(cloud, disc_grid(10, 1.0, 0.4, 0.0));
    const Camera cam = top_camera(4.5, 4.5, 10.0);
    const ScreenView view = make_screen_view(cam, {100, 100});
    const std::uint64_t a = post_pick(reg, query_at_pixel(view, expected_pixel(cam, 100, {3.0, 6.0, 0.0})));
    const std::uint64_t miss = post_pick(reg, query_from_ray({{50.0, 50.0, 10.0}, {0.0, 0.0, -1.0}}));
    const std::uint64_t b = post_pick(reg, query_at_pixel(view, expected_pixel(cam, 100, {7.0, 2.0, 0.0})));
    EXPECT_NE(a, miss);
    EXPECT_NE(a, b);
    picking_system(reg, FrameContext{3, 0.0, 0.0});
    ASSERT_NE(find_pick_answer(reg, a), nullptr);
    ASSERT_NE(find_pick_answer(reg, miss), nullptr);
    ASSERT_NE(find_pick_answer(reg, b), nullptr);
    EXPECT_EQ(find_pick_answer(reg, a)->index, 63u);
    EXPECT_EQ(find_pick_answer(reg, miss)->kind, PickKind::none);
    EXPECT_EQ(find_pick_answer(reg, b)->index, 27u);
    EXPECT_EQ(reg.resource<PickResults>().serial, 3u);
    // The next frame's picks replace the answers: an old id is no longer answered.
    const std::uint64_t c = post_pick(reg, query_at_pixel(view, expected_pixel(cam, 100, {3.0, 6.0, 0.0})));
    picking_system(reg, FrameContext{4, 0.0, 0.0});
    EXPECT_EQ(find_pick_answer(reg, a), nullptr);
    ASSERT_NE(find_pick_answer(reg, c), nullptr);
    EXPECT_EQ(find_pick_answer(reg, c)->index, 63u);
}

TEST(ScreenView, RayAndProjectionAgreeWithPinholeModel) {
    const Camera cam = top_camera(1.0, 2.0, 5.0);
    const ScreenView view = make_screen_view(cam, {200, 200});
    const glm::dvec3 p{1.7, 1.1, 0.5};
    const auto proj = project(view, p);
    ASSERT_TRUE(proj);
    const glm::dvec2 expected = expected_pixel(cam, 200, p);
    EXPECT_NEAR(proj->screen.x, expected.x, 1e-9);
    EXPECT_NEAR(proj->screen.y, expected.y, 1e-9);
    EXPECT_NEAR(proj->depth, 4.5, 1e-9);
    const Ray r = ray_through(view, expected);
    const glm::dvec3 dir = glm::normalize(p - cam.eye);
    expect_near(r.origin, cam.eye, 1e-12);
    expect_near(r.direction, dir, 1e-12);
    EXPECT_FALSE(project(view, {1.0, 2.0, 6.0}));  // behind the eye
}

}  // namespace
}  // namespace sffd::picking
