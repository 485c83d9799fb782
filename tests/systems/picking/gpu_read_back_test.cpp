// Picking a deformed cloud whose deformed data lives only on the GPU (the deformation's compute pass,
// residency state deformed_gpu): picking reads the buffer back once per deformed_version and never
// deforms on the CPU itself; the hits equal those of the CPU route (tests/systems/picking/deformed_test.cpp,
// gaussian_pick_test.cpp use the same scenes).
#include <gtest/gtest.h>

#include <cmath>

#include "runtime/ecs/registry.h"
#include "runtime/gfx/residency.h"
#include "runtime/gfx/splat_store.h"
#include "systems/ffd/components.h"
#include "systems/ffd/ffd_system.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/gaussian_system.h"
#include "systems/gaussian/gpu_store.h"
#include "systems/picking/picking_system.h"
#include "systems/residency/residency_system.h"
#include "test_scenes.h"
#include "tests/test_util/headless_gl.h"

namespace sffd::picking {
namespace {

class PickingGpuReadBack : public sffd::test::HeadlessGlTest {
protected:
    void TearDown() override {
        ffd_release_gpu(reg);
        gaussian_release_gpu(reg);
        reg.erase_resource<gfx::GpuSplatStore>();
        reg.erase_resource<gaussian::GpuGaussianStore>();
    }
    // One frame's residency and deformation phases, the deformation on its compute pass.
    void deform() {
        residency_system(reg, FrameContext{});
        ffd_system(reg, FrameContext{});
        gaussian_deform_system(reg, FrameContext{});
    }
    ecs::Registry reg;
};

PickQuery surface_query(const Ray& ray) {
    PickQuery q = query_from_ray(ray);
    q.control_points = false;
    return q;
}

// The sheet of deformed_test.cpp: 11 x 11 splats at z = 0.5 in a 2x2x2 Bernstein lattice on the unit
// cube; moving the middle layer by D moves every splat by D / 2.
TEST_F(PickingGpuReadBack, SurfaceSplatsAreReadBackOncePerVersion) {
    reg.set_resource<FfdSettings>().force_gpu = true;  // llvmpipe would choose the CPU path
    const ecs::Entity lattice = reg.create();
    reg.emplace<Lattice>(lattice, test::box_lattice({0, 0, 0}, {1, 1, 1}, {2, 2, 2}));
    const ecs::Entity cloud = reg.create();
    reg.emplace<SplatCloud>(cloud, test::disc_grid(11, 0.1, 0.045, 0.5));
    reg.emplace<Deformers>(cloud, Deformers{{lattice}});
    auto stretch_middle_layer = [&](glm::dvec3 d) {
        Lattice& l = reg.patch<Lattice>(lattice);
        for (int i = 0; i <= 2; ++i)
            for (int j = 0; j <= 2; ++j) l.current[l.index(i, j, 1)] += d;
    };
    stretch_middle_layer({0.2, 0.0, 0.3});  // splats move by (0.1, 0, 0.15)
    deform();
    ASSERT_TRUE(ffd::output_on_gpu(reg, cloud));
    ASSERT_FALSE(reg.get<DeformedSplats>(cloud).cpu_valid);
    ASSERT_EQ(reg.resource<gfx::GpuSplatStore>().clouds.at(cloud).state, gfx::Residency::deformed_gpu);

    PickingState state;
    const PickHit hit = pick(reg, state, surface_query({{0.4, 0.4, 2.0}, {0, 0, -1}}));
    ASSERT_EQ(hit.kind, PickKind::surface);
    EXPECT_EQ(hit.entity, cloud);
    EXPECT_EQ(hit.index, 4u * 11u + 3u);
    EXPECT_NEAR(hit.position.z, 0.65, 1e-5);
    EXPECT_NEAR(hit.distance, 1.35, 1e-5);
    EXPECT_EQ(state.stats().gpu_read_backs, 1u);
    EXPECT_EQ(state.stats().cpu_deformations, 0u);

    // Nothing moved: no second read-back.
    EXPECT_EQ(pick(reg, state, surface_query({{0.4, 0.4, 2.0}, {0, 0, -1}})).index, 4u * 11u + 3u);
    EXPECT_EQ(state.stats().gpu_read_backs, 1u);

    // A new deformation (a new deformed_version): read back again, the hit follows.
    stretch_middle_layer({0.2, 0.0, 0.0});  // another 0.1 along x
    deform();
    const PickHit moved = pick(reg, state, surface_query({{0.5, 0.4, 2.0}, {0, 0, -1}}));
    ASSERT_EQ(moved.kind, PickKind::surface);
    EXPECT_EQ(moved.index, 4u * 11u + 3u);
    EXPECT_NEAR(moved.position.x, 0.5, 1e-5);
    EXPECT_EQ(state.stats().gpu_read_backs, 2u);
    EXPECT_EQ(state.stats().cpu_deformations, 0u);
}

// One Gaussian (opacity 1: picked at k1 standard deviations) at the centre of the unit cube, the lattice
// doubling x: the deformed ellipsoid is centred at x = 1 with sigma_x = 0.1.
TEST_F(PickingGpuReadBack, GaussiansAreReadBackOncePerVersion) {
    reg.set_resource<FfdSettings>().force_gpu = true;
    const ecs::Entity lattice = reg.create();
    reg.emplace<Lattice>(lattice, test::box_lattice({0, 0, 0}, {1, 1, 1}, {2, 2, 2}));
    GaussianCloud g;
    g.positions = {{0.5f, 0.5f, 0.5f}};
    g.scales = {{0.05f, 0.05f, 0.05f}};
    g.rotations = {glm::quat(1, 0, 0, 0)};
    g.opacities = {1.0f};
    g.sh = {0.1f, 0.1f, 0.1f};
    const ecs::Entity e = reg.create();
    reg.emplace<GaussianCloud>(e, g);
    reg.emplace<Deformers>(e, Deformers{{lattice}});
    for (glm::dvec3& p : reg.patch<Lattice>(lattice).current) p.x *= 2.0;
    deform();
    ASSERT_TRUE(gaussian::output_on_gpu(reg, e));
    ASSERT_EQ(reg.resource<gaussian::GpuGaussianStore>().clouds.at(e).state, gfx::Residency::deformed_gpu);

    const double k1 = std::sqrt(2.0 * std::log(255.0));
    PickingState state;
    const PickQuery along_x = surface_query({{5.0, 0.5, 0.5}, {-1, 0, 0}});
    const PickHit hit = pick(reg, state, along_x);
    ASSERT_EQ(hit.kind, PickKind::gaussian);
    EXPECT_NEAR(hit.distance, 4.0 - 0.1 * k1, 1e-5);
    EXPECT_EQ(state.stats().gaussian_gpu_read_backs, 1u);
    EXPECT_EQ(state.stats().gaussian_cpu_deformations, 0u);
    pick(reg, state, along_x);
    EXPECT_EQ(state.stats().gaussian_gpu_read_backs, 1u);

    for (glm::dvec3& p : reg.patch<Lattice>(lattice).current) p.x *= 1.5;  // x' = 3x
    deform();
    EXPECT_NEAR(pick(reg, state, along_x).distance, 3.5 - 0.15 * k1, 1e-5);
    EXPECT_EQ(state.stats().gaussian_gpu_read_backs, 2u);
    EXPECT_EQ(state.stats().gaussian_cpu_deformations, 0u);
}

}  // namespace
}  // namespace sffd::picking
