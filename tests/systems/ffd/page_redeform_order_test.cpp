// Page-bounded re-deformation on a cloud in Morton order (runtime/scene/point_order.h, what `splatffd
// convert --order morton` writes): a one-control-point drag of a B-spline lattice over the 1M sphere
// redoes exactly the pages whose rest box meets the point's support, counted here from the positions (the
// band order too); the output equals a deformation from scratch. On this hollow sphere Morton pages are
// halves of octants, whose boxes reach the centre, so they redo MORE pages than the latitude bands: the
// printed line records what finer boxes would give.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>

#include "runtime/scene/point_order.h"
#include "runtime/scene/point_pages.h"
#include "systems/ffd/components.h"
#include "systems/ffd/ffd_system.h"
#include "systems/ffd/lattice.h"
#include "tests/systems/ffd/test_util.h"

namespace sffd::ffd {
namespace {

SplatCloud sphere_cloud(std::size_t n, bool morton) {
    const test::Cloud c = test::fibonacci_sphere(n);
    SplatCloud s;
    s.positions = c.p, s.normals = c.n, s.axis_u = c.u, s.axis_v = c.v;
    if (morton) {
        EXPECT_TRUE(permute(s, morton_order(s.positions)));
    }
    return s;
}

// The lattice of the drags: [-1.1, 1.1]^3, `div` cells a side, cubic B-spline.
Lattice cube_lattice(int div) {
    return make_lattice(glm::dvec3(-1.1),
                        {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)},
                        glm::ivec3(div), LatticeBasis::bspline);
}

// Pages whose box of positions meets the support of control point `ijk` of cube_lattice(div): l·t in
// [i-2, i+2] on each axis, clipped to the box, widened as the rule widens it (1e-4 parameter units on the
// support and on the page box: 2 x 2.2e-4 world units). With `block` < kPagePoints: the pages with a
// block of that many points whose box meets it (what a rule with finer boxes would redo; 1: the pages
// holding a point inside the support).
std::size_t pages_meeting_support(const SplatCloud& c, int div, glm::ivec3 ijk,
                                  std::size_t block = kPagePoints) {
    const double cell = 2.2 / div, margin = 2e-4 * 2.2;
    glm::dvec3 lo, hi;
    for (int a = 0; a < 3; ++a) {
        lo[a] = -1.1 + std::max(0, ijk[a] - 2) * cell - margin;
        hi[a] = -1.1 + std::min(div, ijk[a] + 2) * cell + margin;
    }
    std::size_t count = 0;
    for (std::size_t p = 0; p < page_count(c.size()); ++p) {
        const PageRange r = page_range(p, c.size());
        bool meets = false;
        for (std::size_t b = r.first; b < r.first + r.count && !meets; b += block) {
            glm::dvec3 plo(1e300), phi(-1e300);
            for (std::size_t i = b; i < std::min(b + block, r.first + r.count); ++i)
                plo = glm::min(plo, glm::dvec3(c.positions[i])),
                phi = glm::max(phi, glm::dvec3(c.positions[i]));
            meets = true;
            for (int a = 0; a < 3; ++a) meets = meets && plo[a] <= hi[a] && phi[a] >= lo[a];
        }
        count += meets;
    }
    return count;
}

struct Drag {
    std::size_t redone = 0, total = 0;
    bool same_as_scratch = false;
};

// Three drag steps of control point `ijk`; the pages each step redid (all equal, else 0) and whether the
// output then equals one deformation of the dragged lattice from scratch, byte for byte.
Drag drag(const SplatCloud& cloud, int div, glm::ivec3 ijk) {
    ecs::Registry reg;
    reg.set_resource<FfdSettings>().force_cpu = true;
    const ecs::Entity c = reg.create(), le = reg.create();
    reg.emplace<SplatCloud>(c, cloud);
    reg.emplace<Lattice>(le, cube_lattice(div));
    reg.emplace<Deformers>(c, Deformers{{le}});
    ffd_system(reg, {});
    Drag d;
    for (int step = 1; step <= 3; ++step) {
        Lattice& l = reg.patch<Lattice>(le);
        const std::size_t cp = l.index(ijk.x, ijk.y, ijk.z);
        l.current[cp] = l.rest[cp] + glm::dvec3(0.01, 0.03, 0.02) * double(step);
        ffd_system(reg, {});
        const std::size_t r = reg.resource<FfdStats>().last_pages.redone;
        d.redone = step == 1 || r == d.redone ? r : 0;
        d.total = reg.resource<FfdStats>().last_pages.total;
    }
    ecs::Registry fresh;
    fresh.set_resource<FfdSettings>().force_cpu = true;
    const ecs::Entity fc = fresh.create(), fl = fresh.create();
    fresh.emplace<SplatCloud>(fc, cloud);
    fresh.emplace<Lattice>(fl, reg.get<Lattice>(le));
    fresh.emplace<Deformers>(fc, Deformers{{fl}});
    ffd_system(fresh, {});
    const auto& a = reg.get<DeformedSplats>(c).positions;
    const auto& b = fresh.get<DeformedSplats>(fc).positions;
    const auto& an = reg.get<DeformedSplats>(c).normals;
    const auto& bn = fresh.get<DeformedSplats>(fc).normals;
    d.same_as_scratch = a.size() == b.size() && an.size() == bn.size() &&
                        std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])) == 0 &&
                        std::memcmp(an.data(), bn.data(), an.size() * sizeof(an[0])) == 0;
    return d;
}

