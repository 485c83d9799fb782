// Picking a deformed surface: after a lattice stretch the ray hits the moved splat, the stale Embree
// scene is refreshed exactly once, and the deformer's CPU output (DeformedSplats) is preferred when valid.
#include <gtest/gtest.h>

#include "runtime/ecs/registry.h"
#include "systems/ffd/components.h"
#include "systems/ffd/deform.h"
#include "systems/picking/picking_system.h"
#include "systems/picking/selection.h"
#include "test_scenes.h"

namespace sffd::picking {
namespace {

using test::box_lattice;
using test::disc_grid;

Ray down_from(double x, double y) { return {{x, y, 2.0}, {0.0, 0.0, -1.0}}; }

// A sheet of 11 x 11 splats (spacing 0.1, radius 0.045) at z = 0.5 inside a 2x2x2 Bernstein lattice on
// the unit cube. Moving the middle layer (k = 1) by D moves every splat by B(2,1,0.5) D = D / 2
// (Σ_i B_i(s) Σ_j B_j(t) = 1): a uniform, hand-checkable deformation.
struct StretchScene {
    ecs::Registry reg;
    ecs::Entity cloud, lattice;
    StretchScene() {
        lattice = reg.create();
        reg.emplace<Lattice>(lattice, box_lattice({0, 0, 0}, {1, 1, 1}, {2, 2, 2}));
        cloud = reg.create();
        reg.emplace<SplatCloud>(cloud, disc_grid(11, 0.1, 0.045, 0.5));
        reg.emplace<Deformers>(cloud, Deformers{{lattice}});
    }
    void stretch_middle_layer(glm::dvec3 d) {
        Lattice& l = reg.patch<Lattice>(lattice);
        for (int i = 0; i <= 2; ++i)
            for (int j = 0; j <= 2; ++j) l.current[l.index(i, j, 1)] += d;
    }
};

TEST(PickingDeformed, RayHitsTheMovedSplatAfterLatticeStretch) {
    StretchScene s;
    PickingState state;
    const PickQuery q = [] {
        PickQuery p = query_from_ray(down_from(0.4, 0.4));
        p.control_points = false;
        return p;
    }();

    const PickHit before = pick(s.reg, state, q);
    ASSERT_EQ(before.kind, PickKind::surface);
    EXPECT_EQ(before.index, 4u * 11u + 4u);
    EXPECT_NEAR(before.position.z, 0.5, 1e-5);

    // Splats move by (0.1, 0, 0.15): splat (3, 4) now sits at (0.4, 0.4, 0.65).
    s.stretch_middle_layer({0.2, 0.0, 0.3});
    const auto commits = state.stats().surface_commits;
    const auto deformations = state.stats().cpu_deformations;
    const PickHit after = pick(s.reg, state, q);
    ASSERT_EQ(after.kind, PickKind::surface);
    EXPECT_EQ(after.entity, s.cloud);
    EXPECT_EQ(after.index, 4u * 11u + 3u);
    EXPECT_NEAR(after.position.x, 0.4, 1e-5);
    EXPECT_NEAR(after.position.z, 0.65, 1e-5);
    EXPECT_NEAR(after.distance, 1.35, 1e-5);
    EXPECT_EQ(state.stats().surface_commits, commits + 1);
    EXPECT_EQ(state.stats().cpu_deformations, deformations + 1);

    // Picking again without a change: no refresh, no deformation.
    EXPECT_EQ(pick(s.reg, state, q).index, 4u * 11u + 3u);
    EXPECT_EQ(state.stats().surface_commits, commits + 1);
    EXPECT_EQ(state.stats().cpu_deformations, deformations + 1);

    // A ray at the old place of splat (0, 4) now misses: the sheet moved right by 0.1.
    EXPECT_EQ(pick(s.reg, state,
                   [] {
                       PickQuery p = query_from_ray(down_from(0.0, 0.4));
                       p.control_points = false;
                       return p;
                   }())
                  .kind,
              PickKind::none);
}

TEST(PickingDeformed, UsesDeformerCpuOutputWhenValid) {
    StretchScene s;
    // The deformer's output, as ffd_system's CPU path writes it: here the lattice at rest but the output
    // deliberately shifted up by 0.25, so the test can tell which data was picked.
    const SplatCloud& c = s.reg.get<SplatCloud>(s.cloud);
    DeformedSplats out;
    out.origin = c.origin;
    out.positions = c.positions;
    for (glm::vec3& p : out.positions) p.z += 0.25f;
    out.normals = c.normals;
    out.axis_u = c.axis_u;
    out.axis_v = c.axis_v;
    out.cpu_valid = true;
    out.version = 1;
    s.reg.emplace<DeformedSplats>(s.cloud, std::move(out));
    PickingState state;
    PickQuery q = query_from_ray(down_from(0.4, 0.4));
    q.control_points = false;
    EXPECT_NEAR(pick(s.reg, state, q).position.z, 0.75, 1e-5);
    EXPECT_EQ(state.stats().cpu_deformations, 0u);

    // GPU-only output (cpu_valid false): picking deforms on the CPU itself (rest lattice: z = 0.5).
    s.reg.patch<DeformedSplats>(s.cloud).cpu_valid = false;
    EXPECT_NEAR(pick(s.reg, state, q).position.z, 0.5, 1e-5);
    EXPECT_EQ(state.stats().cpu_deformations, 1u);
}

TEST(PickingDeformed, CpuDeformationMatchesFfdReference) {
    // A non-uniform stretch: the hit position must lie on the splat that ffd's reference puts there.
    StretchScene s;
    {
        Lattice& l = s.reg.patch<Lattice>(s.lattice);
        l.current[l.index(2, 1, 1)] += glm::dvec3(0.3, 0.2, 0.4);
    }
    PickingState state;
    const glm::dvec3 rest{0.7, 0.6, 0.5};  // splat (7, 6)
    const ffd::ReferencePoint ref = ffd::reference_point(s.reg.get<Lattice>(s.lattice), rest);
    ASSERT_TRUE(ref.inside);
    PickQuery q = query_from_ray({ref.position + glm::dvec3(0, 0, 2), {0, 0, -1}});
    q.control_points = false;
    const PickHit hit = pick(s.reg, state, q);
    ASSERT_EQ(hit.kind, PickKind::surface);
    EXPECT_EQ(hit.index, 6u * 11u + 7u);
    EXPECT_NEAR(hit.position.z, ref.position.z,
                2e-4);  // the disc plane is tilted slightly by the deformation
}

TEST(PickingDeformed, SurfaceHitMapsBackToItsRestPointOnTheSplat) {
    // One large splat (radius 0.4) at (0.5, 0.5, 0.5) in a unit-cube lattice; moving the middle layer by
    // (0.2, 0, 0) translates it by (0.1, 0, 0). A ray at (0.7, 0.3) then hits the splat at its own
    // coordinates (0.6 - 0.5, 0.3 - 0.5) / 0.4 = (0.25, -0.5): the rest point is (0.6, 0.3, 0.5).
    ecs::Registry reg;
    const ecs::Entity lat = reg.create();
    reg.emplace<Lattice>(lat, box_lattice({0, 0, 0}, {1, 1, 1}, {2, 2, 2}));
    const ecs::Entity cloud = reg.create();
    reg.emplace<SplatCloud>(cloud, disc_grid(1, 1.0, 0.4, 0.5, {0.5, 0.5}));
    reg.emplace<Deformers>(cloud, Deformers{{lat}});
    {
        Lattice& l = reg.patch<Lattice>(lat);
        for (int i = 0; i <= 2; ++i)
            for (int j = 0; j <= 2; ++j) l.current[l.index(i, j, 1)].x += 0.2;
    }
    PickingState state;
    PickQuery q = query_from_ray(down_from(0.7, 0.3));
    q.control_points = false;
    const PickHit hit = pick(reg, state, q);
    ASSERT_EQ(hit.kind, PickKind::surface);
    EXPECT_NEAR(hit.splat_coords.x, 0.25, 1e-5);
    EXPECT_NEAR(hit.splat_coords.y, -0.5, 1e-5);
    const auto rest = surface_hit_in_lattice_space(reg, lat, hit);
    ASSERT_TRUE(rest);
    EXPECT_NEAR(rest->x, 0.6, 1e-5);
    EXPECT_NEAR(rest->y, 0.3, 1e-5);
    EXPECT_NEAR(rest->z, 0.5, 1e-5);
}

}  // namespace
}  // namespace sffd::picking
