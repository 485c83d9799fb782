// lattice_node_bounds against the FFD itself: points sampled in a box (corners, faces, random inside) are
// deformed by the double-precision reference and must land inside the box's bounds, under extreme lattices
// (half and full turns of twist, a stretch to ten times the lattice, random control points, oblique axes,
// a moved rest grid), both bases, boxes inside, across the boundary and outside, with and without per-point
// weights; and the bounds of a small box are far tighter than the lattice-wide ones (ffd::deformed_bounds).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "systems/ffd/deform.h"
#include "systems/ffd/lattice.h"
#include "systems/ffd/operations.h"
#include "systems/lod/lattice_bounds.h"

namespace {

using namespace sffd;
using ffd::Box;

struct Case {
    std::string name;
    Lattice lattice;
};

Lattice base(LatticeBasis basis, glm::ivec3 d, bool oblique) {
    const std::array<glm::dvec3, 3> axes =
        oblique
            ? std::array<glm::dvec3, 3>{glm::dvec3(2.0, 0.3, 0.0), glm::dvec3(-0.4, 1.5, 0.2),
                                        glm::dvec3(0.1, -0.2, 1.8)}
            : std::array<glm::dvec3, 3>{glm::dvec3(2.0, 0, 0), glm::dvec3(0, 2.0, 0), glm::dvec3(0, 0, 2.0)};
    return make_lattice(glm::dvec3(-1.0), axes, d, basis);
}

std::vector<Case> cases() {
    std::vector<Case> out;
    for (const LatticeBasis basis : {LatticeBasis::bernstein, LatticeBasis::bspline}) {
        const std::string b = basis == LatticeBasis::bernstein ? "bernstein" : "bspline";
        const glm::ivec3 d = basis == LatticeBasis::bernstein ? glm::ivec3(4, 5, 3) : glm::ivec3(8, 7, 9);
        {
            Lattice l = base(basis, d, false);
            ffd::twist_graded(l, ffd::all_control_points(l), glm::dvec3(0, 1, 0),
                              M_PI);  // half a turn per unit
            out.push_back({b + " twist", l});
        }
        {
            Lattice l = base(basis, d, true);
            ffd::twist_graded(l, ffd::all_control_points(l), glm::dvec3(0.2, 1, 0.1), 2.0 * M_PI);
            out.push_back({b + " oblique full twist", l});
        }
        {
            Lattice l = base(basis, d, false);
            ffd::stretch(l, ffd::select_range(l, glm::ivec3(d.x / 2, 0, 0), d), glm::dvec3(20.0, -5.0, 8.0));
            out.push_back({b + " big stretch", l});
        }
        {
            Lattice l = base(basis, d, true);
            std::mt19937 rng(3);
            std::uniform_real_distribution<double> u(-3.0, 3.0);
            for (auto& p : l.current) p += glm::dvec3(u(rng), u(rng), u(rng));
            out.push_back({b + " random", l});
        }
        {
            Lattice l = base(basis, d, false);  // a rest grid that is not the uniform one
            std::mt19937 rng(9);
            std::uniform_real_distribution<double> u(-0.2, 0.2);
            for (auto& p : l.rest) p += glm::dvec3(u(rng), u(rng), u(rng));
            ffd::twist_graded(l, ffd::all_control_points(l), glm::dvec3(1, 0, 0), 1.5);
            out.push_back({b + " moved rest", l});
        }
    }
    return out;
}

std::vector<Box> boxes() {
    return {
        Box{glm::dvec3(-0.2, -0.3, -0.1), glm::dvec3(0.1, 0.2, 0.3), false},       // small, inside
        Box{glm::dvec3(-1.0), glm::dvec3(1.0), false},                             // the lattice's own box
        Box{glm::dvec3(0.6, 0.5, 0.7), glm::dvec3(1.4, 1.3, 1.5), false},          // across a corner
        Box{glm::dvec3(-2.0, -0.1, -0.1), glm::dvec3(2.0, 0.1, 0.1), false},       // a rod through it
        Box{glm::dvec3(-3.0), glm::dvec3(3.0), false},                             // around it
        Box{glm::dvec3(4.0, 4.0, 4.0), glm::dvec3(5.0, 5.0, 5.0), false},          // outside
        Box{glm::dvec3(-0.95, -0.9, -0.99), glm::dvec3(-0.7, -0.6, -0.8), false},  // a corner cell
        Box{glm::dvec3(0.3, 0.3, 0.3), glm::dvec3(0.3, 0.3, 0.3), false},          // a point
    };
}

std::vector<glm::vec3> samples(const Box& b, std::mt19937& rng) {
    std::vector<glm::vec3> p;
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int c = 0; c < 8; ++c)
        p.push_back(
            glm::vec3((c & 4) ? b.hi.x : b.lo.x, (c & 2) ? b.hi.y : b.lo.y, (c & 1) ? b.hi.z : b.lo.z));
    for (int i = 0; i < 3000; ++i) {
        glm::dvec3 t(u(rng), u(rng), u(rng));
        if (i % 3 == 0) t[i % 9 / 3] = (i % 2) ? 1.0 : 0.0;  // on a face
        p.push_back(glm::vec3(b.lo + t * (b.hi - b.lo)));
    }
    return p;
}

