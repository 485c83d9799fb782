// ffd_system on the CPU path (no GL context): change detection, deformers in order, bounds, inverted count.
#include <gtest/gtest.h>

#include "runtime/core/log.h"
#include "runtime/ecs/registry.h"
#include "runtime/scene/components.h"
#include "systems/ffd/components.h"
#include "systems/ffd/deform.h"
#include "systems/ffd/ffd_system.h"
#include "systems/ffd/lattice.h"
#include "systems/ffd/operations.h"
#include "tests/systems/ffd/test_util.h"

#include <random>

namespace sffd {
namespace {

struct Scene {
    ecs::Registry reg;
    ecs::Entity cloud, global, local;
};

void make_scene(Scene& s) {
    const ffd::test::Cloud c = ffd::test::fibonacci_sphere(5000);
    s.cloud = s.reg.create();
    SplatCloud sc;
    sc.origin = glm::dvec3(100, 0, 0);
    sc.positions = c.p, sc.normals = c.n, sc.axis_u = c.u, sc.axis_v = c.v;
    s.reg.emplace<SplatCloud>(s.cloud, std::move(sc));
    s.global = s.reg.create();
    s.reg.emplace<Lattice>(
        s.global,
        ffd::make_lattice({98.9, -1.1, -1.1},
                          {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)}, {4, 4, 4}));
    s.local = s.reg.create();
    s.reg.emplace<Lattice>(
        s.local,
        ffd::make_lattice({100.2, 0.2, -0.5}, {glm::dvec3(1, 0, 0), glm::dvec3(0, 1, 0), glm::dvec3(0, 0, 1)},
                          {3, 3, 3}, LatticeBasis::bspline));
    s.reg.emplace<Deformers>(s.cloud, Deformers{{s.global, s.local}});
    s.reg.set_resource<FfdSettings>();
}

TEST(FfdSystem, RunsOnlyWhenSomethingChanged) {
    Scene s;
    make_scene(s);
    ffd_system(s.reg, {});
    const auto& stats = s.reg.resource<FfdStats>();
    EXPECT_EQ(stats.cpu_runs, 1u);
    const DeformedSplats& d = s.reg.get<DeformedSplats>(s.cloud);
    EXPECT_TRUE(d.cpu_valid);
    const std::uint64_t v = d.version;
    ffd_system(s.reg, {});
    EXPECT_EQ(stats.cpu_runs, 1u);  // nothing moved
    EXPECT_EQ(s.reg.get<DeformedSplats>(s.cloud).version, v);
    ffd::twist(s.reg.patch<Lattice>(s.local), ffd::all_control_points(s.reg.get<Lattice>(s.local)), {0, 0, 1},
               0.3);
    ffd_system(s.reg, {});
    EXPECT_EQ(stats.cpu_runs, 2u);  // the local lattice's stamp moved
    EXPECT_GT(s.reg.get<DeformedSplats>(s.cloud).version, v);
    s.reg.patch<SplatCloud>(s.cloud);
    ffd_system(s.reg, {});
    EXPECT_EQ(stats.cpu_runs, 3u);  // the rest points changed
    s.reg.patch<Deformers>(s.cloud).lattices.pop_back();
    ffd_system(s.reg, {});
    EXPECT_EQ(stats.cpu_runs, 4u);  // the deformer list changed
}

TEST(FfdSystem, DeformersApplyInOrderAndBoundsCover) {
    Scene s;
    make_scene(s);
    Lattice& g = s.reg.patch<Lattice>(s.global);
    ffd::twist_graded(g, ffd::all_control_points(g), {0, 1, 0}, 1.0, glm::dvec3(100, 0, 0));
    Lattice& l = s.reg.patch<Lattice>(s.local);
    ffd::stretch(l, ffd::select_range(l, {1, 1, 1}, {2, 2, 2}), {0.1, 0.05, 0.0});
    ffd_system(s.reg, {});
    const DeformedSplats& d = s.reg.get<DeformedSplats>(s.cloud);
    const SplatCloud& c = s.reg.get<SplatCloud>(s.cloud);
    ASSERT_EQ(d.positions.size(), c.size());
    std::size_t changed_by_local = 0;
    for (std::size_t i = 0; i < c.size(); ++i) {
        const glm::dvec3 x = c.origin + glm::dvec3(c.positions[i]);
        const ffd::ReferencePoint a = ffd::reference_point(s.reg.get<Lattice>(s.global), x);
        const ffd::ReferencePoint b = ffd::reference_point(s.reg.get<Lattice>(s.local), a.position);
        const glm::dvec3 got = d.origin + glm::dvec3(d.positions[i]);
        ASSERT_LT(glm::length(got - b.position), 1e-5) << i;
        changed_by_local += glm::length(b.position - a.position) > 1e-4;
        ASSERT_TRUE(glm::all(glm::greaterThanEqual(got, d.bounds_min)) &&
                    glm::all(glm::lessThanEqual(got, d.bounds_max)));
        // Normal through both Jacobians (cofactor = det · inverse transpose, composed).
        const glm::dmat3 J = b.jacobian * a.jacobian;
        const glm::dvec3 n =
            glm::normalize(glm::determinant(J) * glm::transpose(glm::inverse(J)) * glm::dvec3(c.normals[i]));
        ASSERT_LT(glm::length(glm::dvec3(d.normals[i]) - n), 1e-4) << i;
    }
    EXPECT_GT(changed_by_local, 50u);
    EXPECT_EQ(d.inverted, 0u);
    // A mirrored global lattice: every splat inside it is reported inverted.
    Lattice& m = s.reg.patch<Lattice>(s.global);
    for (std::size_t i = 0; i < m.size(); ++i)
        m.current[i] = glm::dvec3(200.0 - m.rest[i].x, m.rest[i].y, m.rest[i].z);
    s.reg.patch<Deformers>(s.cloud).lattices = {s.global};
    ffd_system(s.reg, {});
    EXPECT_EQ(s.reg.get<DeformedSplats>(s.cloud).inverted, c.size());
}

TEST(FfdSystem, BadLatticeIsSkippedWithAWarning) {
    Scene s;
    make_scene(s);
    s.reg.patch<Lattice>(s.local).current[3].x = std::nan("");
    log::ScopedLogCapture capture;
    ffd_system(s.reg, {});
    EXPECT_TRUE(capture.contains("control point 3 is not finite"));
    EXPECT_TRUE(s.reg.get<DeformedSplats>(s.cloud).cpu_valid);
}

// The bounds come from control points and a cached rest box only (the GPU path never sees the deformed
// splats on the CPU); against the CPU deformation they must contain every point, for any lattice: both
// bases, random divisions and displacements, a non-uniform rest (after apply_as_rest), lattices that
// cover only part of the cloud, and two deformers in a chain.
TEST(FfdSystem, BoundsContainEveryDeformedPointForRandomLattices) {
    std::mt19937 rng(12);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int trial = 0; trial < 40; ++trial) {
        ecs::Registry reg;
        const ffd::test::Cloud c = ffd::test::random_cloud(3000, -1.0, 1.0, 100 + unsigned(trial));
        const ecs::Entity cloud = reg.create();
        SplatCloud sc;
        sc.origin = glm::dvec3(50.0 * trial, -3.0, 7.0);
        sc.positions = c.p, sc.normals = c.n, sc.axis_u = c.u, sc.axis_v = c.v;
        reg.emplace<SplatCloud>(cloud, std::move(sc));
        std::vector<ecs::Entity> chain;
        const int deformers = 1 + trial % 2;
        for (int d = 0; d < deformers; ++d) {
            // A box around part of (or all of) the cloud, sheared a little.
            const glm::dvec3 lo = glm::dvec3(50.0 * trial, -3.0, 7.0) +
                                  glm::dvec3(-1.2 + 0.8 * unit(rng), -1.2 + 0.8 * unit(rng), -1.2);
            const double size = 1.2 + 1.4 * unit(rng);
            const std::array<glm::dvec3, 3> axes{glm::dvec3(size, 0.1 * unit(rng), 0),
                                                 glm::dvec3(0, size, 0.1 * unit(rng)),
                                                 glm::dvec3(0.1 * unit(rng), 0, size)};
            const glm::ivec3 div(1 + int(unit(rng) * 6), 1 + int(unit(rng) * 6), 1 + int(unit(rng) * 6));
            Lattice l = ffd::make_lattice(
                lo, axes, div, (trial + d) % 3 == 0 ? LatticeBasis::bspline : LatticeBasis::bernstein);
            auto jitter = [&](double amount) {
                for (glm::dvec3& p : l.current)
                    p += amount * glm::dvec3(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5);
            };
            jitter(0.6);
            if (trial % 4 == 1) {
                ASSERT_TRUE(ffd::apply_as_rest(l).ok());  // non-uniform rest, then displaced again
                jitter(0.4);
            }
            if (trial % 5 == 2)
                ffd::twist_graded(l, ffd::all_control_points(l), {0, 1, 0}, 2.0, lo + 0.5 * size);
            const ecs::Entity le = reg.create();
            reg.emplace<Lattice>(le, std::move(l));
            chain.push_back(le);
        }
        reg.emplace<Deformers>(cloud, Deformers{chain});
        reg.set_resource<FfdSettings>().force_cpu = true;
        ffd_system(reg, {});
        const DeformedSplats& d = reg.get<DeformedSplats>(cloud);
        ASSERT_TRUE(d.cpu_valid);
        ASSERT_EQ(d.positions.size(), c.size());
        // Float outputs may round past an exact bound by an ulp of the coordinates.
        const double tol = 1e-5 * (1.0 + glm::length(d.bounds_max - d.bounds_min));
        std::size_t moved = 0;
        for (std::size_t i = 0; i < c.size(); ++i) {
            const glm::dvec3 x = d.origin + glm::dvec3(d.positions[i]);
            moved += glm::length(glm::dvec3(d.positions[i] - c.p[i])) > 1e-3;
            ASSERT_TRUE(glm::all(glm::greaterThanEqual(x, d.bounds_min - tol)) &&
                        glm::all(glm::lessThanEqual(x, d.bounds_max + tol)))
                << "trial " << trial << " point " << i;
        }
        EXPECT_GT(moved, 100u) << "trial " << trial;  // the lattices really deform the cloud
    }
}

// The rest box is one pass over the splats per cloud change, not per lattice edit.
TEST(FfdSystem, RestBoxIsComputedOncePerCloudChange) {
    Scene s;
    make_scene(s);
    ffd_system(s.reg, {});
    const auto& stats = s.reg.resource<FfdStats>();
    EXPECT_EQ(stats.cpu_splat_passes, 2u);  // rest box + the CPU deformation
    ffd::stretch(s.reg.patch<Lattice>(s.local), {0}, {0.01, 0, 0});
    ffd_system(s.reg, {});
    EXPECT_EQ(stats.cpu_splat_passes, 3u);  // the CPU deformation only
    const glm::dvec3 lo = s.reg.get<DeformedSplats>(s.cloud).bounds_min;
    for (glm::vec3& p : s.reg.patch<SplatCloud>(s.cloud).positions) p.x -= 5.0f;  // the cloud moves out
    ffd_system(s.reg, {});
    EXPECT_EQ(stats.cpu_splat_passes, 5u);  // the box follows the new cloud
    EXPECT_LT(s.reg.get<DeformedSplats>(s.cloud).bounds_min.x, lo.x - 4.0);
}

}  // namespace
}  // namespace sffd
