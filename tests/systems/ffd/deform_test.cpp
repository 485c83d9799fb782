// FFD deformation: exactness against independent references (affine maps, finite differences, PyGeM),
// agreement of the reference / fast / sparse paths, B-spline properties, boundary and robustness cases.
// The tests that run the float kernels (FfdDeformKernel) run once per SIMD target this CPU runs, the target
// pinned (names end in /avx3, /avx2, /sse4, /scalar): every target meets the same tolerances.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <string>

#include "systems/ffd/deform.h"
#include "systems/ffd/deform_kernels.h"
#include "systems/ffd/lattice.h"
#include "tests/systems/ffd/test_util.h"
#include "tests/test_util/simd_targets.h"

namespace sffd::ffd {
namespace {

using test::Cloud;

struct Output {
    std::vector<glm::vec3> p, n, u, v;
    DeformStats stats;
};

Output run(const Lattice& l, const Cloud& c, Backend b, bool full = true) {
    Output o;
    o.p.resize(c.size());
    o.n.resize(c.size());
    o.u.resize(c.size());
    o.v.resize(c.size());
    PointsIn in{c.p.data(),
                full ? c.n.data() : nullptr,
                full ? c.u.data() : nullptr,
                full ? c.v.data() : nullptr,
                c.size(),
                c.origin};
    PointsOut out{o.p.data(), o.n.data(), o.u.data(), o.v.data()};
    auto r = deform(l, in, out, b);
    EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.message());
    if (r.ok()) o.stats = *r;
    return o;
}

// Keeps the points inside the lattice's box.
Cloud inside_only(const Lattice& l, const Cloud& c) {
    Cloud r;
    r.origin = c.origin;
    for (std::size_t i = 0; i < c.size(); ++i)
        if (inside(local_coords(l, c.origin + glm::dvec3(c.p[i])))) {
            r.p.push_back(c.p[i]), r.n.push_back(c.n[i]), r.u.push_back(c.u[i]), r.v.push_back(c.v[i]);
        }
    return r;
}

const Backend kAll[] = {Backend::reference, Backend::fast, Backend::sparse};

Lattice skewed_lattice(glm::ivec3 div, LatticeBasis basis = LatticeBasis::bernstein) {
    return make_lattice({-1.1, -1.2, -1.05},
                        {glm::dvec3(2.3, 0.2, -0.1), glm::dvec3(0.1, 2.4, 0.3), glm::dvec3(-0.2, 0.1, 2.2)},
                        div, basis);
}

class FfdDeformKernel : public sffd::test::EverySimdTarget {};

TEST_P(FfdDeformKernel, IdentityLatticeIsExact) {
    const Cloud c = test::random_cloud(3000, -1.5, 1.5);
    for (LatticeBasis basis : {LatticeBasis::bernstein, LatticeBasis::bspline}) {
        const Lattice l = skewed_lattice({4, 5, 3}, basis);
        for (Backend b : kAll) {
            const Output o = run(l, c, b);
            for (std::size_t i = 0; i < c.size(); ++i) {
                ASSERT_EQ(o.p[i], c.p[i]) << backend_name(b) << " point " << i;
                ASSERT_NEAR(glm::length(o.n[i] - c.n[i]), 0.0f, 1e-7f);
                ASSERT_EQ(o.u[i], c.u[i]);
                ASSERT_EQ(o.v[i], c.v[i]);
            }
            EXPECT_GT(o.stats.inside, 500u);
            EXPECT_LT(o.stats.inside, c.size());
        }
    }
}

// Moving every control point by X -> A X + b moves every inside point by the same map (linear precision),
// normals by A^-T (times sign det A: the cofactor), axes by A.
void check_affine(const glm::dmat3& A, bool expect_inverted) {
    const glm::dvec3 b(0.3, -0.2, 0.5);
    Lattice l = skewed_lattice({3, 4, 5});
    for (std::size_t c = 0; c < l.size(); ++c) l.current[c] = A * l.rest[c] + b;
    const Cloud c = inside_only(l, test::random_cloud(2000, -1.0, 1.0, 3));
    const glm::dmat3 cof = glm::determinant(A) * glm::transpose(glm::inverse(A));
    for (Backend be : kAll) {
        const Output o = run(l, c, be);
        EXPECT_EQ(o.stats.inside, c.size());
        EXPECT_EQ(o.stats.inverted, expect_inverted ? c.size() : 0u);
        const double tol = be == Backend::reference ? 1e-6 : 2e-5;  // float storage of the outputs
        for (std::size_t i = 0; i < c.size(); ++i) {
            const glm::dvec3 want = A * glm::dvec3(c.p[i]) + b;
            ASSERT_LT(glm::length(glm::dvec3(o.p[i]) - want), tol) << backend_name(be);
            const glm::dvec3 wn = glm::normalize(cof * glm::dvec3(c.n[i]));
            ASSERT_LT(glm::length(glm::dvec3(o.n[i]) - wn), tol) << backend_name(be);
            ASSERT_LT(glm::length(glm::dvec3(o.u[i]) - A * glm::dvec3(c.u[i])), tol * 0.1);
            ASSERT_LT(glm::length(glm::dvec3(o.v[i]) - A * glm::dvec3(c.v[i])), tol * 0.1);
        }
    }
}

TEST_P(FfdDeformKernel, AffineMapOfControlPointsIsReproduced) {
    check_affine(
        glm::dmat3(glm::dvec3(1.2, 0.1, -0.3), glm::dvec3(0.2, 0.8, 0.1), glm::dvec3(-0.1, 0.4, 1.5)), false);
}

TEST_P(FfdDeformKernel, MirroredLatticeFlipsNormalsConsistentlyAndCountsInverted) {
    // A reflection (det < 0): cof(A) n = det(A) A^-T n, the orientation follows the map.
    check_affine(glm::dmat3(glm::dvec3(-1.0, 0.0, 0.0), glm::dvec3(0.0, 1.1, 0.0), glm::dvec3(0.1, 0.0, 0.9)),
                 true);
}

TEST_P(FfdDeformKernel, MirroredAxesAtRestAreNotInverted) {
    // A left-handed box (S pointing down x) at rest is the identity: nothing flips.
    const Lattice l = make_lattice(
        {1, -1, -1}, {glm::dvec3(-2, 0, 0), glm::dvec3(0, 2, 0), glm::dvec3(0, 0, 2)}, {3, 3, 3});
    const Cloud c = test::random_cloud(500, -0.9, 0.9);
    for (Backend b : kAll) {
        const Output o = run(l, c, b);
        EXPECT_EQ(o.stats.inverted, 0u);
        for (std::size_t i = 0; i < c.size(); ++i) ASSERT_LT(glm::length(o.n[i] - c.n[i]), 1e-6f);
    }
}

TEST_P(FfdDeformKernel, NormalsAgreeWithFiniteDifferences) {
    for (LatticeBasis basis : {LatticeBasis::bernstein, LatticeBasis::bspline}) {
        Lattice l = skewed_lattice({5, 4, 6}, basis);
        test::twist_about_t(l, 0.8);
        test::jitter(l, 0.05, 11, 3);
        Cloud c = test::random_cloud(300, -0.9, 0.9, 5);
        const Output o = run(l, c, Backend::fast);
        const double h = 1e-5;
        for (std::size_t i = 0; i < c.size(); ++i) {
            const glm::dvec3 x = glm::dvec3(c.p[i]), n = glm::dvec3(c.n[i]);
            const glm::dvec3 t1 = glm::normalize(glm::dvec3(c.u[i])), t2 = glm::cross(n, t1);
            auto f = [&](glm::dvec3 q) { return reference_point(l, q).position; };
            const glm::dvec3 d1 = (f(x + h * t1) - f(x - h * t1)) / (2 * h);
            const glm::dvec3 d2 = (f(x + h * t2) - f(x - h * t2)) / (2 * h);
            const glm::dvec3 want = glm::normalize(glm::cross(d1, d2));
            ASSERT_LT(glm::length(glm::dvec3(o.n[i]) - want), 1e-4) << "point " << i;
            // Axes: J u equals the directional derivative along u.
            const glm::dvec3 ju = d1 * glm::length(glm::dvec3(c.u[i]));
            ASSERT_LT(glm::length(glm::dvec3(o.u[i]) - ju), 1e-6);
        }
    }
}

TEST_P(FfdDeformKernel, PyGeMSphereCase) {
    std::vector<double> orig, mod;
    std::vector<std::size_t> shape, shape2;
    ASSERT_TRUE(test::read_npy_f64(SFFD_TEST_DATA_DIR "/pygem/meshpoints_sphere_orig.npy", orig, shape));
    ASSERT_TRUE(test::read_npy_f64(SFFD_TEST_DATA_DIR "/pygem/meshpoints_sphere_mod.npy", mod, shape2));
    ASSERT_EQ(shape.size(), 2u);
    ASSERT_EQ(shape[1], 3u);
    ASSERT_EQ(orig.size(), mod.size());
    const Lattice l = test::pygem_lattice();
    const std::size_t n = shape[0];
    // Double reference: PyGeM's expected output to 1e-10 (its test checks 6 decimals).
    double worst = 0.0;
    std::size_t moved = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const glm::dvec3 x(orig[3 * i], orig[3 * i + 1], orig[3 * i + 2]),
            want(mod[3 * i], mod[3 * i + 1], mod[3 * i + 2]);
        worst = std::max(worst, glm::length(reference_point(l, x).position - want));
        moved += want != x;
    }
    EXPECT_LT(worst, 1e-10);
    EXPECT_GT(moved, n / 10);
    // Float paths, with the cloud origin at the lattice origin: 1e-5 relative to the box size (~100).
    Cloud c;
    c.origin = l.origin;
    for (std::size_t i = 0; i < n; ++i)
        c.p.push_back(glm::vec3(glm::dvec3(orig[3 * i], orig[3 * i + 1], orig[3 * i + 2]) - c.origin));
    c.n.assign(n, glm::vec3(0, 0, 1));
    c.u.assign(n, glm::vec3(1, 0, 0));
    c.v.assign(n, glm::vec3(0, 1, 0));
    for (Backend b : {Backend::fast, Backend::sparse}) {
        const Output o = run(l, c, b);
        double w = 0.0;
        for (std::size_t i = 0; i < n; ++i)
            w = std::max(w, glm::length(c.origin + glm::dvec3(o.p[i]) -
                                        glm::dvec3(mod[3 * i], mod[3 * i + 1], mod[3 * i + 2])));
        EXPECT_LT(w, 1e-3) << backend_name(b);  // 1e-5 of the 100-unit box
    }
}

