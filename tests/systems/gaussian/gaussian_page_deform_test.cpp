// Page-bounded re-deformation of 3D Gaussians (the deformation skeleton shared with surface splats,
// systems/ffd/deform_skeleton.h): after random control-point edits of chained B-spline and Bernstein
// lattices, and an edit of a range of Gaussians, gaussian_deform_system's output equals a deformation from
// scratch byte for byte (centres, scales, rotations, SH or SH frames), in both SH modes, and redoes only
// the pages the edits reach.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <numeric>
#include <random>

#include "runtime/scene/point_pages.h"
#include "systems/ffd/ffd_system.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/gaussian_system.h"
#include "tests/systems/gaussian/random_cloud.h"

namespace sffd {
namespace {

Lattice box_lattice(glm::dvec3 lo, double size, int div, LatticeBasis basis) {
    return make_lattice(lo, {glm::dvec3(size, 0, 0), glm::dvec3(0, size, 0), glm::dvec3(0, 0, size)},
                        glm::ivec3(div), basis);
}

struct Rig {
    ecs::Registry reg;
    ecs::Entity cloud;
    std::vector<ecs::Entity> lattices;
    Rig(const GaussianCloud& c, const std::vector<Lattice>& ls, gaussian::ShMode mode) {
        reg.set_resource<FfdSettings>().force_cpu = true;
        reg.set_resource<GaussianDeformSettings>().cpu_sh = mode;
        cloud = reg.create();
        reg.emplace<GaussianCloud>(cloud, c);
        for (const Lattice& l : ls) {
            lattices.push_back(reg.create());
            reg.emplace<Lattice>(lattices.back(), l);
        }
        reg.emplace<Deformers>(cloud, Deformers{lattices});
    }
    const GaussianDeformStats& stats() const { return reg.resource<GaussianDeformStats>(); }
};

template <class T>
bool same_bytes(const std::vector<T>& a, const std::vector<T>& b) {
    // memcmp of two empty vectors would pass null pointers, which it must not be given.
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

void expect_equals_from_scratch(const Rig& inc, gaussian::ShMode mode, const std::string& what) {
    std::vector<Lattice> ls;
    for (ecs::Entity e : inc.lattices) ls.push_back(inc.reg.get<Lattice>(e));
    Rig fresh(inc.reg.get<GaussianCloud>(inc.cloud), ls, mode);
    gaussian_deform_system(fresh.reg, {});
    const GaussianCloud &a = inc.reg.get<DeformedGaussians>(inc.cloud).cloud,
                        &b = fresh.reg.get<DeformedGaussians>(fresh.cloud).cloud;
    ASSERT_EQ(a.size(), inc.reg.get<GaussianCloud>(inc.cloud).size()) << what;
    EXPECT_TRUE(same_bytes(a.positions, b.positions)) << what;
    EXPECT_TRUE(same_bytes(a.scales, b.scales)) << what;
    EXPECT_TRUE(same_bytes(a.rotations, b.rotations)) << what;
    EXPECT_TRUE(same_bytes(a.sh, b.sh)) << what;
    EXPECT_TRUE(same_bytes(a.sh_frames, b.sh_frames)) << what;
    EXPECT_TRUE(same_bytes(a.opacities, b.opacities)) << what;
    const DeformedGaussians &da = inc.reg.get<DeformedGaussians>(inc.cloud),
                            &db = fresh.reg.get<DeformedGaussians>(fresh.cloud);
    EXPECT_EQ(da.inverted, db.inverted) << what;
    EXPECT_EQ(da.degenerate, db.degenerate) << what;
}

class GaussianPageRedeform : public ::testing::TestWithParam<gaussian::ShMode> {};

TEST_P(GaussianPageRedeform, RandomEditsEqualADeformationFromScratchByteForByte) {
    const gaussian::ShMode mode = GetParam();
    // 4 pages (250,000 Gaussians, SH degree 1), slabs in y; a global B-spline lattice and a local
    // Bernstein one, chained.
    const GaussianCloud cloud = test::slab_cloud(250000, 1);
    Rig rig(cloud,
            {box_lattice(glm::dvec3(-1.1), 2.2, 10, LatticeBasis::bspline),
             box_lattice(glm::dvec3(-0.5, 0.2, -0.5), 0.9, 3, LatticeBasis::bernstein)},
            mode);
    gaussian_deform_system(rig.reg, {});
    ASSERT_EQ(rig.stats().last_pages.total, 4u);
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> step(-0.05, 0.05);
    std::size_t partial = 0;
    for (int edit = 0; edit < 10; ++edit) {
        const std::size_t d = edit % 3 == 2 ? 1 : 0;
        Lattice& l = rig.reg.patch<Lattice>(rig.lattices[d]);
        std::uniform_int_distribution<std::size_t> pick(0, l.size() - 1);
        l.current[pick(rng)] += glm::dvec3(step(rng), step(rng), step(rng));
        gaussian_deform_system(rig.reg, {});
        partial += rig.stats().last_pages.redone < rig.stats().last_pages.total;
        expect_equals_from_scratch(rig, mode, "edit " + std::to_string(edit));
    }
    EXPECT_GT(partial, 0u);
    // Gaussians 10..19 (page 0) grow: only their page is redone.
    GaussianCloud& c = rig.reg.get<GaussianCloud>(rig.cloud);
    for (std::size_t i = 10; i < 20; ++i) c.scales[i] *= 1.5f;
    mark_points_changed(rig.reg, rig.cloud, PointColumn::scale, 10, 10);
    gaussian_deform_system(rig.reg, {});
    EXPECT_EQ(rig.stats().last_pages.redone, 1u);
    expect_equals_from_scratch(rig, mode, "range edit");
}

TEST_P(GaussianPageRedeform, ADragNearTheBottomRedoesOnlyTheBottomPages) {
    const gaussian::ShMode mode = GetParam();
    const GaussianCloud cloud = test::slab_cloud(400000, 0);  // 7 pages
    Rig rig(cloud, {box_lattice(glm::dvec3(-1.1), 2.2, 20, LatticeBasis::bspline)}, mode);
    gaussian_deform_system(rig.reg, {});
    // Control point (10, 1, 10) influences l·t in (-1, 3): y below -1.1 + 3 * 0.11 = -0.77, under 1/4 of
    // the lattice's height; the slabs holding such y, from the centres themselves.
    const double top = -0.77 + 2e-4 * 2.2;
    std::size_t expected = 0;
    for (std::size_t p = 0; p < page_count(cloud.size()); ++p)
        expected += double(cloud.positions[page_range(p, cloud.size()).first].y) <= top;
    for (int s = 1; s <= 2; ++s) {
        Lattice& l = rig.reg.patch<Lattice>(rig.lattices[0]);
        l.current[l.index(10, 1, 10)] += glm::dvec3(0.02, 0.03, 0.0);
        gaussian_deform_system(rig.reg, {});
        EXPECT_EQ(rig.stats().last_pages.redone, expected);
    }
    EXPECT_LT(expected, 3u);
    expect_equals_from_scratch(rig, mode, "drag");
}

INSTANTIATE_TEST_SUITE_P(ShModes, GaussianPageRedeform,
                         ::testing::Values(gaussian::ShMode::rotate_coefficients,
                                           gaussian::ShMode::rotate_view));

}  // namespace
}  // namespace sffd
