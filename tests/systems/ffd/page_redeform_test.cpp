// Page-bounded re-deformation of surface splats (systems/ffd/deform_staleness.h): after random edits of
// control points (B-spline and Bernstein lattices, chained) and of ranges of points, the output that
// ffd_system updates page by page equals, byte for byte, a deformation of the same inputs from scratch; the
// pages it redoes are the ones the edits reach, counted.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <random>

#include "runtime/scene/point_pages.h"
#include "systems/ffd/components.h"
#include "systems/ffd/deform.h"
#include "systems/ffd/ffd_system.h"
#include "systems/ffd/lattice.h"
#include "tests/systems/ffd/test_util.h"

namespace sffd::ffd {
namespace {

SplatCloud sphere_cloud(std::size_t n) {
    const test::Cloud c = test::fibonacci_sphere(n);
    SplatCloud s;
    s.positions = c.p, s.normals = c.n, s.axis_u = c.u, s.axis_v = c.v;
    return s;
}

Lattice box_lattice(glm::dvec3 lo, double size, int div, LatticeBasis basis) {
    return make_lattice(lo, {glm::dvec3(size, 0, 0), glm::dvec3(0, size, 0), glm::dvec3(0, 0, size)},
                        glm::ivec3(div), basis);
}

struct Rig {
    ecs::Registry reg;
    ecs::Entity cloud;
    std::vector<ecs::Entity> lattices;
    Rig(const SplatCloud& c, const std::vector<Lattice>& ls) {
        reg.set_resource<FfdSettings>().force_cpu = true;
        cloud = reg.create();
        reg.emplace<SplatCloud>(cloud, c);
        for (const Lattice& l : ls) {
            lattices.push_back(reg.create());
            reg.emplace<Lattice>(lattices.back(), l);
        }
        reg.emplace<Deformers>(cloud, Deformers{lattices});
    }
    const DeformedSplats& out() const { return reg.get<DeformedSplats>(cloud); }
    const FfdStats& stats() const { return reg.resource<FfdStats>(); }
};

template <class T>
bool same_bytes(const std::vector<T>& a, const std::vector<T>& b) {
    // memcmp of two empty vectors would pass null pointers, which it must not be given.
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

// The output from scratch: a fresh registry with the same cloud and lattices, one run.
void expect_equals_from_scratch(const Rig& inc, const std::string& what) {
    std::vector<Lattice> ls;
    for (ecs::Entity e : inc.lattices) ls.push_back(inc.reg.get<Lattice>(e));
    Rig fresh(inc.reg.get<SplatCloud>(inc.cloud), ls);
    ffd_system(fresh.reg, {});
    const DeformedSplats &a = inc.out(), &b = fresh.out();
    ASSERT_TRUE(a.cpu_valid) << what;
    EXPECT_TRUE(same_bytes(a.positions, b.positions)) << what;
    EXPECT_TRUE(same_bytes(a.normals, b.normals)) << what;
    EXPECT_TRUE(same_bytes(a.axis_u, b.axis_u)) << what;
    EXPECT_TRUE(same_bytes(a.axis_v, b.axis_v)) << what;
    EXPECT_EQ(a.inverted, b.inverted) << what;
    EXPECT_EQ(fresh.stats().last_pages.redone, page_count(a.positions.size())) << what;
}

TEST(PageRedeform, RandomControlPointEditsEqualADeformationFromScratchByteForByte) {
    // 5 pages (300,000 points: the last one partial), in latitude bands (the Fibonacci order); a global
    // B-spline lattice and a local Bernstein one inside it, chained.
    const SplatCloud cloud = sphere_cloud(300000);
    Rig rig(cloud, {box_lattice(glm::dvec3(-1.1), 2.2, 10, LatticeBasis::bspline),
                    box_lattice(glm::dvec3(0.1, 0.3, -0.6), 1.0, 3, LatticeBasis::bernstein)});
    ffd_system(rig.reg, {});
    ASSERT_EQ(rig.stats().last_pages.total, 5u);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> step(-0.06, 0.06);
    std::size_t partial_runs = 0;
    for (int edit = 0; edit < 16; ++edit) {
        const std::size_t d = edit % 4 == 3 ? 1 : 0;  // mostly the B-spline lattice
        Lattice& l = rig.reg.patch<Lattice>(rig.lattices[d]);
        std::uniform_int_distribution<std::size_t> pick(0, l.size() - 1);
        const int moves = edit % 5 == 4 ? 3 : 1;
        for (int m = 0; m < moves; ++m) l.current[pick(rng)] += glm::dvec3(step(rng), step(rng), step(rng));
        ffd_system(rig.reg, {});
        const auto last = rig.stats().last_pages;
        partial_runs += last.redone < last.total;
        expect_equals_from_scratch(rig, "edit " + std::to_string(edit));
    }
    // B-spline edits near the poles reach only some of the bands.
    EXPECT_GT(partial_runs, 0u);
}

TEST(PageRedeform, PagesAreTheKernelsBlocksSoAPageAloneGivesTheWholeRunsBits) {
    // The system deforms page by page; ffd::deform over the whole arrays at once must agree bit for bit.
    const SplatCloud cloud = sphere_cloud(200000);
    Lattice l = box_lattice(glm::dvec3(-1.1), 2.2, 6, LatticeBasis::bspline);
    l.current[l.index(3, 2, 3)] += glm::dvec3(0.1, -0.2, 0.05);
    Rig rig(cloud, {l});
    ffd_system(rig.reg, {});
    std::vector<glm::vec3> p(cloud.size()), n(cloud.size()), u(cloud.size()), v(cloud.size());
    ASSERT_TRUE(deform(l,
                       {cloud.positions.data(), cloud.normals.data(), cloud.axis_u.data(),
                        cloud.axis_v.data(), cloud.size(), cloud.origin},
                       {p.data(), n.data(), u.data(), v.data()}));
    EXPECT_TRUE(same_bytes(rig.out().positions, p));
    EXPECT_TRUE(same_bytes(rig.out().normals, n));
    EXPECT_TRUE(same_bytes(rig.out().axis_u, u));
    EXPECT_TRUE(same_bytes(rig.out().axis_v, v));
}

TEST(PageRedeform, AnEditOfARangeOfPointsRedoesOnlyItsPages) {
    const SplatCloud cloud = sphere_cloud(300000);
    Lattice l = box_lattice(glm::dvec3(-1.1), 2.2, 4, LatticeBasis::bernstein);
    l.current[l.index(2, 2, 2)] += glm::dvec3(0.2, 0.0, 0.0);
    Rig rig(cloud, {l});
    ffd_system(rig.reg, {});
    // Points 70,000..70,099 (page 1) and 250,000 (page 3) move.
    SplatCloud& c = rig.reg.get<SplatCloud>(rig.cloud);
    for (std::size_t i = 70000; i < 70100; ++i) c.positions[i] *= 0.9f;
    mark_points_changed(rig.reg, rig.cloud, PointColumn::position, 70000, 100);
    c.normals[250000] = -c.normals[250000];
    mark_points_changed(rig.reg, rig.cloud, PointColumn::frame, 250000, 1);
    ffd_system(rig.reg, {});
    EXPECT_EQ(rig.stats().last_pages.redone, 2u);
    expect_equals_from_scratch(rig, "range edit");
    // A colour edit changes nothing the deformation reads.
    rig.reg.get<SplatCloud>(rig.cloud).colors.assign(cloud.size(), 0xff00ff00u);
    mark_points_changed(rig.reg, rig.cloud, PointColumn::colour, 0, cloud.size());
    ffd_system(rig.reg, {});
    EXPECT_EQ(rig.stats().last_pages.redone, 0u);
    // An edit that is not marked re-deforms everything.
    rig.reg.patch<SplatCloud>(rig.cloud).positions[5] *= 1.01f;
    ffd_system(rig.reg, {});
    EXPECT_EQ(rig.stats().last_pages.redone, 5u);
    expect_equals_from_scratch(rig, "unmarked edit");
}

// The pages holding a point inside the world box [lo, hi] (the support's extent), from the positions.
std::size_t pages_with_point_in(const SplatCloud& c, const glm::dvec3& lo, const glm::dvec3& hi) {
    std::size_t count = 0;
    for (std::size_t p = 0; p < page_count(c.size()); ++p) {
        const PageRange r = page_range(p, c.size());
        bool hit = false;
        for (std::size_t i = r.first; i < r.first + r.count && !hit; ++i) {
            const glm::dvec3 x(c.positions[i]);
            hit = glm::all(glm::greaterThanEqual(x, lo)) && glm::all(glm::lessThanEqual(x, hi));
        }
        count += hit;
    }
    return count;
}

TEST(PageRedeform, OneControlPointDragOnAMillionPointsRedoesOnlyThePagesOfItsSupport) {
    // 1M points (16 pages, latitude bands), a 21^3 B-spline lattice around them; control point (10, 2, 10)
    // influences l·s, l·u in (8, 12) and l·t in (0, 4): x, z in [-0.22, 0.22] and y in [-1.1, -0.66], under
    // a quarter of the lattice on every axis. The page boxes of the 4 lowest bands meet that box; only the
    // pages with a point in it are redone.
    const SplatCloud cloud = sphere_cloud(1000000);
    Rig rig(cloud, {box_lattice(glm::dvec3(-1.1), 2.2, 20, LatticeBasis::bspline)});
    ffd_system(rig.reg, {});
    ASSERT_EQ(rig.stats().last_pages.redone, 16u);
    // The rule widens the page box and the support by 1e-4 each in parameter units (2.2 world units).
    const double margin = 2e-4 * 2.2;
    const std::size_t expected = pages_with_point_in(cloud, glm::dvec3(-0.22, -1.1, -0.22) - margin,
                                                     glm::dvec3(0.22, -1.1 + 4 * 0.11, 0.22) + margin);
    for (int step = 1; step <= 3; ++step) {
        Lattice& l = rig.reg.patch<Lattice>(rig.lattices[0]);
        l.current[l.index(10, 2, 10)] =
            l.rest[l.index(10, 2, 10)] + glm::dvec3(0.0, 0.03, 0.02) * double(step);
        ffd_system(rig.reg, {});
        EXPECT_EQ(rig.stats().last_pages.redone, expected) << "step " << step;
        EXPECT_LE(rig.stats().last_pages.redone * 10, rig.stats().last_pages.total * 3) << "step " << step;
    }
    EXPECT_EQ(expected, 2u);  // the last 2 bands hold the sphere's points near its bottom pole
    expect_equals_from_scratch(rig, "drag");
}

TEST(PageRedeform, PagesOutsideEveryLatticeAreDeformedOnceAndNeverAgain) {
    // A lattice over the upper half of the sphere: the lower half's pages never meet it.
    const SplatCloud cloud = sphere_cloud(400000);
    Rig rig(cloud, {box_lattice(glm::dvec3(-1.1, 0.2, -1.1), 2.2, 5, LatticeBasis::bernstein)});
    ffd_system(rig.reg, {});
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> step(-0.05, 0.05);
    const std::size_t upper =
        pages_with_point_in(cloud, glm::dvec3(-10.0, 0.2 - (2e-4 + 1e-6) * 2.2, -10.0), glm::dvec3(10.0));
    ASSERT_LT(upper, page_count(cloud.size()));
    for (int edit = 0; edit < 4; ++edit) {
        Lattice& l = rig.reg.patch<Lattice>(rig.lattices[0]);
        l.current[l.index(2, 2 + edit % 2, 3)] += glm::dvec3(step(rng), step(rng), step(rng));
        ffd_system(rig.reg, {});
        EXPECT_EQ(rig.stats().last_pages.redone, upper) << "edit " << edit;
    }
    expect_equals_from_scratch(rig, "upper lattice");
}

}  // namespace
}  // namespace sffd::ffd
