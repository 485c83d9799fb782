// Lattice operations: stretch/twist against closed forms, fit (incl. flat and collinear input), apply as
// rest, exact resolution raising (Bernstein elevation, B-spline doubling), least-squares lowering.
#include <gtest/gtest.h>

#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "systems/ffd/deform.h"
#include "systems/ffd/lattice.h"
#include "systems/ffd/operations.h"
#include "tests/systems/ffd/test_util.h"

namespace sffd::ffd {
namespace {

Lattice box(glm::ivec3 div, LatticeBasis basis = LatticeBasis::bernstein) {
    return make_lattice({-1, -1, -1}, {glm::dvec3(2, 0, 0), glm::dvec3(0, 2, 0), glm::dvec3(0, 0, 2)}, div,
                        basis);
}

TEST(FfdOperations, StretchMovesOnlyTheSelection) {
    Lattice l = box({4, 4, 4});
    const Selection sel = select_range(l, {1, 1, 1}, {3, 3, 3});
    EXPECT_EQ(sel.size(), 27u);
    stretch(l, sel, {0.1, 0.2, 0.3});
    EXPECT_EQ(moved_count(l), 27u);
    for (std::size_t c : sel) EXPECT_EQ(l.current[c], l.rest[c] + glm::dvec3(0.1, 0.2, 0.3));
    reset(l);
    EXPECT_EQ(moved_count(l), 0u);
}

TEST(FfdOperations, TwistRotatesAboutPivotDefaultCentroid) {
    Lattice l = box({2, 2, 2});
    const Selection all = all_control_points(l);
    twist(l, all, {0, 0, 1}, M_PI / 2);  // pivot = centroid = (0,0,0)
    for (std::size_t c = 0; c < l.size(); ++c) {
        const glm::dvec3 r = l.rest[c];
        EXPECT_NEAR(glm::length(l.current[c] - glm::dvec3(-r.y, r.x, r.z)), 0.0, 1e-12);
    }
    // Explicit pivot.
    reset(l);
    twist(l, {l.index(2, 0, 0)}, {0, 0, 1}, M_PI, glm::dvec3(0, -1, -1));
    EXPECT_NEAR(glm::length(l.current[l.index(2, 0, 0)] - glm::dvec3(-1, -1, -1)), 0.0, 1e-12);
    // A rigid rotation of the whole lattice rotates the points (and normals) rigidly.
    reset(l);
    twist(l, all, {1, 1, 0}, 0.7, glm::dvec3(0.1, 0, 0));
    const glm::dvec3 x(0.3, -0.2, 0.5);
    const ReferencePoint rp = reference_point(l, x);
    EXPECT_NEAR(glm::length(rp.position - glm::dvec3(0.1, 0, 0)), glm::length(x - glm::dvec3(0.1, 0, 0)),
                1e-12);
    EXPECT_NEAR(glm::determinant(rp.jacobian), 1.0, 1e-12);
}

TEST(FfdOperations, FitLatticeWithPaddingAndDegenerateInput) {
    const test::Cloud c = test::fibonacci_sphere(1000, 2.0);
    auto l = fit_lattice(c.p, {10, 0, 0}, {3, 3, 3}, LatticeBasis::bernstein, 0.1);
    ASSERT_TRUE(l.ok()) << l.message();
    for (const auto& p : c.p) {
        const glm::dvec3 stu = local_coords(*l, glm::dvec3(10, 0, 0) + glm::dvec3(p));
        EXPECT_TRUE(glm::all(glm::greaterThan(stu, glm::dvec3(0.05))) &&
                    glm::all(glm::lessThan(stu, glm::dvec3(0.95))));
    }
    // Flat (z = 0), collinear, and a single point: valid lattices containing the points.
    const std::vector<glm::vec3> flat = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
    const std::vector<glm::vec3> line = {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}};
    const std::vector<glm::vec3> one = {{5, 5, 5}};
    for (const auto* pts : {&flat, &line, &one}) {
        auto f = fit_lattice(*pts, {}, {2, 2, 2}, LatticeBasis::bspline, 0.0);
        ASSERT_TRUE(f.ok()) << f.message();
        EXPECT_TRUE(validate(*f).ok());
        for (const auto& p : *pts) EXPECT_TRUE(inside(local_coords(*f, glm::dvec3(p))));
    }
    EXPECT_FALSE(fit_lattice({}, {}, {2, 2, 2}).ok());
    EXPECT_NE(fit_lattice({{0, NAN, 0}}, {}, {2, 2, 2}).message().find("not finite"), std::string::npos);
}

// Points on a regular 9x7x5 grid of a box with half-extents (3, 2, 1), rotated by R and moved to c:
// the grid is symmetric in the box frame, so its covariance is diagonal there and PCA recovers R's
// columns exactly (to rounding); the oriented fit is then that box grown by the padding.
TEST(FfdOperations, OrientedFitFindsTheRotatedBox) {
    const glm::dmat3 R = glm::dmat3(glm::rotate(glm::dmat4(1.0), 0.5, glm::normalize(glm::dvec3(1, 2, 3))));
    const glm::dvec3 half(3, 2, 1), c(100, -50, 7);
    std::vector<glm::vec3> pts;
    for (int i = 0; i <= 8; ++i)
        for (int j = 0; j <= 6; ++j)
            for (int k = 0; k <= 4; ++k) {
                const glm::dvec3 q(-half.x + 2 * half.x * i / 8, -half.y + 2 * half.y * j / 6,
                                   -half.z + 2 * half.z * k / 4);
                pts.push_back(glm::vec3(R * q));  // relative to the origin c
            }
    FitOptions o;
    o.shape = FitShape::oriented;
    o.padding = 0.1;
    o.divisions = {4, 3, 2};
    auto l = fit_lattice(pts, c, o);
    ASSERT_TRUE(l.ok()) << l.message();
    // 0.5 rad about (1,2,3): each box axis stays closest to its own world axis, signs kept positive.
    for (int a = 0; a < 3; ++a) {
        const glm::dvec3 e = glm::normalize(l->axes[std::size_t(a)]);
        EXPECT_NEAR(std::abs(glm::dot(e, R[a])), 1.0, 1e-6) << "axis " << a;
        EXPECT_GT(e[a], 0.0);
        EXPECT_NEAR(glm::length(l->axes[std::size_t(a)]), 2 * half[a] + 2 * 0.1 * 6.0, 1e-5) << "axis " << a;
    }
    const glm::dvec3 centre = l->origin + 0.5 * (l->axes[0] + l->axes[1] + l->axes[2]);
    EXPECT_LT(glm::length(centre - c), 1e-5);
    EXPECT_EQ(l->divisions, glm::ivec3(4, 3, 2));
    EXPECT_EQ(l->rest, l->current);
    for (const auto& p : pts) EXPECT_TRUE(inside(local_coords(*l, c + glm::dvec3(p))));
    // Its volume is the box's (6+1.2)(4+1.2)(2+1.2); the axis-aligned fit of the same points is larger.
    auto aabb = fit_lattice(pts, c, FitOptions{{4, 3, 2}, LatticeBasis::bernstein, 0.1, FitShape::box});
    ASSERT_TRUE(aabb.ok());
    const auto volume = [](const Lattice& x) {
        return std::abs(glm::determinant(glm::dmat3(x.axes[0], x.axes[1], x.axes[2])));
    };
    EXPECT_NEAR(volume(*l), 7.2 * 5.2 * 3.2, 1e-4);
    EXPECT_GT(volume(*aabb), 1.5 * volume(*l));
    // An axis-aligned object: the oriented fit is the box fit.
    std::vector<glm::vec3> aligned;
    for (int i = 0; i <= 4; ++i)
        for (int j = 0; j <= 2; ++j)
            for (int k = 0; k <= 1; ++k)
                aligned.push_back(glm::vec3(float(i), 0.5f * float(j), 2.0f * float(k)));
    auto ob =
        fit_lattice(aligned, {}, FitOptions{{2, 2, 2}, LatticeBasis::bernstein, 0.0, FitShape::oriented});
    auto bb = fit_lattice(aligned, {}, FitOptions{{2, 2, 2}, LatticeBasis::bernstein, 0.0, FitShape::box});
    ASSERT_TRUE(ob.ok() && bb.ok());
    for (int a = 0; a < 3; ++a)
        EXPECT_LT(glm::length(ob->axes[std::size_t(a)] - bb->axes[std::size_t(a)]), 1e-9);
    EXPECT_LT(glm::length(ob->origin - bb->origin), 1e-9);
    // A sphere has no principal axes: the oriented fit keeps the axis-aligned box (not 5% smaller).
    const test::Cloud sphere = test::fibonacci_sphere(2000, 1.0);
    auto os =
        fit_lattice(sphere.p, {}, FitOptions{{2, 2, 2}, LatticeBasis::bernstein, 0.05, FitShape::oriented});
    auto bs = fit_lattice(sphere.p, {}, FitOptions{{2, 2, 2}, LatticeBasis::bernstein, 0.05, FitShape::box});
    ASSERT_TRUE(os.ok() && bs.ok());
    EXPECT_EQ(os->axes, bs->axes);
    EXPECT_EQ(os->origin, bs->origin);
}

TEST(FfdOperations, FitSpecParsesAndRoundTrips) {
    auto d = parse_fit_spec("fit");
    ASSERT_TRUE(d.ok());
    EXPECT_EQ(d->divisions, glm::ivec3(10));
    EXPECT_EQ(d->shape, FitShape::box);
    EXPECT_EQ(d->basis, LatticeBasis::bernstein);
    EXPECT_EQ(d->padding, 0.05);
    auto f = parse_fit_spec("fit:4,5,6,pad=0.2,obb,bspline");
    ASSERT_TRUE(f.ok()) << f.message();
    EXPECT_EQ(f->divisions, glm::ivec3(4, 5, 6));
    EXPECT_EQ(f->padding, 0.2);
    EXPECT_EQ(f->shape, FitShape::oriented);
    EXPECT_EQ(f->basis, LatticeBasis::bspline);
    auto g = parse_fit_spec(fit_spec_string(*f));
    ASSERT_TRUE(g.ok());
    EXPECT_EQ(g->divisions, f->divisions);
    EXPECT_EQ(g->padding, f->padding);
    EXPECT_EQ(g->shape, f->shape);
    EXPECT_EQ(g->basis, f->basis);
    EXPECT_EQ(parse_fit_spec("fit:3")->divisions, glm::ivec3(3));
    EXPECT_EQ(parse_fit_spec("fit:pad=0")->padding, 0.0);
    const std::pair<const char*, const char*> bad[] = {{"fit:", "empty item"},
                                                       {"fit:0", "1..64"},
                                                       {"fit:65", "1..64"},
                                                       {"fit:4,x", "unknown item 'x'"},
                                                       {"fit:4,5", "one division count"},
                                                       {"fit:1,2,3,4", "at most three"},
                                                       {"fit:pad=-1", "pad must be"},
                                                       {"fit:pad=abc", "pad must be"},
                                                       {"fit:obb,4", "divisions come first"},
                                                       {"fits", "a fit spec reads"},
                                                       {"fit:4,,4,4", "empty item"}};
    for (const auto& [spec, want] : bad) {
        auto r = parse_fit_spec(spec);
        ASSERT_FALSE(r.ok()) << spec;
        EXPECT_NE(r.message().find(want), std::string::npos) << spec << " -> " << r.message();
        EXPECT_EQ(r.message().rfind(spec, 0), 0u) << r.message();  // the message starts with the spec
    }
}

TEST(FfdOperations, ApplyAsRestBakesTheShape) {
    Lattice l = box({3, 3, 3});
    test::twist_about_t(l, 0.5);
    test::Cloud c = test::random_cloud(500, -0.9, 0.9);
    std::vector<glm::vec3> before(c.size());
    const PointsIn in{c.p.data(), nullptr, nullptr, nullptr, c.size(), {}};
    ASSERT_TRUE(deform(l, in, PointsOut{before.data()}).ok());
    BakeTarget bake{&c.p, &c.n, &c.u, &c.v, {}};
    ASSERT_TRUE(apply_as_rest(l, &bake).ok());
    EXPECT_EQ(l.rest, l.current);
    for (std::size_t i = 0; i < c.size(); ++i) EXPECT_LT(glm::length(c.p[i] - before[i]), 1e-5f);
    // The deformation is now the identity; further edits act on the baked shape.
    std::vector<glm::vec3> after(c.size());
    ASSERT_TRUE(
        deform(l, PointsIn{c.p.data(), nullptr, nullptr, nullptr, c.size(), {}}, PointsOut{after.data()})
            .ok());
    EXPECT_EQ(after, c.p);
}

double max_deviation(const Lattice& a, const Lattice& b, const test::Cloud& c) {
    double worst = 0.0;
    for (const auto& p : c.p) {
        const glm::dvec3 x(p);
        worst = std::max(worst, glm::length(reference_point(a, x).position - reference_point(b, x).position));
    }
    return worst;
}

TEST(FfdOperations, BernsteinDegreeElevationIsExact) {
    Lattice l = box({3, 2, 4});
    test::twist_about_t(l, 0.8);
    test::jitter(l, 0.1, 4, 2);
    auto hi = raise_resolution(l, {7, 5, 4});
    ASSERT_TRUE(hi.ok()) << hi.message();
    EXPECT_EQ(hi->size(), 8u * 6u * 5u);
    const test::Cloud c = test::random_cloud(500, -1, 1);
    EXPECT_LT(max_deviation(l, *hi, c), 1e-9);
    // Lowering back by least squares recovers the original lattice (it lies in the smaller space).
    auto lo = lower_resolution(*hi, {3, 2, 4});
    ASSERT_TRUE(lo.ok()) << lo.message();
    for (std::size_t i = 0; i < l.size(); ++i) EXPECT_LT(glm::length(lo->current[i] - l.current[i]), 1e-8);
    EXPECT_FALSE(raise_resolution(l, {2, 2, 4}).ok());
}

TEST(FfdOperations, BSplineDoublingIsExactWithRestBoundary) {
    Lattice l = box({4, 4, 4}, LatticeBasis::bspline);
    // Move interior control points only (boundary layer at rest).
    for (int i = 1; i < 4; ++i)
        for (int j = 1; j < 4; ++j)
            for (int k = 1; k < 4; ++k)
                l.current[l.index(i, j, k)] += glm::dvec3(0.05 * i, -0.03 * j, 0.02 * k * i);
    bool exact = false;
    auto hi = raise_resolution(l, {8, 4, 8}, &exact);
    ASSERT_TRUE(hi.ok()) << hi.message();
    EXPECT_TRUE(exact);
    const test::Cloud c = test::random_cloud(500, -1, 1);
    EXPECT_LT(max_deviation(l, *hi, c), 1e-9);
    auto lo = lower_resolution(*hi, {4, 4, 4});
    ASSERT_TRUE(lo.ok());
    EXPECT_LT(max_deviation(l, *lo, c), 1e-9);
    // A moved boundary point: reported as not exact (the grid has no points outside the lattice).
    l.current[l.index(0, 2, 2)] += glm::dvec3(0.1, 0, 0);
    ASSERT_TRUE(raise_resolution(l, {8, 8, 8}, &exact).ok());
    EXPECT_FALSE(exact);
    EXPECT_FALSE(raise_resolution(l, {6, 4, 4}).ok());
}

TEST(FfdOperations, LowerResolutionIsALeastSquaresApproximation) {
    Lattice l = box({10, 10, 10});
    test::twist_about_t(l, 0.6);
    auto lo = lower_resolution(l, {4, 4, 4});
    ASSERT_TRUE(lo.ok());
    const test::Cloud c = test::random_cloud(300, -1, 1);
    const double err = max_deviation(l, *lo, c);
    EXPECT_LT(err, 0.02);  // a smooth twist is captured well by degree 4
    EXPECT_GT(err, 0.0);
}

}  // namespace
}  // namespace sffd::ffd
