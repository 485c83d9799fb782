// Per-point weights (PointWeights, runtime/scene/point_columns.h) through the CPU surface path: every
// backend and SIMD target against the test's own double-precision Bernstein reference (weights_reference.h:
// X + w (X' − X), J_w = I + w (J − I), normals by cof(J_w), axes J_w a), weight 0 is the rest point bit for
// bit, weight 1 and a cloud without weights are the unweighted code's bytes, chained lattices weight each
// step, and ffd_system reads the component (and re-deforms when it changes).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "runtime/ecs/registry.h"
#include "runtime/scene/components.h"
#include "runtime/scene/point_columns.h"
#include "systems/ffd/components.h"
#include "systems/ffd/deform.h"
#include "systems/ffd/deform_cloud.h"
#include "systems/ffd/ffd_system.h"
#include "systems/ffd/lattice.h"
#include "tests/systems/ffd/test_util.h"
#include "tests/systems/ffd/weights_reference.h"
#include "tests/test_util/simd_targets.h"

namespace sffd::ffd {
namespace {

using test::Cloud;

// Points well inside the lattice (local coordinates in [0.03, 0.97]), with random normals and axes.
Cloud inside_points(const Lattice& l, std::size_t n, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u01(0.03, 0.97), dir(-1.0, 1.0);
    Cloud c;
    c.origin = glm::dvec3(0.25, -0.5, 0.125);  // positions relative to a cloud origin, as scans are
    for (std::size_t i = 0; i < n; ++i) {
        const glm::dvec3 world =
            l.origin + u01(rng) * l.axes[0] + u01(rng) * l.axes[1] + u01(rng) * l.axes[2];
        glm::dvec3 nn;
        do nn = glm::dvec3(dir(rng), dir(rng), dir(rng));
        while (glm::length(nn) < 0.2);
        nn = glm::normalize(nn);
        const glm::dvec3 t =
            glm::normalize(glm::cross(nn, std::abs(nn.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0)));
        c.p.push_back(glm::vec3(world - c.origin));
        c.n.push_back(glm::vec3(nn));
        c.u.push_back(glm::vec3(t * 0.02));
        c.v.push_back(glm::vec3(glm::cross(nn, t) * 0.03));
    }
    return c;
}

// Weights 0, 0.5, 1 and random ones in [0, 1], in an order that mixes whole SIMD blocks of one weight with
// blocks where a weight-0 point sits among others (the kernels' per-point path).
std::vector<float> mixed_weights(std::size_t n, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::vector<float> w(n);
    for (std::size_t i = 0; i < n; ++i) {
        const std::size_t block = i / 32;
        switch (block % 5) {
            case 0: w[i] = 0.0f; break;
            case 1: w[i] = 0.5f; break;
            case 2: w[i] = 1.0f; break;
            case 3: w[i] = (i % 7 == 3) ? 0.0f : u(rng); break;
            default: w[i] = u(rng); break;
        }
    }
    return w;
}

struct Out {
    std::vector<glm::vec3> p, n, u, v;
    std::vector<glm::mat3> j;
};

Out run(const Lattice& l, const Cloud& c, Backend b, const float* weights) {
    Out o;
    o.p.resize(c.size()), o.n.resize(c.size()), o.u.resize(c.size()), o.v.resize(c.size()),
        o.j.resize(c.size());
    PointsIn in{c.p.data(), c.n.data(), c.u.data(), c.v.data(), c.size(), c.origin};
    in.weights = weights;
    PointsOut out{o.p.data(), o.n.data(), o.u.data(), o.v.data()};
    out.jacobians = o.j.data();
    auto r = deform(l, in, out, b);
    EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.message());
    return o;
}

template <class T>
bool same_bytes(const std::vector<T>& a, const std::vector<T>& b) {
    // memcmp of two empty vectors would pass null pointers, which it must not be given.
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

class PointWeightsKernel : public sffd::test::EverySimdTarget {};

// Weights 0, 0.5, 1 (and random ones) give the rest point, half and the whole displacement, with J_w
// blended alike, on every backend: positions, normals, axes and Jacobians against the double reference.
TEST_P(PointWeightsKernel, ZeroHalfAndOneGiveRestHalfAndFullDisplacement) {
    for (glm::ivec3 div : {glm::ivec3(4, 3, 5), glm::ivec3(2, 2, 2), glm::ivec3(7, 6, 8)}) {
        const Lattice l = test::weighted_test_lattice(div);
        const Cloud c = inside_points(l, 1500, 11u + unsigned(div.x));
        const std::vector<float> w = mixed_weights(c.size(), 5u);
        for (Backend b : {Backend::fast, Backend::sparse, Backend::reference}) {
            SCOPED_TRACE(std::string(backend_name(b)) + " divisions " + std::to_string(div.x));
            const Out o = run(l, c, b, w.data());
            double worst_p = 0, worst_n = 0, worst_a = 0, worst_j = 0, max_disp = 0;
            for (std::size_t i = 0; i < c.size(); ++i) {
                const glm::dvec3 x = c.origin + glm::dvec3(c.p[i]);
                const test::WeightedRef r = test::weighted_bernstein(l, x, double(w[i]));
                ASSERT_TRUE(r.inside);
                if (w[i] == 0.0f) {  // the rest point, bit for bit
                    ASSERT_EQ(std::memcmp(&o.p[i], &c.p[i], sizeof(glm::vec3)), 0) << i;
                    ASSERT_EQ(std::memcmp(&o.n[i], &c.n[i], sizeof(glm::vec3)), 0) << i;
                    ASSERT_EQ(std::memcmp(&o.u[i], &c.u[i], sizeof(glm::vec3)), 0) << i;
                    ASSERT_EQ(std::memcmp(&o.v[i], &c.v[i], sizeof(glm::vec3)), 0) << i;
                    ASSERT_EQ(o.j[i], glm::mat3(1.0f)) << i;
                    continue;
                }
                max_disp = std::max(max_disp, glm::length(r.position - x));
                worst_p = std::max(worst_p, glm::length(c.origin + glm::dvec3(o.p[i]) - r.position));
                worst_n =
                    std::max(worst_n, glm::length(glm::dvec3(o.n[i]) -
                                                  test::ref_cofactor_normal(r.jacobian, glm::dvec3(c.n[i]))));
                const glm::dvec3 au = r.jacobian * glm::dvec3(c.u[i]), av = r.jacobian * glm::dvec3(c.v[i]);
                worst_a = std::max({worst_a, glm::length(glm::dvec3(o.u[i]) - au) / glm::length(au),
                                    glm::length(glm::dvec3(o.v[i]) - av) / glm::length(av)});
                for (int col = 0; col < 3; ++col)
                    worst_j = std::max(worst_j, glm::length(glm::dvec3(o.j[i][col]) - r.jacobian[col]));
            }
            EXPECT_GT(max_disp, 0.1);  // the lattice moves the points: the test can tell w from 1
            EXPECT_LT(worst_p, 2e-6 * 4.0);
            EXPECT_LT(worst_n, 2e-5);
            EXPECT_LT(worst_a, 2e-5);
            EXPECT_LT(worst_j, 2e-5);
        }
    }
}

// The half weight is half the float kernel's own displacement (to float rounding): the weight scales the
// displacement itself, not a later blend of two results.
TEST_P(PointWeightsKernel, HalfWeightIsHalfTheDisplacement) {
    const Lattice l = test::weighted_test_lattice({5, 4, 6});
    const Cloud c = inside_points(l, 999, 3u);
    const std::vector<float> half(c.size(), 0.5f);
    for (Backend b : {Backend::fast, Backend::sparse}) {
        const Out full = run(l, c, b, nullptr), h = run(l, c, b, half.data());
        for (std::size_t i = 0; i < c.size(); ++i) {
            const glm::dvec3 d_full = glm::dvec3(full.p[i]) - glm::dvec3(c.p[i]);
            const glm::dvec3 d_half = glm::dvec3(h.p[i]) - glm::dvec3(c.p[i]);
            ASSERT_LT(glm::length(d_half - 0.5 * d_full), 1e-6) << i;
            const glm::dmat3 jf(full.j[i]), jh(h.j[i]);
            for (int col = 0; col < 3; ++col)
                ASSERT_LT(glm::length((jh - glm::dmat3(1.0))[col] - 0.5 * (jf - glm::dmat3(1.0))[col]), 1e-5)
                    << i;
        }
    }
}

// Weight 1 everywhere is the unweighted code's output byte for byte (both bases, every backend), so a
// cloud whose weights are all 1 draws exactly what it drew without them.
TEST_P(PointWeightsKernel, WeightOneIsTheUnweightedOutputBitForBit) {
    for (LatticeBasis basis : {LatticeBasis::bernstein, LatticeBasis::bspline}) {
        Lattice l = test::weighted_test_lattice({6, 5, 7});
        l.basis = basis;
        const Cloud c = inside_points(l, 2051, 9u);
        const std::vector<float> ones(c.size(), 1.0f);
        for (Backend b : {Backend::fast, Backend::sparse, Backend::reference}) {
            if (basis == LatticeBasis::bspline && b == Backend::sparse) continue;  // Bernstein only
            const Out a = run(l, c, b, nullptr), o = run(l, c, b, ones.data());
            EXPECT_TRUE(same_bytes(a.p, o.p) && same_bytes(a.n, o.n) && same_bytes(a.u, o.u) &&
                        same_bytes(a.v, o.v) && same_bytes(a.j, o.j))
                << backend_name(b);
        }
    }
}

// The B-spline kernel weights alike: against the library's own double reference (no independent B-spline
// evaluator here), weight 0 the rest point bit for bit.
TEST_P(PointWeightsKernel, BSplineWeightsMatchTheDoubleReference) {
    Lattice l = test::weighted_test_lattice({6, 6, 6});
    l.basis = LatticeBasis::bspline;
    const Cloud c = inside_points(l, 1777, 21u);
    const std::vector<float> w = mixed_weights(c.size(), 8u);
    const Out f = run(l, c, Backend::fast, w.data()), r = run(l, c, Backend::reference, w.data());
    double worst_p = 0, worst_n = 0;
    for (std::size_t i = 0; i < c.size(); ++i) {
        const ReferencePoint full = reference_point(l, c.origin + glm::dvec3(c.p[i]));
        const glm::dvec3 expect =
            glm::dvec3(c.p[i]) + double(w[i]) * (full.position - (c.origin + glm::dvec3(c.p[i])));
        worst_p = std::max(worst_p, glm::length(glm::dvec3(f.p[i]) - expect));
        worst_n = std::max(worst_n, glm::length(glm::dvec3(f.n[i]) - glm::dvec3(r.n[i])));
        if (w[i] == 0.0f) ASSERT_EQ(std::memcmp(&f.p[i], &c.p[i], sizeof(glm::vec3)), 0);
    }
    EXPECT_LT(worst_p, 1e-5);
    EXPECT_LT(worst_n, 2e-5);
}

SFFD_INSTANTIATE_EVERY_SIMD_TARGET(PointWeightsKernel);

SplatCloud splat_cloud(const Cloud& c) {
    SplatCloud s;
    s.origin = c.origin;
    s.positions = c.p, s.normals = c.n, s.axis_u = c.u, s.axis_v = c.v;
    return s;
}

// Several lattices: the weight applies to each lattice's step (the second reads the first's weighted
// output), against the reference applied twice.
TEST(PointWeights, ChainedLatticesWeightEachStep) {
    const Lattice a = test::weighted_test_lattice({4, 4, 4});
    Lattice b = test::weighted_test_lattice({3, 5, 2}, -1.6, 3.2);
    for (glm::dvec3& p : b.current) p += glm::dvec3(0.05 * p.y, -0.1 * p.z * p.z, 0.08 * p.x);
    const Cloud c = inside_points(a, 1300, 4u);
    const SplatCloud cloud = splat_cloud(c);
    PointWeights weights{mixed_weights(c.size(), 2u)};
    const Lattice* chain[] = {&a, &b};
    DeformedSplats out;
    deform_cloud(cloud, chain, out, "test", &weights);
    double worst = 0, worst_n = 0;
    for (std::size_t i = 0; i < c.size(); ++i) {
        const double w = weights.values[i];
        const test::WeightedRef r1 = test::weighted_bernstein(a, c.origin + glm::dvec3(c.p[i]), w);
        const test::WeightedRef r2 = test::weighted_bernstein(b, r1.position, w);
        ASSERT_TRUE(r2.inside);
        worst = std::max(worst, glm::length(c.origin + glm::dvec3(out.positions[i]) - r2.position));
        const glm::dvec3 n = test::ref_cofactor_normal(r2.jacobian * r1.jacobian, glm::dvec3(c.n[i]));
        worst_n = std::max(worst_n, glm::length(glm::dvec3(out.normals[i]) - n));
    }
    EXPECT_LT(worst, 1e-5);
    EXPECT_LT(worst_n, 5e-5);
}

// A cloud without weights (no component, or an empty one) is deformed by the unweighted code: the same
// bytes as ffd::deform() with no weights, lattice by lattice.
TEST(PointWeights, ACloudWithoutWeightsIsTheUnweightedCodePath) {
    const Lattice a = test::weighted_test_lattice({5, 5, 5});
    const Cloud c = inside_points(a, 4099, 6u);
    const SplatCloud cloud = splat_cloud(c);
    const Lattice* chain[] = {&a};
    DeformedSplats none, empty;
    deform_cloud(cloud, chain, none, "test");
    const PointWeights no_values;
    deform_cloud(cloud, chain, empty, "test", &no_values);
    const Out direct = run(a, c, Backend::automatic, nullptr);
    for (const DeformedSplats* o : {&none, &empty})
        EXPECT_TRUE(same_bytes(o->positions, direct.p) && same_bytes(o->normals, direct.n) &&
                    same_bytes(o->axis_u, direct.u) && same_bytes(o->axis_v, direct.v));
}

// The system reads the entity's PointWeights: its CPU output is deform_cloud() with them; replacing the
// weights re-deforms; removing them gives the unweighted output back, bit for bit.
TEST(PointWeights, FfdSystemReadsTheWeightsAndRedeformsWhenTheyChange) {
    ecs::Registry reg;
    reg.set_resource<FfdSettings>().force_cpu = true;
    const Lattice lat = test::weighted_test_lattice({4, 3, 4});
    const Cloud c = inside_points(lat, 70000, 12u);  // over one page (65,536 points)
    const ecs::Entity le = reg.create();
    reg.emplace<Lattice>(le, lat);
    const ecs::Entity e = reg.create();
    reg.emplace<SplatCloud>(e, splat_cloud(c));
    reg.emplace<Deformers>(e, Deformers{{le}});
    reg.emplace<PointWeights>(e, PointWeights{mixed_weights(c.size(), 1u)});
    const FrameContext frame{};
    ffd_system(reg, frame);
    const Lattice* chain[] = {&lat};
    auto expect_output = [&](const PointWeights* w, const char* what) {
        DeformedSplats want;
        deform_cloud(reg.get<SplatCloud>(e), chain, want, "test", w);
        const DeformedSplats& got = reg.get<DeformedSplats>(e);
        ASSERT_TRUE(got.cpu_valid) << what;
        EXPECT_TRUE(same_bytes(got.positions, want.positions) && same_bytes(got.normals, want.normals) &&
                    same_bytes(got.axis_u, want.axis_u) && same_bytes(got.axis_v, want.axis_v))
            << what;
    };
    expect_output(&reg.get<PointWeights>(e), "first run");
    const std::uint64_t v0 = reg.get<DeformedSplats>(e).version;
    ffd_system(reg, frame);
    EXPECT_EQ(reg.get<DeformedSplats>(e).version, v0);  // nothing changed: nothing runs
    reg.patch<PointWeights>(e).values.assign(c.size(), 0.25f);
    ffd_system(reg, frame);
    EXPECT_GT(reg.get<DeformedSplats>(e).version, v0);
    expect_output(&reg.get<PointWeights>(e), "weights replaced");
    reg.remove<PointWeights>(e);
    ffd_system(reg, frame);
    expect_output(nullptr, "weights removed");
}

}  // namespace
}  // namespace sffd::ffd