// The double-precision reference of a case with, per point, the Frobenius norms of its Jacobian and of the
// inverse. Each case is evaluated once and kept for every SIMD target's run of the test (key: the case).
struct Reference {
    Output out;
    std::vector<double> fro_j, fro_inverse;
};
const Reference& reference_of(const std::string& key, const Lattice& l, const Cloud& c) {
    static std::map<std::string, Reference> cache;
    if (auto it = cache.find(key); it != cache.end()) return it->second;
    auto fro = [](const glm::dmat3& m) {
        double s = 0;
        for (int x = 0; x < 3; ++x)
            for (int y = 0; y < 3; ++y) s += m[x][y] * m[x][y];
        return std::sqrt(s);
    };
    Reference r;
    r.out = run(l, c, Backend::reference);
    for (std::size_t i = 0; i < c.size(); ++i) {
        const glm::dmat3 J = reference_point(l, c.origin + glm::dvec3(c.p[i])).jacobian;
        r.fro_j.push_back(fro(J));
        r.fro_inverse.push_back(fro(glm::inverse(J)));
    }
    return cache.emplace(key, std::move(r)).first->second;
}

// Relative agreement: positions relative to the lattice size, normals absolute, axes relative to length.
// Normals are compared where the reference Jacobian is well conditioned (cond_F(J) <= 20): near a singular
// J the normal is ill-defined and any float evaluation drifts; `normal_tol` grows for very fine lattices,
// where float derivative sums cancel (error ~ divisions * |ΔP| * 6e-8, see README "Precision").
void expect_agree(const Reference& ref, const Output& b, double size, const char* what, const Cloud& c,
                  double normal_tol = 1e-5) {
    const Output& a = ref.out;
    ASSERT_EQ(a.p.size(), b.p.size());
    for (std::size_t i = 0; i < a.p.size(); ++i) {
        ASSERT_LT(glm::length(a.p[i] - b.p[i]), 1e-5 * size) << what << " position " << i;
        const double fro_j = ref.fro_j[i];
        if (fro_j * ref.fro_inverse[i] <= 20.0) {
            ASSERT_LT(glm::length(a.n[i] - b.n[i]), normal_tol) << what << " normal " << i;
        }
        // Axes relative to |J| |axis| (a nearly singular J shrinks an axis; its error does not shrink).
        ASSERT_LT(double(glm::length(a.u[i] - b.u[i])), normal_tol * fro_j * double(glm::length(c.u[i])))
            << what << " axis_u " << i;
        ASSERT_LT(double(glm::length(a.v[i] - b.v[i])), normal_tol * fro_j * double(glm::length(c.v[i])))
            << what << " axis_v " << i;
    }
    EXPECT_EQ(a.stats.inside, b.stats.inside) << what;
    EXPECT_EQ(a.stats.inverted, b.stats.inverted) << what;
}