double volume(const Box& b) {
    const glm::dvec3 e = b.hi - b.lo;
    return e.x * e.y * e.z;
}

TEST(LatticeNodeBounds, HoldEverySampledPointUnderExtremeLattices) {
    std::mt19937 rng(11);
    for (const Case& c : cases())
        for (const Box& box : boxes())
            for (const bool weighted : {false, true}) {
                const std::vector<glm::vec3> in = samples(box, rng);
                std::vector<float> w(in.size());
                std::uniform_real_distribution<float> u(0.0f, 1.0f);
                for (float& x : w) x = u(rng);
                std::vector<glm::vec3> out(in.size());
                ffd::PointsIn pin{in.data(), nullptr, nullptr, nullptr, in.size(), glm::dvec3(0.0)};
                if (weighted) pin.weights = w.data();
                ASSERT_TRUE(ffd::deform(c.lattice, pin, ffd::PointsOut{out.data()}, ffd::Backend::reference));
                const Box b = lod::lattice_node_bounds(c.lattice, box, weighted);
                ASSERT_FALSE(b.empty);
                const double tol = 1e-5 * (1.0 + glm::length(b.hi - b.lo));
                std::size_t outside = 0;
                for (const glm::vec3& p : out)
                    for (int a = 0; a < 3; ++a)
                        outside += double(p[a]) < b.lo[a] - tol || double(p[a]) > b.hi[a] + tol;
                EXPECT_EQ(outside, 0u) << c.name << (weighted ? " weighted" : "") << " box [" << box.lo.x
                                       << ", " << box.lo.y << ", " << box.lo.z << "] .. [" << box.hi.x << ", "
                                       << box.hi.y << ", " << box.hi.z << "]";
            }
}

TEST(LatticeNodeBounds, AreTightForSmallBoxes) {
    // A small box deep inside a twisted lattice: its bounds are a small share of the lattice-wide ones
    // (a stretch that moves the whole far half by one vector is the same vector for both, so only the
    // twists are held to it). Printed: how far each is from the sampled image's own box.
    std::mt19937 rng(5);
    for (const Case& c : cases()) {
        if (c.name.find("random") != std::string::npos) continue;
        const Box box{glm::dvec3(-0.1, -0.1, -0.1), glm::dvec3(0.1, 0.1, 0.1), false};
        const Box tight = lod::lattice_node_bounds(c.lattice, box);
        const Box wide = ffd::deformed_bounds(c.lattice, box);
        const std::vector<glm::vec3> in = samples(box, rng);
        std::vector<glm::vec3> out(in.size());
        ASSERT_TRUE(ffd::deform(c.lattice, ffd::PointsIn{in.data(), nullptr, nullptr, nullptr, in.size()},
                                ffd::PointsOut{out.data()}, ffd::Backend::reference));
        Box seen;
        for (const glm::vec3& p : out) seen.add(glm::dvec3(p));
        const double share = volume(tight) / volume(wide);
        const double over = std::cbrt(volume(tight) / std::max(volume(seen), 1e-12));
        std::printf("  %-28s bounds %.3g of the lattice-wide volume, %.2f x the sampled image per side\n",
                    c.name.c_str(), share, over);
        EXPECT_LE(volume(tight), volume(wide) * (1.0 + 1e-4)) << c.name;  // both padded by the slack
        if (c.name.find("twist") != std::string::npos) {
            EXPECT_LT(share, 0.1) << c.name;
        }
    }
}

TEST(LatticeNodeBounds, ChainsAndLeaveOutsideBoxesAlone) {
    Lattice a = base(LatticeBasis::bernstein, glm::ivec3(3), false);
    ffd::twist_graded(a, ffd::all_control_points(a), glm::dvec3(0, 1, 0), 1.0);
    const Box far{glm::dvec3(10.0), glm::dvec3(11.0), false};
    const Box same = lod::lattice_node_bounds(a, far);
    EXPECT_EQ(same.lo, far.lo);
    EXPECT_EQ(same.hi, far.hi);
    Lattice b = base(LatticeBasis::bspline, glm::ivec3(6), true);
    ffd::stretch(b, ffd::select_range(b, glm::ivec3(3, 0, 0), glm::ivec3(6)), glm::dvec3(0.5, 0, 0));
    const Lattice* chain[] = {&a, &b};
    const Box box{glm::dvec3(-0.5), glm::dvec3(0.5), false};
    const Box c = lod::lattice_node_bounds(chain, box);
    const Box first = lod::lattice_node_bounds(a, box);
    const Box second = lod::lattice_node_bounds(b, first);
    EXPECT_EQ(c.lo, second.lo);
    EXPECT_EQ(c.hi, second.hi);
    std::mt19937 rng(2);
    std::vector<glm::vec3> p = samples(box, rng);
    for (const Lattice* l : chain)
        ASSERT_TRUE(ffd::deform(*l, ffd::PointsIn{p.data(), nullptr, nullptr, nullptr, p.size()},
                                ffd::PointsOut{p.data()}, ffd::Backend::reference));
    for (const glm::vec3& q : p)
        for (int ax = 0; ax < 3; ++ax) {
            EXPECT_GE(double(q[ax]), c.lo[ax] - 1e-5);
            EXPECT_LE(double(q[ax]), c.hi[ax] + 1e-5);
        }
}

}  // namespace
