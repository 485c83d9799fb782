// Page-bounded re-deformation on the compute path, both kinds (the deformation skeleton's one staleness
// rule, systems/ffd/deform_staleness.h): a control-point drag dispatches only the pages its support reaches,
// and what the resident buffers then hold equals, byte for byte, a deformation of the same inputs from
// scratch on the same path; so do the counts, which the passes keep per page (shaders/ffd/page_stats.glsl),
// also where a lowered block limit starts batches inside a page and work groups straddle two pages.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <numeric>
#include <vector>

#include "runtime/ecs/registry.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/limits.h"
#include "runtime/gfx/splat_store.h"
#include "runtime/scene/components.h"
#include "runtime/scene/point_pages.h"
#include "systems/ffd/components.h"
#include "systems/ffd/ffd_gpu.h"
#include "systems/ffd/ffd_system.h"
#include "systems/ffd/lattice.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/gaussian_system.h"
#include "systems/gaussian/gpu_deform.h"
#include "systems/gaussian/gpu_store.h"
#include "systems/residency/residency_system.h"
#include "tests/systems/ffd/test_util.h"
#include "tests/systems/gaussian/random_cloud.h"
#include "tests/test_util/headless_gl.h"

namespace sffd {
namespace {

class GpuPageRedeform : public test::HeadlessGlTest {};

Lattice box_lattice(glm::dvec3 lo, double size, int div, LatticeBasis basis) {
    return make_lattice(lo, {glm::dvec3(size, 0, 0), glm::dvec3(0, size, 0), glm::dvec3(0, 0, size)},
                        glm::ivec3(div), basis);
}

// A 21^3 B-spline lattice over [-1.1, 1.1]^3: control point (10, 2, 10) influences l·s, l·u in (8, 12)
// and l·t in (0, 4), x, z in [-0.22, 0.22] and y in [-1.1, -0.66] (under a quarter of the lattice on every
// axis), widened by the rule's margin.
constexpr int kI = 10, kJ = 2, kK = 10;
const glm::dvec3 kSupportLo = glm::dvec3(-0.22, -1.1, -0.22) - 2e-4 * 2.2;
const glm::dvec3 kSupportHi = glm::dvec3(0.22, -0.66, 0.22) + 2e-4 * 2.2;

// Pulled down by over half the sphere's radius, the point folds the cells at the sphere's bottom pole
// (∂D_y/∂y there is about -2 per unit of drag: det J < 0).
const glm::dvec3 kFold(0.0, -1.0, 0.0);

// Pages with a point inside [lo, hi]: the ones the rule redoes.
std::size_t pages_with_point_in(const std::vector<glm::vec3>& p, glm::dvec3 lo, glm::dvec3 hi) {
    std::size_t pages = 0;
    for (std::size_t page = 0; page < page_count(p.size()); ++page) {
        const PageRange r = page_range(page, p.size());
        pages += std::any_of(p.begin() + std::ptrdiff_t(r.first),
                             p.begin() + std::ptrdiff_t(r.first + r.count), [&](const glm::vec3& x) {
                                 return glm::all(glm::greaterThanEqual(glm::dvec3(x), lo)) &&
                                        glm::all(glm::lessThanEqual(glm::dvec3(x), hi));
                             });
    }
    return pages;
}

template <class Cloud>
struct Rig {
    ecs::Registry reg;
    ecs::Entity cloud, lattice;
    Rig(const Cloud& c, const Lattice& l) {
        reg.set_resource<FfdSettings>().force_gpu = true;  // llvmpipe would choose the CPU path
        cloud = reg.create(), lattice = reg.create();
        reg.emplace<Cloud>(cloud, c);
        reg.emplace<Lattice>(lattice, l);
        reg.emplace<Deformers>(cloud, Deformers{{lattice}});
    }
    ~Rig() {
        ffd_release_gpu(reg);
        gaussian_release_gpu(reg);
    }
    // One frame's residency and deformation phases.
    void frame() {
        residency_system(reg, {});
        if constexpr (std::is_same_v<Cloud, SplatCloud>) ffd_system(reg, {});
        else gaussian_deform_system(reg, {});
    }
    // The counts of the last run: the read-back arrives once the GPU is done (glFinish stands in for
    // frames passing) and a frame in which nothing moved collects it.
    void settle() {
        glFinish();
        frame();
    }
    void drag(glm::dvec3 by) {
        Lattice& l = reg.patch<Lattice>(lattice);
        l.current[l.index(kI, kJ, kK)] += by;
    }
};

std::vector<std::byte> read_buffer(GLuint buffer, std::size_t bytes) {
    std::vector<std::byte> v(bytes);
    if (bytes) glGetNamedBufferSubData(buffer, 0, GLsizeiptr(bytes), v.data());
    return v;
}

SplatCloud sphere(std::size_t n) {
    const ffd::test::Cloud c = ffd::test::fibonacci_sphere(n);  // latitude bands: pages are slabs
    SplatCloud s;
    s.positions = c.p, s.normals = c.n, s.axis_u = c.u, s.axis_v = c.v;
    return s;
}

std::vector<std::byte> deformed_splats(Rig<SplatCloud>& rig) {
    const gfx::GpuSplats& g = rig.reg.resource<gfx::GpuSplatStore>().clouds.at(rig.cloud);
    EXPECT_EQ(g.state, gfx::Residency::deformed_gpu);
    return read_buffer(g.deformed.id(), std::size_t(g.count) * sizeof(gpu::GpuSplat));
}

TEST_F(GpuPageRedeform, SurfaceDragDispatchesOnlyItsPagesAndEqualsARunFromScratch) {
    if (IsSkipped() || HasFatalFailure()) return;
    const SplatCloud cloud = sphere(400000);  // 7 pages
    const std::size_t total = page_count(cloud.size());
    const Lattice l = box_lattice(glm::dvec3(-1.1), 2.2, 20, LatticeBasis::bspline);
    Rig<SplatCloud> rig(cloud, l);
    rig.frame();
    const FfdStats& stats = rig.reg.resource<FfdStats>();
    ASSERT_EQ(stats.gpu_runs, 1u);
    ASSERT_EQ(stats.last_pages.redone, total);
    const std::size_t expected = pages_with_point_in(cloud.positions, kSupportLo, kSupportHi);
    ASSERT_GT(expected, 0u);
    ASSERT_LT(expected * 10, total * 3);  // under 30% of the pages
    // A step, one that folds cells near the point, and a step of the folded lattice: the pages redone last
    // count their inverted cells again, which only their zeroed counters keep from being counted twice.
    for (const glm::dvec3 by : {glm::dvec3(0.0, 0.03, 0.02), kFold, glm::dvec3(0.01, 0.03, 0.0)}) {
        const std::uint64_t runs = stats.gpu_runs;
        rig.drag(by);
        rig.frame();
        EXPECT_EQ(stats.gpu_runs, runs + 1);
        EXPECT_EQ(stats.last_pages.redone, expected);
        EXPECT_EQ(stats.last_pages.total, total);
    }
    rig.settle();
    Rig<SplatCloud> fresh(cloud, rig.reg.get<Lattice>(rig.lattice));
    fresh.frame();
    fresh.settle();
    EXPECT_EQ(fresh.reg.resource<FfdStats>().last_pages.redone, total);
    EXPECT_TRUE(deformed_splats(rig) == deformed_splats(fresh)) << "page-wise output differs from scratch";
    const DeformedSplats &a = rig.reg.get<DeformedSplats>(rig.cloud),
                         &b = fresh.reg.get<DeformedSplats>(fresh.cloud);
    EXPECT_GT(b.inverted, 0u) << "the fold should invert some cells";
    EXPECT_EQ(a.inverted, b.inverted);
    EXPECT_EQ(a.inverted_version, a.version) << "the last run's count has arrived";
}

TEST_F(GpuPageRedeform, CountsStayRightWhenWorkGroupsStraddlePages) {
    if (IsSkipped() || HasFatalFailure()) return;
    // A lattice mirrored in x: every point is inside and in an inverted cell (J = diag(-1, 1, 1)), so
    // every work group counts both, the ones across two pages too.
    const ffd::test::Cloud c = ffd::test::fibonacci_sphere(300000);
    Lattice l = box_lattice(glm::dvec3(-1.1), 2.2, 3, LatticeBasis::bernstein);
    for (std::size_t i = 0; i < l.current.size(); ++i) l.current[i].x = -l.rest[i].x;
    auto gpu = ffd::GpuDeformer::create();
    ASSERT_TRUE(gpu) << gpu.message();
    const std::size_t n = c.p.size();
    auto run = [&]() -> Result<ffd::DeformStats> {
        std::vector<glm::vec3> p(n), nn(n), u(n), v(n);
        return gpu->deform(l, {c.p.data(), c.n.data(), c.u.data(), c.v.data(), n, c.origin},
                           {p.data(), nn.data(), u.data(), v.data()});
    };
    auto whole = run();
    ASSERT_TRUE(whole) << whole.message();
    EXPECT_EQ(whole->inside, n);
    EXPECT_EQ(whole->inverted, n);
    // About 100,003 splats a batch: batches start inside pages, off the 64-wide groups' grid.
    gfx::GlLimits small = gfx::limits();
    small.max_ssbo_block_size = 100003 * 64;
    gfx::ScopedLimits scope(small);
    auto cut = run();
    ASSERT_TRUE(cut) << cut.message();
    EXPECT_EQ(cut->inside, n);
    EXPECT_EQ(cut->inverted, n);
}

struct GaussianBuffers {
    std::vector<std::byte> deformed, frames, sh;
    bool operator==(const GaussianBuffers&) const = default;
};

GaussianBuffers deformed_gaussians(Rig<GaussianCloud>& rig) {
    const gaussian::GpuGaussians& g = rig.reg.resource<gaussian::GpuGaussianStore>().clouds.at(rig.cloud);
    EXPECT_EQ(g.state, gfx::Residency::deformed_gpu);
    GaussianBuffers b;
    b.deformed = read_buffer(g.deformed.id(), std::size_t(g.count) * sizeof(gpu::GpuGaussian));
    if (g.has_frames()) b.frames = read_buffer(g.frames.id(), std::size_t(g.count) * 12 * sizeof(float));
    if (g.sh_source == gaussian::ShSource::rotated)
        b.sh = read_buffer(g.deformed_sh.id(),
                           std::size_t(g.count) * std::size_t(sh_coeffs(g.sh_degree)) * 3 * 4);
    return b;
}

class GpuPageRedeformGaussians : public test::HeadlessGlTest,
                                 public ::testing::WithParamInterface<gaussian::ShMode> {};

TEST_P(GpuPageRedeformGaussians, DragDispatchesOnlyItsPagesAndEqualsARunFromScratch) {
    if (IsSkipped() || HasFatalFailure()) return;
    const GaussianCloud cloud = test::slab_cloud(300000, 1);  // 5 pages
    const std::size_t total = page_count(cloud.size());
    const Lattice l = box_lattice(glm::dvec3(-1.1), 2.2, 20, LatticeBasis::bspline);
    Rig<GaussianCloud> rig(cloud, l);
    rig.reg.set_resource<GaussianDeformSettings>().gpu_sh = GetParam();
    rig.frame();
    const GaussianDeformStats& stats = rig.reg.resource<GaussianDeformStats>();
    ASSERT_EQ(stats.gpu_runs, 1u);
    ASSERT_EQ(stats.last_pages.redone, total);
    const std::size_t expected = pages_with_point_in(cloud.positions, kSupportLo, kSupportHi);
    ASSERT_GT(expected, 0u);
    ASSERT_LT(expected, total);
    for (const glm::dvec3 by : {glm::dvec3(0, 0.6, 0), glm::dvec3(0.02, 0.03, 0.0)}) {
        rig.drag(by);
        rig.frame();
        EXPECT_EQ(stats.last_pages.redone, expected);
    }
    rig.settle();
    Rig<GaussianCloud> fresh(cloud, rig.reg.get<Lattice>(rig.lattice));
    fresh.reg.set_resource<GaussianDeformSettings>().gpu_sh = GetParam();
    fresh.frame();
    fresh.settle();
    EXPECT_TRUE(deformed_gaussians(rig) == deformed_gaussians(fresh))
        << "page-wise output differs from scratch";
    const DeformedGaussians &a = rig.reg.get<DeformedGaussians>(rig.cloud),
                            &b = fresh.reg.get<DeformedGaussians>(fresh.cloud);
    ASSERT_TRUE(a.stats_arrived && b.stats_arrived);
    EXPECT_GT(b.inverted, 0u) << "the fold should invert some cells";
    EXPECT_EQ(a.inverted, b.inverted);
    EXPECT_EQ(a.degenerate, b.degenerate);
}

INSTANTIATE_TEST_SUITE_P(ShModes, GpuPageRedeformGaussians,
                         ::testing::Values(gaussian::ShMode::rotate_view,
                                           gaussian::ShMode::rotate_coefficients));

}  // namespace
}  // namespace sffd