TEST_P(FfdDeformKernel, FastSparseAndReferenceAgree) {
    const Cloud c = test::random_cloud(4000, -1.3, 1.3, 9);
    for (glm::ivec3 div : {glm::ivec3(1, 1, 1), glm::ivec3(3, 5, 2), glm::ivec3(10, 10, 10),
                           glm::ivec3(4, 3, 14), glm::ivec3(20, 6, 33)}) {
        for (LatticeBasis basis : {LatticeBasis::bernstein, LatticeBasis::bspline}) {
            SCOPED_TRACE(testing::Message()
                         << "divisions " << div.x << " " << div.y << " " << div.z << " basis " << int(basis));
            Lattice l = skewed_lattice(div, basis);
            test::twist_about_t(l, 0.7);
            // Jitter a fraction of the cell size: keeps J well conditioned (float normals of a nearly
            // singular J are ill-defined whatever the algorithm).
            test::jitter(l, 0.2 * 2.3 / std::max({div.x, div.y, div.z}), 5, 7);
            const Reference& ref =
                reference_of("agree " + std::to_string(div.x) + " " + std::to_string(div.y) + " " +
                                 std::to_string(div.z) + " " + std::to_string(int(basis)),
                             l, c);
            const Output fast = run(l, c, Backend::fast);
            const double ntol = std::max({div.x, div.y, div.z}) > 12 ? 1e-4 : 1e-5;
            expect_agree(ref, fast, 2.3, "fast", c, ntol);
            expect_agree(ref, run(l, c, Backend::sparse), 2.3, "sparse", c, ntol);
            // Positions-only mode gives the same positions.
            const Output po = run(l, c, Backend::fast, false);
            for (std::size_t i = 0; i < c.size(); ++i) ASSERT_EQ(po.p[i], fast.p[i]);
        }
    }
}

TEST_P(FfdDeformKernel, PaperCaseAgreesTo1e5) {
    // The benchmark case: Fibonacci sphere in an 11x11x11 lattice, global twist; every normal compared.
    const Cloud c = test::fibonacci_sphere(59650);
    for (LatticeBasis basis : {LatticeBasis::bernstein, LatticeBasis::bspline}) {
        Lattice l = make_lattice({-1.1, -1.1, -1.1},
                                 {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)},
                                 {10, 10, 10}, basis);
        test::twist_about_t(l, 0.6);
        const Reference& ref = reference_of("paper " + std::to_string(int(basis)), l, c);
        expect_agree(ref, run(l, c, Backend::fast), 2.2, "fast", c);
        expect_agree(ref, run(l, c, Backend::sparse), 2.2, "sparse", c);
    }
}