TEST(PageRedeformMorton, OneControlPointDragRedoesThePagesHoldingAPointInItsSupportCountedFromPositions) {
    const SplatCloud bands = sphere_cloud(1000000, false), morton = sphere_cloud(1000000, true);
    struct Case {
        int div;
        glm::ivec3 ijk;
    };
    // 21^3: an off-centre point (support 1/5 of the height at the bottom) and the centre; 11^3: both.
    for (const Case& k :
         {Case{20, {10, 2, 10}}, Case{20, {10, 10, 10}}, Case{10, {5, 1, 5}}, Case{10, {5, 5, 5}}}) {
        const std::string what = std::to_string(k.div + 1) + "^3, point (" + std::to_string(k.ijk.x) + ", " +
                                 std::to_string(k.ijk.y) + ", " + std::to_string(k.ijk.z) + ")";
        const Drag m = drag(morton, k.div, k.ijk);
        // The rule redoes a page when one of its points meets the support (its box only nominates it).
        const std::size_t expected = pages_meeting_support(morton, k.div, k.ijk, 1);
        EXPECT_EQ(m.total, 16u) << what;
        EXPECT_EQ(m.redone, expected) << what;
        EXPECT_TRUE(m.same_as_scratch) << what;
        // The band order's count by the same independent rule.
        const Drag b = drag(bands, k.div, k.ijk);
        EXPECT_EQ(b.redone, pages_meeting_support(bands, k.div, k.ijk, 1)) << what;
        // The bound holds in the sphere's own order; Morton pages (half an octant each, reaching from
        // the pole to the equator) can hold a point in a bottom support on 5 or 6 of 16.
        EXPECT_LE(b.redone * 10, b.total * 3) << what;
        EXPECT_TRUE(b.same_as_scratch) << what;
        // For the record: what a test of the page boxes alone, or of boxes per 2,048-point block, would redo.
        std::printf(
            "%s: redone Morton %zu / %zu, bands %zu / %zu; with 2048-point block boxes Morton %zu, "
            "bands %zu; with page boxes alone: Morton %zu, bands %zu\n",
            what.c_str(), m.redone, m.total, b.redone, b.total,
            pages_meeting_support(morton, k.div, k.ijk, 2048),
            pages_meeting_support(bands, k.div, k.ijk, 2048), pages_meeting_support(morton, k.div, k.ijk),
            pages_meeting_support(bands, k.div, k.ijk));
    }
}

}  // namespace
}  // namespace sffd::ffd
