// Hidden and deleted points (PointFlags, kPointGone) are never hit: surface discs, point spheres (a cloud
// without normals) and Gaussians, against stacked geometry whose hits are known; a flag edit is seen by
// the next pick without rebuilding the geometry.
#include <gtest/gtest.h>

#include <glm/gtc/quaternion.hpp>

#include "runtime/ecs/registry.h"
#include "runtime/scene/components.h"
#include "runtime/scene/point_columns.h"
#include "systems/picking/components.h"
#include "systems/picking/picking_state.h"
#include "systems/picking/picking_system.h"
#include "test_scenes.h"

namespace sffd::picking {
namespace {

Ray down_from(double x, double y, double z = 10.0) { return {{x, y, z}, {0.0, 0.0, -1.0}}; }

// Two 4 x 4 disc grids in one cloud: indices 0..15 at z = 1, 16..31 at z = 0, the same (x, y).
SplatCloud two_layers(bool normals) {
    SplatCloud c = test::disc_grid(4, 1.0, 0.4, 1.0);
    const SplatCloud low = test::disc_grid(4, 1.0, 0.4, 0.0);
    for (auto* col : {&c.positions, &c.normals, &c.axis_u, &c.axis_v}) {
        const auto& from = col == &c.positions ? low.positions
                           : col == &c.normals ? low.normals
                           : col == &c.axis_u  ? low.axis_u
                                               : low.axis_v;
        col->insert(col->end(), from.begin(), from.end());
    }
    c.colors.insert(c.colors.end(), low.colors.begin(), low.colors.end());
    if (!normals) c.normals.clear();
    return c;
}

void set_flag(ecs::Registry& reg, ecs::Entity e, std::size_t i, std::uint8_t bits) {
    reg.patch<PointFlags>(e).bits[i] = bits;
}

class GonePoints : public ::testing::TestWithParam<bool> {};

TEST_P(GonePoints, HiddenAndDeletedSplatsAreNeverHit) {
    ecs::Registry reg;
    const ecs::Entity cloud = reg.create();
    reg.emplace<SplatCloud>(cloud, two_layers(GetParam()));
    reg.emplace<PointFlags>(cloud).bits.assign(32, 0);
    PickingState state;
    const std::size_t top = 2 * 4 + 1, bottom = 16 + top;  // the splats under (1, 2)
    const double sphere = GetParam() ? 0.0 : 0.4;          // a point sphere is hit at its radius

    PickHit hit = pick(reg, state, query_from_ray(down_from(1.0, 2.0)));
    ASSERT_EQ(hit.kind, PickKind::surface);
    EXPECT_EQ(hit.index, top);
    EXPECT_NEAR(hit.distance, 9.0 - sphere, 1e-4);
    const auto updates = state.stats().geometries_updated;

    set_flag(reg, cloud, top, kPointHidden);
    hit = pick(reg, state, query_from_ray(down_from(1.0, 2.0)));
    ASSERT_EQ(hit.kind, PickKind::surface);
    EXPECT_EQ(hit.index, bottom);  // through the hidden one to the one below
    EXPECT_NEAR(hit.distance, 10.0 - sphere, 1e-4);

    set_flag(reg, cloud, bottom, kPointDeleted | kPointSelected);
    EXPECT_EQ(pick(reg, state, query_from_ray(down_from(1.0, 2.0))).kind, PickKind::none);
    // Nothing hides what is behind gone points either.
    EXPECT_FALSE(state.surface_between({1.0, 2.0, 5.0}, {1.0, 2.0, -5.0}));
    // The neighbours are untouched.
    EXPECT_EQ(pick(reg, state, query_from_ray(down_from(2.0, 2.0))).index, top + 1);
    EXPECT_TRUE(state.surface_between({2.0, 2.0, 5.0}, {2.0, 2.0, -5.0}));

    set_flag(reg, cloud, top, 0);  // unhidden
    EXPECT_EQ(pick(reg, state, query_from_ray(down_from(1.0, 2.0))).index, top);
    EXPECT_EQ(state.stats().geometries_updated, updates);  // flag edits rebuilt no geometry

    reg.remove<PointFlags>(cloud);  // no flags: every point is there
    EXPECT_EQ(pick(reg, state, query_from_ray(down_from(1.0, 2.0))).index, top);
}

INSTANTIATE_TEST_SUITE_P(DiscsAndSpheres, GonePoints, ::testing::Values(true, false));

TEST(GonePoints, HiddenAndDeletedGaussiansAreNeverHit) {
    ecs::Registry reg;
    const ecs::Entity e = reg.create();
    GaussianCloud c;
    for (double z : {2.0, 0.0, -2.0}) {  // three unit-scale Gaussians along the ray, front to back
        c.positions.emplace_back(0.0f, 0.0f, float(z));
        c.scales.emplace_back(0.1f);
        c.rotations.emplace_back(1.0f, 0.0f, 0.0f, 0.0f);
        c.opacities.push_back(1.0f);
        c.sh.insert(c.sh.end(), {0.1f, 0.1f, 0.1f});
    }
    reg.emplace<GaussianCloud>(e, c);
    reg.emplace<PointFlags>(e).bits.assign(3, 0);
    PickingState state;
    const double k1 = std::sqrt(2.0 * std::log(255.0)) * 0.1;  // the alpha-cut radius at opacity 1

    PickHit hit = pick(reg, state, query_from_ray(down_from(0.0, 0.0)));
    ASSERT_EQ(hit.kind, PickKind::gaussian);
    EXPECT_EQ(hit.index, 0u);
    EXPECT_NEAR(hit.distance, 8.0 - k1, 1e-4);
    set_flag(reg, e, 0, kPointHidden);
    hit = pick(reg, state, query_from_ray(down_from(0.0, 0.0)));
    EXPECT_EQ(hit.index, 1u);
    EXPECT_NEAR(hit.distance, 10.0 - k1, 1e-4);
    set_flag(reg, e, 1, kPointDeleted);
    EXPECT_EQ(pick(reg, state, query_from_ray(down_from(0.0, 0.0))).index, 2u);
    set_flag(reg, e, 2, kPointHidden | kPointDeleted);
    EXPECT_EQ(pick(reg, state, query_from_ray(down_from(0.0, 0.0))).kind, PickKind::none);
    EXPECT_FALSE(state.surface_between({0.0, 0.0, 5.0}, {0.0, 0.0, -5.0}));
    set_flag(reg, e, 1, 0);
    EXPECT_EQ(pick(reg, state, query_from_ray(down_from(0.0, 0.0))).index, 1u);
    EXPECT_TRUE(state.surface_between({0.0, 0.0, 5.0}, {0.0, 0.0, -5.0}));
}

}  // namespace
}  // namespace sffd::picking