TEST_P(FfdDeformKernel, DenseBernsteinSumsOnlyTheCoordinatesThatMove) {
    // The dense kernel leaves out each coordinate of ΔP that stays within 1e-12 of the lattice's size
    // everywhere (a twist's axis: rounding). Each edit below is checked against the double-precision
    // evaluator, positions and whole Jacobians, so a coordinate summed into the wrong output shows.
    const Cloud c = test::random_cloud(3000, -1.05, 1.05, 4);
    const double size = 3 * 2.2;  // the sum of the axes' lengths
    struct Edit {
        const char* what;
        int coords;
        int coord[3];
        void (*apply)(Lattice&);
    };
    const Edit edits[] = {
        {"stretch along z",
         1,
         {2, 0, 0},
         [](Lattice& l) {
             for (std::size_t i = 0; i < l.size(); i += 3) l.current[i].z += 0.15;
         }},
        {"stretch along y",
         1,
         {1, 0, 0},
         [](Lattice& l) {
             for (std::size_t i = 1; i < l.size(); i += 2) l.current[i].y -= 0.1;
         }},
        {"x and z",
         2,
         {0, 2, 0},
         [](Lattice& l) {
             for (std::size_t i = 0; i < l.size(); i += 2) l.current[i] += glm::dvec3(0.1, 0.0, -0.12);
         }},
        {"twist about y, y off by rounding",
         2,
         {0, 2, 0},
         [](Lattice& l) {
             test::twist_about_t(l, 0.6);
             l.current[5].y += 1e-14;  // below the floor, as a double rotation's rounding is
         }},
        {"twist about y, y moved by 1e-9 of the size",
         3,
         {0, 1, 2},
         [](Lattice& l) {
             test::twist_about_t(l, 0.6);
             l.current[5].y += 1e-9 * 3 * 2.2;
         }},
        {"every coordinate", 3, {0, 1, 2}, [](Lattice& l) { test::jitter(l, 0.05, 3); }},
    };
    for (const Edit& e : edits) {
        SCOPED_TRACE(e.what);
        Lattice l = make_lattice({-1.1, -1.1, -1.1},
                                 {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)},
                                 {4, 6, 5}, LatticeBasis::bernstein);
        e.apply(l);
        const detail::Prepared P = detail::prepare(l, c.origin);
        ASSERT_EQ(P.coords, e.coords);
        for (int a = 0; a < e.coords; ++a) EXPECT_EQ(P.coord[a], e.coord[a]) << "slot " << a;
        std::vector<glm::vec3> p(c.size());
        std::vector<glm::mat3> jac(c.size());
        PointsIn in{c.p.data(), nullptr, nullptr, nullptr, c.size(), c.origin};
        PointsOut out{p.data(), nullptr, nullptr, nullptr};
        out.jacobians = jac.data();
        ASSERT_TRUE(deform(l, in, out, Backend::fast).ok());
        for (std::size_t i = 0; i < c.size(); ++i) {
            const ReferencePoint r = reference_point(l, c.origin + glm::dvec3(c.p[i]));
            ASSERT_LT(glm::length(glm::dvec3(p[i]) + c.origin - r.position), 1e-6 * size) << "point " << i;
            for (int col = 0; col < 3; ++col)
                ASSERT_LT(glm::length(glm::dvec3(jac[i][col]) - r.jacobian[col]), 1e-5)
                    << "point " << i << " column " << col;
        }
    }
}

TEST(FfdDeform, AutomaticPicksSparseForLocalEdits) {
    Lattice l = skewed_lattice({10, 10, 10});
    EXPECT_EQ(choose_backend(l), Backend::sparse);
    test::twist_about_t(l, 0.5);
    EXPECT_EQ(choose_backend(l), Backend::fast);
    l.current = l.rest;
    for (int i = 4; i < 7; ++i)
        for (int j = 4; j < 7; ++j)
            for (int k = 4; k < 7; ++k) l.current[l.index(i, j, k)] += glm::dvec3(0.1, 0, 0);
    EXPECT_EQ(moved_count(l), 27u);
    EXPECT_EQ(choose_backend(l), Backend::sparse);
}

TEST_P(FfdDeformKernel, BSplineAffinePrecisionAwayFromBoundary) {
    const glm::dmat3 A(glm::dvec3(1.1, 0.2, 0.0), glm::dvec3(-0.1, 0.9, 0.1), glm::dvec3(0.0, 0.3, 1.2));
    const glm::dvec3 b(0.1, 0.2, -0.1);
    Lattice l = make_lattice({-2, -2, -2}, {glm::dvec3(4, 0, 0), glm::dvec3(0, 4, 0), glm::dvec3(0, 0, 4)},
                             {8, 8, 8}, LatticeBasis::bspline);
    for (std::size_t c = 0; c < l.size(); ++c) l.current[c] = A * l.rest[c] + b;
    // Interior: l·s in [1, l-1] on every axis, i.e. [-1.5, 1.5] here.
    const Cloud inner = test::random_cloud(1000, -1.5, 1.5, 4);
    for (Backend be : kAll) {
        const Output o = run(l, inner, be);
        for (std::size_t i = 0; i < inner.size(); ++i) {
            ASSERT_LT(glm::length(glm::dvec3(o.p[i]) - (A * glm::dvec3(inner.p[i]) + b)), 2e-5)
                << backend_name(be);
            ASSERT_LT(glm::length(glm::dvec3(o.u[i]) - A * glm::dvec3(inner.u[i])), 2e-6);
        }
    }
    // Near the boundary the missing neighbours break affine precision (the documented convention).
    const ReferencePoint rp = reference_point(l, glm::dvec3(-1.95, 0, 0));
    EXPECT_GT(glm::length(rp.position - (A * glm::dvec3(-1.95, 0, 0) + b)), 1e-3);
}

TEST_P(FfdDeformKernel, BSplineIsLocal) {
    Lattice l = make_lattice({0, 0, 0}, {glm::dvec3(1, 0, 0), glm::dvec3(0, 1, 0), glm::dvec3(0, 0, 1)},
                             {10, 10, 10}, LatticeBasis::bspline);
    const int ci = 5, cj = 4, ck = 6;
    l.current[l.index(ci, cj, ck)] += glm::dvec3(0.05, -0.02, 0.03);
    const Cloud c = test::random_cloud(20000, 0.0, 1.0, 8);
    for (Backend be : kAll) {
        const Output o = run(l, c, be);
        std::size_t changed = 0;
        for (std::size_t i = 0; i < c.size(); ++i) {
            const glm::dvec3 x(c.p[i]);
            const bool in_support =
                std::abs(10 * x.x - ci) < 2 && std::abs(10 * x.y - cj) < 2 && std::abs(10 * x.z - ck) < 2;
            if (!in_support) {
                ASSERT_EQ(o.p[i], c.p[i]) << backend_name(be) << " point " << i;
            }
            changed += o.p[i] != c.p[i];
        }
        EXPECT_GT(changed, 100u);
    }
}

TEST_P(FfdDeformKernel, PointsOnFacesEdgesAndCornersDeform) {
    Lattice l = skewed_lattice({3, 2, 4});
    test::jitter(l, 0.1, 3);
    Cloud c;
    c.origin = glm::dvec3(0.3, 0.2, 0.1);
    for (double a : {0.0, 0.5, 1.0})
        for (double b : {0.0, 0.37, 1.0})
            for (double d : {0.0, 0.81, 1.0}) {
                if (a != 0 && a != 1 && b != 0 && b != 1 && d != 0 && d != 1) continue;  // interior: skip
                const glm::dvec3 x = l.origin + a * l.axes[0] + b * l.axes[1] + d * l.axes[2];
                c.p.push_back(glm::vec3(x - c.origin));
                c.n.push_back(glm::vec3(0, 0, 1));
                c.u.push_back(glm::vec3(0.01f, 0, 0));
                c.v.push_back(glm::vec3(0, 0.01f, 0));
            }
    for (Backend be : kAll) {
        const Output o = run(l, c, be);
        EXPECT_EQ(o.stats.inside, c.size()) << backend_name(be);
        for (std::size_t i = 0; i < c.size(); ++i) {
            const glm::dvec3 want = reference_point(l, c.origin + glm::dvec3(c.p[i])).position - c.origin;
            ASSERT_LT(glm::length(glm::dvec3(o.p[i]) - want), 1e-5) << backend_name(be) << " point " << i;
        }
    }
    // Bernstein interpolates the corners: the corner point lands on the corner control point.
    const glm::dvec3 corner = l.origin + l.axes[0] + l.axes[1] + l.axes[2];
    EXPECT_LT(glm::length(reference_point(l, corner).position - l.current[l.index(3, 2, 4)]), 1e-12);
}

TEST_P(FfdDeformKernel, FarFromOriginNoJitter) {
    // A scan at 1e6: cloud origin and lattice there, positions relative. The result equals the same
    // deformation computed at the world origin.
    const glm::dvec3 far(1.0e6, -2.0e6, 3.0e6);
    Cloud c = test::fibonacci_sphere(5000);
    Lattice near_l = make_lattice(
        {-1.1, -1.1, -1.1}, {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)}, {6, 6, 6});
    test::twist_about_t(near_l, 1.0);
    Lattice far_l = near_l;
    far_l.origin += far;
    for (auto& p : far_l.rest) p += far;
    for (auto& p : far_l.current) p += far;
    const Output a = run(near_l, c, Backend::fast);
    c.origin = far;
    for (Backend be : kAll) {
        const Output b = run(far_l, c, be);
        for (std::size_t i = 0; i < c.size(); ++i)
            ASSERT_LT(glm::length(a.p[i] - b.p[i]), 2e-6f) << backend_name(be);
        for (std::size_t i = 0; i < c.size(); ++i)
            ASSERT_LT(glm::length(a.n[i] - b.n[i]), 2e-5f) << backend_name(be);
    }
}

TEST_P(FfdDeformKernel, BoundsFromControlPointsContainEveryDeformedPoint) {
    const Cloud c = test::random_cloud(20000, -1.6, 1.6, 12);
    Box in;
    for (const auto& p : c.p) in.add(glm::dvec3(p));
    for (LatticeBasis basis : {LatticeBasis::bernstein, LatticeBasis::bspline}) {
        Lattice l = skewed_lattice({5, 5, 5}, basis);
        test::twist_about_t(l, 1.2);
        test::jitter(l, 0.4, 2, 5);
        const Output o = run(l, c, Backend::fast);
        const Box b = deformed_bounds(l, in);
        for (const auto& p : o.p) {
            ASSERT_TRUE(glm::all(glm::greaterThanEqual(glm::dvec3(p), b.lo - 1e-6)));
            ASSERT_TRUE(glm::all(glm::lessThanEqual(glm::dvec3(p), b.hi + 1e-6)));
        }
    }
}

// Bit-for-bit equality of two vectors (NaN payloads included).
bool same_bits(const glm::vec3& a, const glm::vec3& b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TEST_P(FfdDeformKernel, NonFinitePointsStayPutWhereverTheyFall) {
    // NaN fails every comparison, infinite and huge coordinates fail the inside test: such a point is
    // copied through and not counted inside, whether it sits among inside points of a whole vector block,
    // in a compacted group or in the tail. A NaN normal or axis on an inside point only spoils that output; a
    // zero normal stays zero (no division by its zero length).
    Lattice l = skewed_lattice({4, 5, 3});
    const Cloud c0 = inside_only(l, test::random_cloud(4000, -1.0, 1.0, 21));
    ASSERT_GT(c0.size(), 2100u);
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    const std::size_t bad[] = {0, 17, 40, 41, 63, 100, 1001, 1500, 2047, 2048, c0.size() - 2, c0.size() - 1};
    const glm::vec3 hostile[] = {{nan, 0, 0},      {0, nan, 0},     {0, 0, nan},        {inf, 0, 0},
                                 {0, -inf, 0},     {nan, nan, nan}, {1e30f, 0, 0},      {0, 0, -1e30f},
                                 {inf, -inf, nan}, {0, 0, inf},     {-nan, 0.1f, 0.2f}, {0.1f, inf, 0.3f}};
    const std::size_t nan_normal = 5, nan_axis = 6, zero_normal = 7;
    for (LatticeBasis basis : {LatticeBasis::bernstein, LatticeBasis::bspline}) {
        SCOPED_TRACE(basis == LatticeBasis::bspline ? "bspline" : "bernstein");
        l = skewed_lattice({4, 5, 3}, basis);
        test::twist_about_t(l, 0.7);
        test::jitter(l, 0.05, 4, 3);
        Cloud c = c0;
        for (std::size_t b = 0; b < std::size(bad); ++b) c.p[bad[b]] = hostile[b];
        c.n[nan_normal] = glm::vec3(nan, 0, 0);
        c.u[nan_axis] = glm::vec3(0, nan, 0);
        c.n[zero_normal] = glm::vec3(0.0f);
        const Output ref = run(l, c, Backend::reference);
        EXPECT_EQ(ref.stats.inside, c.size() - std::size(bad));
        for (Backend be : {Backend::fast, Backend::sparse}) {
            SCOPED_TRACE(backend_name(be));
            const Output o = run(l, c, be);
            EXPECT_EQ(o.stats.inside, ref.stats.inside);
            EXPECT_EQ(o.stats.inverted, ref.stats.inverted);
            for (std::size_t b : bad) {
                ASSERT_TRUE(same_bits(o.p[b], c.p[b])) << "point " << b;
                ASSERT_TRUE(same_bits(o.n[b], c.n[b])) << "point " << b;
                ASSERT_TRUE(same_bits(o.u[b], c.u[b])) << "point " << b;
                ASSERT_TRUE(same_bits(o.v[b], c.v[b])) << "point " << b;
            }
            for (std::size_t i = 0; i < c.size(); ++i) {
                if (std::find(std::begin(bad), std::end(bad), i) != std::end(bad)) continue;
                ASSERT_LT(glm::length(o.p[i] - ref.p[i]), 1e-5f * 2.3f) << "point " << i;
                if (i == nan_normal) {
                    EXPECT_TRUE(std::isnan(o.n[i].x) && std::isnan(o.n[i].y) && std::isnan(o.n[i].z));
                    EXPECT_TRUE(std::isnan(ref.n[i].x) && std::isnan(ref.n[i].y) && std::isnan(ref.n[i].z));
                } else if (i == zero_normal) {
                    EXPECT_EQ(o.n[i], glm::vec3(0.0f));
                    EXPECT_EQ(ref.n[i], glm::vec3(0.0f));
                } else {
                    ASSERT_LT(glm::length(o.n[i] - ref.n[i]), 1e-4f) << "point " << i;
                }
                if (i == nan_axis) {
                    EXPECT_TRUE(std::isnan(o.u[i].x) && std::isnan(o.u[i].y) && std::isnan(o.u[i].z));
                } else {
                    ASSERT_LT(glm::length(o.u[i] - ref.u[i]), 1e-6f) << "point " << i;
                }
                ASSERT_LT(glm::length(o.v[i] - ref.v[i]), 1e-6f) << "point " << i;
            }
        }
    }
}

TEST_P(FfdDeformKernel, FoldedCellsAreInvertedWhereTheReferenceSaysSo) {
    // Layer i = 1 pushed 1.5 S along S, past layers 2 and 3: the map folds over a slab of the box (det J < 0
    // there, ∂X'/∂s reversed) and the normals flip with the cell. Each point's Jacobian (and so the sign of
    // its determinant), normal and the inverted count follow the reference; a float det within 1e-3 of
    // zero may take either sign, and the count may differ by those points only.
    const Cloud c = inside_only(skewed_lattice({4, 3, 5}), test::random_cloud(3000, -1.0, 1.0, 31));
    for (LatticeBasis basis : {LatticeBasis::bernstein, LatticeBasis::bspline}) {
        SCOPED_TRACE(basis == LatticeBasis::bspline ? "bspline" : "bernstein");
        Lattice l = skewed_lattice({4, 3, 5}, basis);
        for (int j = 0; j <= 3; ++j)
            for (int k = 0; k <= 5; ++k) l.current[l.index(1, j, k)] += 1.5 * l.axes[0];
        std::vector<double> det(c.size());
        std::size_t surely = 0, maybe = 0;
        for (std::size_t i = 0; i < c.size(); ++i) {
            det[i] = glm::determinant(reference_point(l, c.origin + glm::dvec3(c.p[i])).jacobian);
            surely += det[i] < -1e-3;
            maybe += det[i] < 1e-3;
        }
        EXPECT_GT(surely, c.size() / 10);
        EXPECT_LT(maybe, c.size() - c.size() / 10);
        const Output ref = run(l, c, Backend::reference);
        for (Backend be : {Backend::fast, Backend::sparse}) {
            SCOPED_TRACE(backend_name(be));
            Output o;
            o.p.resize(c.size()), o.n.resize(c.size()), o.u.resize(c.size()), o.v.resize(c.size());
            std::vector<glm::mat3> jac(c.size());
            PointsIn in{c.p.data(), c.n.data(), c.u.data(), c.v.data(), c.size(), c.origin};
            PointsOut out{o.p.data(), o.n.data(), o.u.data(), o.v.data()};
            out.jacobians = jac.data();
            auto r = deform(l, in, out, be);
            ASSERT_TRUE(r.ok()) << r.message();
            EXPECT_GE(r->inverted, surely);
            EXPECT_LE(r->inverted, maybe);
            for (std::size_t i = 0; i < c.size(); ++i) {
                const ReferencePoint rp = reference_point(l, c.origin + glm::dvec3(c.p[i]));
                for (int col = 0; col < 3; ++col)
                    ASSERT_LT(glm::length(glm::dvec3(jac[i][col]) - rp.jacobian[col]), 1e-4)
                        << "point " << i << " column " << col;
                if (std::abs(det[i]) > 1e-3) {
                    ASSERT_EQ(glm::determinant(glm::dmat3(jac[i])) < 0.0, det[i] < 0.0) << "point " << i;
                    // The normal's orientation follows the cofactor: the reference's, away from det ≈ 0.
                    ASSERT_GT(glm::dot(o.n[i], ref.n[i]), 0.99f) << "point " << i << " det " << det[i];
                }
                ASSERT_LT(glm::length(o.p[i] - ref.p[i]), 1e-5f * 2.3f) << "point " << i;
            }
        }
    }
}

TEST(FfdDeform, GpuControlPreparationEqualsTheFullOneInWhatTheGpuReads) {
    // The GPU path prepares only ΔP, M⁻¹, the origin offset, the cull box, whether anything moved and
    // which coordinates move, in one pass of its own; the shaders must see exactly what the full
    // preparation gives the CPU kernels.
    const glm::dvec3 origin(0.3, -0.2, 1e3);
    for (LatticeBasis basis : {LatticeBasis::bernstein, LatticeBasis::bspline})
        for (int shape = 0; shape < 7; ++shape) {
            Lattice l = skewed_lattice({4, 5, 3}, basis);
            if (shape == 1) l.current[l.index(2, 3, 1)] += glm::dvec3(0.1, -0.2, 0.05);  // one point
            if (shape == 2) test::jitter(l, 0.3, 4, 7);                                  // scattered
            if (shape == 3) test::twist_about_t(l, 0.8);                                 // every point
            if (shape == 4) l.rest[0].y = 0.0, l.current[0].y = -0.0;  // ΔP.y = -0.0: not a move
            if (shape == 5)  // z only, in two points: one moving coordinate
                l.current[l.index(1, 1, 1)].z += 0.2, l.current[l.index(3, 2, 0)].z -= 0.1;
            if (shape == 6)  // x and y, y in a point of its own: two
                l.current[l.index(0, 4, 2)].x += 0.1, l.current[l.index(2, 0, 3)].y += 1e-3;
            const detail::Prepared full = detail::prepare(l, origin);
            const detail::Prepared gpu = detail::prepare(l, origin, detail::PrepareFor::gpu_controls);
            const std::string what = std::string(basis == LatticeBasis::bspline ? "bspline" : "bernstein") +
                                     " shape " + std::to_string(shape);
            EXPECT_EQ(gpu.any_moved, shape != 0 && shape != 4) << what;
            EXPECT_EQ(full.any_moved, gpu.any_moved) << what;
            EXPECT_EQ(gpu.coords, shape == 5 ? 1 : shape == 6 ? 2 : shape == 0 || shape == 4 ? 1 : 3) << what;
            EXPECT_EQ(full.coords, gpu.coords) << what;
            for (int a = 0; a < 3; ++a) EXPECT_EQ(full.coord[a], gpu.coord[a]) << what << " slot " << a;
            ASSERT_EQ(full.dp4.size(), gpu.dp4.size()) << what;
            ASSERT_EQ(full.grid.size(), gpu.grid.size()) << what;
            EXPECT_EQ(basis == LatticeBasis::bspline ? gpu.grid.empty() : gpu.dp4.empty(), false) << what;
            // Bit for bit, signed zeros included (one of the two arrays is empty: no memcmp of null).
            const auto same_bits = [](const std::vector<float>& a, const std::vector<float>& b) {
                return a.size() == b.size() &&
                       (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0);
            };
            EXPECT_TRUE(same_bits(full.dp4, gpu.dp4)) << what;
            EXPECT_TRUE(same_bits(full.grid, gpu.grid)) << what;
            EXPECT_EQ(std::memcmp(full.minv, gpu.minv, sizeof full.minv), 0) << what;
            EXPECT_EQ(std::memcmp(full.stu0, gpu.stu0, sizeof full.stu0), 0) << what;
            for (int a = 0; a < 3; ++a) {
                EXPECT_EQ(full.cull_lo[a], gpu.cull_lo[a]) << what << " axis " << a;
                EXPECT_EQ(full.cull_hi[a], gpu.cull_hi[a]) << what << " axis " << a;
            }
        }
}

TEST(FfdDeform, RestIsUniformOnlyWithinItsTolerance) {
    Lattice l = skewed_lattice({3, 4, 5});
    EXPECT_TRUE(rest_is_uniform(l));
    const double scale = glm::length(l.axes[0]) + glm::length(l.axes[1]) + glm::length(l.axes[2]);
    for (std::size_t c : {std::size_t(0), l.index(2, 1, 3), l.size() - 1}) {
        Lattice near = l, off = l;
        near.rest[c].z += 0.5e-12 * scale;  // inside the 1e-12 relative tolerance
        off.rest[c].z += 2e-12 * scale;
        EXPECT_TRUE(rest_is_uniform(near)) << c;
        EXPECT_FALSE(rest_is_uniform(off)) << c;
    }
    Lattice fewer = l;
    fewer.rest.pop_back();
    EXPECT_FALSE(rest_is_uniform(fewer));
}

TEST(FfdDeform, HugeButFiniteControlPointsAreValidAndEachNonFiniteOneIsNamed) {
    // Validation sums each point's coordinates to test them all at once: a sum that overflows to
    // infinity must not turn finite points into an error.
    Lattice big = skewed_lattice({2, 2, 2});
    big.current[4] = glm::dvec3(1.5e308, 1.5e308, 1.5e308);
    EXPECT_TRUE(validate(big).ok()) << validate(big).message();
    for (std::size_t c : {std::size_t(0), std::size_t(13), std::size_t(26)}) {
        Lattice rest = skewed_lattice({2, 2, 2}), current = rest;
        rest.rest[c].x = -INFINITY;
        current.current[c].z = std::nan("");
        EXPECT_EQ(validate(rest).message(),
                  "lattice: rest control point " + std::to_string(c) + " is not finite");
        EXPECT_EQ(validate(current).message(),
                  "lattice: control point " + std::to_string(c) + " is not finite");
    }
}

TEST(FfdDeform, DegenerateLatticesAreRefused) {
    const Cloud c = test::random_cloud(10, -1, 1);
    auto message = [&](const Lattice& l) {
        std::vector<glm::vec3> out(c.size());
        auto r =
            deform(l, PointsIn{c.p.data(), nullptr, nullptr, nullptr, c.size(), {}}, PointsOut{out.data()});
        return r.ok() ? std::string("ok") : r.message();
    };
    Lattice flat =
        make_lattice({0, 0, 0}, {glm::dvec3(1, 0, 0), glm::dvec3(0, 1, 0), glm::dvec3(1, 1, 0)}, {2, 2, 2});
    EXPECT_NE(message(flat).find("zero-volume"), std::string::npos) << message(flat);
    Lattice nan = skewed_lattice({2, 2, 2});
    nan.current[5].y = std::nan("");
    EXPECT_NE(message(nan).find("control point 5 is not finite"), std::string::npos) << message(nan);
    Lattice count = skewed_lattice({2, 2, 2});
    count.current.pop_back();
    EXPECT_NE(message(count).find("expected 27 control points, got 26"), std::string::npos) << message(count);
    Lattice zero_div = skewed_lattice({2, 2, 2});
    zero_div.divisions.y = 0;
    EXPECT_NE(message(zero_div).find("divisions"), std::string::npos);
    Lattice inf_axis = skewed_lattice({2, 2, 2});
    inf_axis.axes[2].x = INFINITY;
    EXPECT_NE(message(inf_axis).find("axis U is not finite"), std::string::npos) << message(inf_axis);
}

SFFD_INSTANTIATE_EVERY_SIMD_TARGET(FfdDeformKernel);

}  // namespace
}  // namespace sffd::ffd
