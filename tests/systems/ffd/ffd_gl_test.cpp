// GPU path (headless EGL, llvmpipe): the compute pass against the CPU reference (1e-5), ffd_system on
// GpuSplatStore buffers, control points uploaded only when edited, nothing dispatched when nothing changed.
#include <gtest/gtest.h>

#include <bit>
#include <optional>

#include "runtime/ecs/registry.h"
#include "runtime/gfx/context.h"
#include "runtime/gfx/dispatch.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/limits.h"
#include "runtime/gfx/render_target.h"
#include "runtime/gfx/splat_store.h"
#include "runtime/scene/components.h"
#include "shaders/common/bindings.h"
#include "systems/ffd/deform.h"
#include "systems/ffd/ffd_gpu.h"
#include "systems/ffd/gpu_kernel.h"
#include "systems/ffd/ffd_system.h"
#include "systems/ffd/lattice.h"
#include "systems/ffd/operations.h"
#include "systems/ffd/paper_mode.h"
#include "tests/systems/ffd/test_util.h"
#include "tests/test_util/headless_gl.h"

#include <glm/gtc/matrix_transform.hpp>

namespace sffd {
namespace {

class FfdGl : public test::HeadlessGlTest {};

// A point cloud with the test points, deformed by one lattice.
std::pair<ecs::Entity, ecs::Entity> add_cloud_and_lattice(ecs::Registry& reg, const ffd::test::Cloud& c,
                                                          Lattice lattice) {
    const ecs::Entity cloud = reg.create();
    SplatCloud sc;
    sc.positions = c.p, sc.normals = c.n, sc.axis_u = c.u, sc.axis_v = c.v;
    reg.emplace<SplatCloud>(cloud, std::move(sc));
    const ecs::Entity le = reg.create();
    reg.emplace<Lattice>(le, std::move(lattice));
    reg.emplace<Deformers>(cloud, Deformers{{le}});
    return {cloud, le};
}

// A Bernstein lattice over the box [-1.1, 1.1]^3 around the test points (a unit sphere).
Lattice box_lattice(glm::ivec3 divisions) {
    return ffd::make_lattice(
        {-1.1, -1.1, -1.1}, {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)}, divisions);
}

// What residency_system does: upload the authored splats as the cloud's `rest` buffer (state rest).
gfx::GpuSplatStore& upload_rest(ecs::Registry& reg, ecs::Entity cloud, const ffd::test::Cloud& c) {
    auto& store = reg.set_resource<gfx::GpuSplatStore>();
    gfx::GpuSplats& s = store.clouds[cloud];
    std::vector<gpu::GpuSplat> packed(c.size());
    for (std::size_t i = 0; i < c.size(); ++i)
        packed[i] = {{c.p[i].x, c.p[i].y, c.p[i].z, 0},
                     {c.n[i].x, c.n[i].y, c.n[i].z, 1},
                     {c.u[i].x, c.u[i].y, c.u[i].z, 0},
                     {c.v[i].x, c.v[i].y, c.v[i].z, 0}};
    s.rest = gfx::Buffer::create("test.rest");
    glNamedBufferData(s.rest.id(), GLsizeiptr(packed.size() * sizeof(gpu::GpuSplat)), packed.data(),
                      GL_STATIC_DRAW);
    s.count = std::uint32_t(c.size());
    s.rest_version = reg.version<SplatCloud>(cloud);
    return store;
}

struct Splats {
    std::vector<glm::vec3> p, n, u, v;
    explicit Splats(std::size_t count) : p(count), n(count), u(count), v(count) {}
    ffd::PointsOut out() { return {p.data(), n.data(), u.data(), v.data()}; }
};

// The GPU's deformation of `in` against the double-precision reference: positions within 1e-5 of the
// lattice's size (2.2 here), unit normals within 1e-5, axes within 1e-5 of their length; the same
// statistics. `g` receives the GPU's output.
void expect_gpu_matches_reference(ffd::GpuDeformer& gpu, const Lattice& l, const ffd::PointsIn& in,
                                  Splats& g) {
    Splats r(in.count);
    auto gs = gpu.deform(l, in, g.out());
    ASSERT_TRUE(gs.ok()) << gs.message();
    auto rs = ffd::deform(l, in, r.out(), ffd::Backend::reference);
    ASSERT_TRUE(rs.ok());
    EXPECT_EQ(gs->inside, rs->inside);
    EXPECT_EQ(gs->inverted, rs->inverted);
    for (std::size_t i = 0; i < in.count; ++i) {
        ASSERT_LT(glm::length(g.p[i] - r.p[i]), 1e-5f * 2.2f) << i;
        ASSERT_LT(glm::length(g.n[i] - r.n[i]), 1e-5f) << i;
        ASSERT_LT(glm::length(g.u[i] - r.u[i]), 1e-5f * glm::length(r.u[i]) + 1e-9f) << i;
        ASSERT_LT(glm::length(g.v[i] - r.v[i]), 1e-5f * glm::length(r.v[i]) + 1e-9f) << i;
    }
}

TEST_F(FfdGl, ComputePassMatchesCpuReference) {
    auto gpu = ffd::GpuDeformer::create();
    ASSERT_TRUE(gpu.ok()) << gpu.message();
    ffd::test::Cloud c = ffd::test::fibonacci_sphere(20000);
    c.origin = glm::dvec3(1e6, 0, 0);  // far from the world origin
    for (LatticeBasis basis : {LatticeBasis::bernstein, LatticeBasis::bspline}) {
        Lattice l = ffd::make_lattice(c.origin + glm::dvec3(-1.1),
                                      {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)},
                                      {10, 10, 10}, basis);
        ffd::twist_graded(l, ffd::all_control_points(l), {0, 1, 0}, 0.6, c.origin);
        const ffd::PointsIn in{c.p.data(), c.n.data(), c.u.data(), c.v.data(), c.size(), c.origin};
        Splats g(c.size());
        expect_gpu_matches_reference(*gpu, l, in, g);
        if (HasFatalFailure()) return;
    }
}

// Clouds beyond 65,535 work groups (4.19M splats) are deformed over a 2D grid (gfx::dispatch_1d). With 4
// groups per row, 5,000 splats take a 4 x 20 grid of 64-wide groups (4 x 5 of the shared-memory Bernstein
// kernel's 256), the last row partly empty: the output is bit-identical to the one-row dispatch's, and the
// statistics count every splat once. Bit equality holds on any implementation here: one program, one
// invocation per splat computing the same expressions; only the grid's shape differs.
TEST_F(FfdGl, GridDispatchDeformsExactlyAsOneRow) {
    auto gpu = ffd::GpuDeformer::create();
    ASSERT_TRUE(gpu.ok()) << gpu.message();
    const ffd::test::Cloud c = ffd::test::fibonacci_sphere(5000);
    // Bernstein direct and shared, B-spline direct and packed.
    for (int variant = 0; variant < 4; ++variant) {
        const LatticeBasis basis = variant >= 2 ? LatticeBasis::bspline : LatticeBasis::bernstein;
        const ffd::GpuBernsteinKernel kernel = variant == 1   ? ffd::GpuBernsteinKernel::shared
                                               : variant == 3 ? ffd::GpuBernsteinKernel::packed
                                                              : ffd::GpuBernsteinKernel::direct;
        gpu->set_bernstein_kernel(kernel);
        Lattice l = ffd::make_lattice(c.origin + glm::dvec3(-1.1),
                                      {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)},
                                      {5, 4, 6}, basis);
        ffd::twist_graded(l, ffd::all_control_points(l), {0, 1, 0}, 0.6, c.origin);
        const std::size_t n = c.size();
        const ffd::PointsIn in{c.p.data(), c.n.data(), c.u.data(), c.v.data(), n, c.origin};
        std::vector<glm::vec3> p1(n), n1(n), u1(n), v1(n), p2(n, glm::vec3(-7.0f)), n2(n), u2(n), v2(n);
        auto row = gpu->deform(l, in, {p1.data(), n1.data(), u1.data(), v1.data()});
        ASSERT_TRUE(row.ok()) << row.message();
        auto grid = [&] {
            gfx::ScopedDispatchLimit four(4);
            return gpu->deform(l, in, {p2.data(), n2.data(), u2.data(), v2.data()});
        }();
        ASSERT_TRUE(grid.ok()) << grid.message();
        EXPECT_EQ(gpu->last_bernstein_kernel(), kernel);
        EXPECT_EQ(row->inside, n);  // the lattice holds the whole sphere: each splat counted once
        EXPECT_EQ(grid->inside, row->inside);
        EXPECT_EQ(grid->inverted, row->inverted);
        std::size_t moved = 0;
        for (std::size_t i = 0; i < n; ++i) {
            ASSERT_EQ(p2[i], p1[i]) << i;
            ASSERT_EQ(n2[i], n1[i]) << i;
            ASSERT_EQ(u2[i], u1[i]) << i;
            ASSERT_EQ(v2[i], v1[i]) << i;
            moved += p1[i] != c.p[i];
        }
        EXPECT_GT(moved, n / 2);  // the twist moved most splats (the comparison is not of unchanged input)
    }
}

// The kernels (GpuBernsteinKernel): control points from shared memory (copied once per work group: the
// lattice for Bernstein, its zero-bordered grid for B-spline) or read directly (Bernstein: a UBO, or the
// SSBO when too large for a UBO; B-spline: the SSBO, point by point or packed in runs along u) run the
// same arithmetic: the same statistics, and each within 1e-5 of the double-precision CPU reference (the
// packed runs' sums over u are dot products, which a driver may add in any order). Not bit-identical
// outputs: they are two differently compiled programs, and GLSL lets each contract a * b + c into an fma
// and round its divisions (the binomials) and inversesqrt within 2.5 ULP; llvmpipe happens to give equal
// bits. The reference bound holds on any conforming implementation (float rounding of sums of at most
// 7³ weights of unit scale); so the kernels agree within twice it. A wrong run layout moves points by
// the lattice's displacements (tenths here), far beyond these bounds.
// Shapes: uneven 6x5x7 and 4x3x5 (the paper's 11³ compiles for minutes on llvmpipe as a shared-memory
// program, whose barrier() llvmpipe splits into coroutines; it runs only in bench_ffd_gpu). Lattices over
// the shared-memory limit fall back to the UBO or the SSBO (KernelChoice.*, without compiling them).
TEST_F(FfdGl, EveryControlPointKernelMatchesTheReferenceForBothBases) {
    auto gpu = ffd::GpuDeformer::create();
    ASSERT_TRUE(gpu.ok()) << gpu.message();
    GLint max_shared = 0;
    glGetIntegerv(GL_MAX_COMPUTE_SHARED_MEMORY_SIZE, &max_shared);
    ffd::test::Cloud c = ffd::test::fibonacci_sphere(3000);
    c.origin = glm::dvec3(0, 2e5, 0);
    for (int shape = 0; shape < 4; ++shape) {
        const glm::ivec3 div = shape % 2 == 0 ? glm::ivec3(5, 4, 6) : glm::ivec3(3, 2, 4);
        const LatticeBasis basis = shape < 2 ? LatticeBasis::bernstein : LatticeBasis::bspline;
        SCOPED_TRACE(basis == LatticeBasis::bernstein ? "bernstein" : "bspline");
        Lattice l = ffd::make_lattice(c.origin + glm::dvec3(-1.1),
                                      {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)},
                                      div, basis);
        ffd::twist_graded(l, ffd::all_control_points(l), {0, 1, 0}, 0.6, c.origin);
        const std::size_t n = c.size();
        const ffd::PointsIn in{c.p.data(), c.n.data(), c.u.data(), c.v.data(), n, c.origin};
        // Kernels 0..2: direct, shared, packed (B-spline runs; Bernstein runs direct); 3: the reference.
        const ffd::GpuBernsteinKernel kernels[3] = {ffd::GpuBernsteinKernel::direct,
                                                    ffd::GpuBernsteinKernel::shared,
                                                    ffd::GpuBernsteinKernel::packed};
        std::vector<glm::vec3> p[4], nn[4], u[4], v[4];
        for (int k = 0; k < 4; ++k) p[k].resize(n), nn[k].resize(n), u[k].resize(n), v[k].resize(n);
        ASSERT_GE(max_shared, 32768);  // GL 4.5's minimum: these lattices' xyz fit
        std::optional<ffd::DeformStats> stats[3];
        for (int k = 0; k < 3; ++k) {
            gpu->set_bernstein_kernel(kernels[k]);
            auto d = gpu->deform(l, in, {p[k].data(), nn[k].data(), u[k].data(), v[k].data()});
            ASSERT_TRUE(d.ok()) << d.message();
            const bool direct =
                kernels[k] == ffd::GpuBernsteinKernel::packed && basis == LatticeBasis::bernstein;
            EXPECT_EQ(gpu->last_bernstein_kernel(), direct ? ffd::GpuBernsteinKernel::direct : kernels[k]);
            stats[k] = *d;
        }
        auto r = ffd::deform(l, in, {p[3].data(), nn[3].data(), u[3].data(), v[3].data()},
                             ffd::Backend::reference);
        ASSERT_TRUE(r.ok());
        for (int k = 0; k < 3; ++k) {
            EXPECT_EQ(stats[k]->inside, r->inside) << "kernel " << k;
            EXPECT_EQ(stats[k]->inverted, r->inverted) << "kernel " << k;
        }
        for (std::size_t i = 0; i < n; ++i) {
            for (int k = 0; k < 3; ++k) {  // each kernel against the reference
                ASSERT_LT(glm::length(p[k][i] - p[3][i]), 1e-5f * 2.2f) << i << " kernel " << k;
                ASSERT_LT(glm::length(nn[k][i] - nn[3][i]), 1e-5f) << i << " kernel " << k;
                ASSERT_LT(glm::length(u[k][i] - u[3][i]), 1e-5f * glm::length(u[3][i]) + 1e-9f)
                    << i << " kernel " << k;
                ASSERT_LT(glm::length(v[k][i] - v[3][i]), 1e-5f * glm::length(v[3][i]) + 1e-9f)
                    << i << " kernel " << k;
            }
            ASSERT_LT(glm::length(p[1][i] - p[0][i]), 2e-5f * 2.2f) << i;
            ASSERT_LT(glm::length(p[2][i] - p[0][i]), 2e-5f * 2.2f) << i;
        }
    }
}

// The Bernstein programs sum only the coordinates of ΔP that move (FFD_MOVE: one program per set of
// them), as the CPU kernel does. Each edit, from a UBO, from shared memory and from the SSBO (what
// lattices past GL_MAX_UNIFORM_BLOCK_SIZE read; a smaller limit, simulated, sends this one there), against
// the double-precision reference: a coordinate summed into the wrong output, or a moving one left out,
// moves points by tenths. The still coordinate of a twist is off by rounding only (1e-14 here), below the
// floor.
TEST_F(FfdGl, BernsteinSumsOnlyTheCoordinatesThatMoveOnEveryKernel) {
    auto gpu = ffd::GpuDeformer::create();
    ASSERT_TRUE(gpu.ok()) << gpu.message();
    ffd::test::Cloud c = ffd::test::random_cloud(2000, -1.05, 1.05, 4);
    for (glm::vec3& u : c.u) u.y = 0.0f;  // so a y residue in J would show in J u (below)
    struct Edit {
        const char* what;
        void (*apply)(Lattice&);
        bool y_still = false;  // y's residue is below the floor: every y stays exactly as it was
    };
    const Edit edits[] = {
        {"stretch along z",
         [](Lattice& l) {
             for (std::size_t i = 0; i < l.size(); i += 3) l.current[i].z += 0.15;
         }},
        {"stretch along y",
         [](Lattice& l) {
             for (std::size_t i = 1; i < l.size(); i += 2) l.current[i].y -= 0.1;
         }},
        {"x and z",
         [](Lattice& l) {
             for (std::size_t i = 0; i < l.size(); i += 2) l.current[i] += glm::dvec3(0.1, 0.0, -0.12);
         }},
        {"y and z",
         [](Lattice& l) {
             for (std::size_t i = 0; i < l.size(); i += 5) l.current[i] += glm::dvec3(0.0, 0.08, 0.1);
         }},
        {"twist about y, y off by rounding",
         [](Lattice& l) {
             ffd::test::twist_about_t(l, 0.6);
             l.current[5].y += 1e-14;
         },
         true},
        {"every coordinate", [](Lattice& l) { ffd::test::jitter(l, 0.05, 3); }},
    };
    const std::size_t n = c.size();
    const ffd::PointsIn in{c.p.data(), c.n.data(), c.u.data(), c.v.data(), n, c.origin};
    auto check = [&](const Lattice& l, ffd::GpuBernsteinKernel kernel, bool y_still) {
        gpu->set_bernstein_kernel(kernel);
        Splats g(n);
        expect_gpu_matches_reference(*gpu, l, in, g);
        if (HasFatalFailure()) return;
        EXPECT_EQ(gpu->last_bernstein_kernel(), kernel);
        // A program that summed y too would add its 1e-14 residue: invisible beside most positions in
        // float, but not beside a zero.
        for (std::size_t i = 0; y_still && i < n; ++i) {
            ASSERT_EQ(g.p[i].y, c.p[i].y) << i;
            ASSERT_EQ(g.u[i].y, 0.0f) << i;
        }
    };
    gfx::GlLimits small = gfx::limits();
    small.max_uniform_block_size = 1024;  // 64 points; the lattice below has 210
    for (const Edit& e : edits)
        for (int kind = 0; kind < 3; ++kind) {
            const ffd::GpuBernsteinKernel kernel =
                kind == 1 ? ffd::GpuBernsteinKernel::shared : ffd::GpuBernsteinKernel::direct;
            std::optional<gfx::ScopedLimits> ssbo;
            if (kind == 2) ssbo.emplace(small);
            SCOPED_TRACE(std::string(e.what) + (kind == 0   ? " (uniform block)"
                                                : kind == 1 ? " (shared)"
                                                            : " (storage buffer)"));
            Lattice l = ffd::make_lattice(
                {-1.1, -1.1, -1.1}, {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)},
                {4, 6, 5}, LatticeBasis::bernstein);
            e.apply(l);
            check(l, kernel, e.y_still);
            if (HasFatalFailure()) return;
        }
}

// A splat's colour word (GpuSplat::color, RGBA8) passes the compute pass bit for bit, moved or not and
// inside the lattice or not, whatever it would mean as a float: uncoloured (0xffffffff) and opaque colours
// with blue >= 128 are NaN or infinity patterns, transparent dark ones denormals. The shader declares the
// word a uint, so no driver may canonicalise or flush it (llvmpipe keeps float bits anyway; a GPU need not).
TEST_F(FfdGl, ColourWordsPassTheComputePassBitForBit) {
    auto gpu = ffd::GpuDeformer::create();
    ASSERT_TRUE(gpu.ok()) << gpu.message();
    const std::uint32_t colours[] = {0xffffffffu, 0xff800000u, 0x7f800000u, 0x7fc00001u,
                                     0x00000001u, 0x0000ff00u, 0x80000000u, 0xff8040c0u};
    std::vector<gpu::GpuSplat> splats;
    for (int k = 0; k < 64; ++k) {
        const float x = -1.5f + 3.0f * float(k) / 63.0f;  // some outside the lattice's [-1.1, 1.1]
        gpu::GpuSplat g{{x, 0.3f, -0.2f, std::bit_cast<float>(colours[k % 8])},
                        {0, 0, 1, 1},
                        {0.01f, 0, 0, 0},
                        {0, 0.01f, 0, 0}};
        splats.push_back(g);
    }
    const GLsizeiptr bytes = GLsizeiptr(splats.size() * sizeof(gpu::GpuSplat));
    gfx::Buffer in = gfx::Buffer::create("test.in"), out = gfx::Buffer::create("test.out");
    glNamedBufferData(in.id(), bytes, splats.data(), GL_STATIC_DRAW);
    glNamedBufferData(out.id(), bytes, nullptr, GL_DYNAMIC_COPY);
    Lattice l = box_lattice({3, 4, 2});
    for (bool moved : {false, true}) {
        SCOPED_TRACE(moved ? "twisted" : "at rest");
        if (moved) ffd::twist_graded(l, ffd::all_control_points(l), {0, 1, 0}, 0.6, glm::dvec3(0.0));
        ASSERT_TRUE(
            gpu->dispatch(l, 0, glm::dvec3(0.0), in.id(), out.id(), std::uint32_t(splats.size())).ok());
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        std::vector<gpu::GpuSplat> got(splats.size());
        glGetNamedBufferSubData(out.id(), 0, bytes, got.data());
        std::size_t moved_splats = 0;
        for (std::size_t k = 0; k < got.size(); ++k) {
            EXPECT_EQ(std::bit_cast<std::uint32_t>(got[k].center[3]), colours[k % 8]) << k;
            moved_splats += got[k].center[0] != splats[k].center[0];
        }
        EXPECT_EQ(moved_splats > 0, moved);
    }
}

TEST_F(FfdGl, SystemWritesDeformedBufferAndUploadsOnlyOnEdit) {
    ecs::Registry reg;
    const ffd::test::Cloud c = ffd::test::fibonacci_sphere(5000);
    const auto [cloud, le] = add_cloud_and_lattice(reg, c, box_lattice({5, 5, 5}));
    auto& settings = reg.set_resource<FfdSettings>();
    settings.force_gpu = true;  // llvmpipe would otherwise pick the (faster) CPU path
    auto& store = upload_rest(reg, cloud, c);
    ffd::twist_graded(reg.patch<Lattice>(le), ffd::all_control_points(reg.get<Lattice>(le)), {0, 1, 0}, 0.8,
                      glm::dvec3(0.0));
    ffd_system(reg, {});
    EXPECT_EQ(reg.resource<FfdStats>().gpu_runs, 1u);
    const gfx::GpuSplats& s = store.clouds[cloud];
    ASSERT_EQ(s.state, gfx::Residency::deformed_gpu);
    EXPECT_TRUE(ffd::output_on_gpu(reg, cloud));
    EXPECT_FALSE(reg.get<DeformedSplats>(cloud).cpu_valid);
    std::vector<gpu::GpuSplat> back(c.size());
    glGetNamedBufferSubData(s.deformed.id(), 0, GLsizeiptr(back.size() * sizeof(gpu::GpuSplat)), back.data());
    std::vector<glm::vec3> rp(c.size()), rn(c.size());
    ASSERT_TRUE(ffd::deform(reg.get<Lattice>(le), {c.p.data(), c.n.data(), nullptr, nullptr, c.size(), {}},
                            {rp.data(), rn.data()}, ffd::Backend::reference)
                    .ok());
    const DeformedSplats& d = reg.get<DeformedSplats>(cloud);
    for (std::size_t i = 0; i < c.size(); ++i) {
        const glm::vec3 p(back[i].center[0], back[i].center[1], back[i].center[2]);
        ASSERT_LT(glm::length(p - rp[i]), 2.2e-5f);
        ASSERT_LT(glm::length(glm::vec3(back[i].normal[0], back[i].normal[1], back[i].normal[2]) - rn[i]),
                  1e-5f);
        ASSERT_TRUE(glm::all(glm::greaterThanEqual(glm::dvec3(p), d.bounds_min)) &&
                    glm::all(glm::lessThanEqual(glm::dvec3(p), d.bounds_max)));
    }
    const std::uint64_t version = s.deformed_version;
    ffd_system(reg, {});  // nothing changed: no dispatch
    EXPECT_EQ(s.deformed_version, version);
    EXPECT_EQ(reg.resource<FfdStats>().gpu_runs, 1u);
    ffd::stretch(reg.patch<Lattice>(le), {0}, {0.01, 0, 0});
    ffd_system(reg, {});
    EXPECT_EQ(reg.resource<FfdStats>().gpu_runs, 2u);
    EXPECT_GT(s.deformed_version, version);
    ffd_release_gpu(reg);
    reg.erase_resource<gfx::GpuSplatStore>();
}

// The statistics' fences are polled without flushing (a flush a frame would be CPU time charged to the
// deformation; a frame loop's swap carries them to the GPU). A loop that never flushes still gets its
// counts: once every read-back slot is in flight, the poll flushes. (llvmpipe signals a fence that was never
// flushed, so only a hardware driver can fail this without that fallback.)
TEST_F(FfdGl, StatisticsArriveInALoopThatNeverFlushes) {
    ecs::Registry reg;
    const ffd::test::Cloud c = ffd::test::fibonacci_sphere(2000);
    const auto [cloud, le] = add_cloud_and_lattice(reg, c, box_lattice({3, 3, 3}));
    reg.set_resource<FfdSettings>().force_gpu = true;
    upload_rest(reg, cloud, c);
    std::uint64_t arrived_at = 0;
    for (std::uint64_t frame = 1; frame <= 40 && arrived_at == 0; ++frame) {
        ffd::stretch(reg.patch<Lattice>(le), {0}, {0.001, 0, 0});
        ffd_system(reg, {});
        if (reg.get<DeformedSplats>(cloud).inverted_version > 0) arrived_at = frame;
    }
    EXPECT_EQ(reg.resource<FfdStats>().gpu_sync_readbacks, 0u);
    ASSERT_GT(arrived_at, 0u) << "no statistics in 40 frames";
    EXPECT_LE(arrived_at, ffd::detail::StatsReadbacks::kMaxSlots + 2);
    EXPECT_EQ(reg.get<DeformedSplats>(cloud).inverted, 0u);  // a small stretch inverts nothing
    ffd_release_gpu(reg);
    reg.erase_resource<gfx::GpuSplatStore>();
}

// GPU-resident deformation phase: after the first frame (which computes the cloud's rest box), lattice
// edits cost the CPU nothing per splat and nothing waits for the GPU; the inverted count arrives a few
// frames later through a fence and equals the CPU path's. Bounds equal the CPU path's and cover the
// GPU's output.
TEST_F(FfdGl, GpuPathTouchesNoPerSplatCpuArrayAfterTheFirstFrame) {
    ecs::Registry reg;
    const ffd::test::Cloud c = ffd::test::fibonacci_sphere(4000);
    // Covers the upper part of the sphere only: outside points pass through (bounds need the rest box).
    const auto [cloud, le] = add_cloud_and_lattice(
        reg, c,
        ffd::make_lattice({-1.1, -0.2, -1.1},
                          {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 1.4, 0), glm::dvec3(0, 0, 2.2)}, {4, 4, 4}));
    auto& settings = reg.set_resource<FfdSettings>();
    settings.force_gpu = true;
    auto& store = upload_rest(reg, cloud, c);
    ffd_system(reg, {});
    ASSERT_EQ(reg.resource<FfdStats>().gpu_runs, 1u);
    EXPECT_EQ(reg.resource<FfdStats>().cpu_splat_passes, 1u);  // the rest box, once
    for (int frame = 0; frame < 6; ++frame) {
        Lattice& l = reg.patch<Lattice>(le);
        ffd::twist_graded(l, ffd::all_control_points(l), {0, 1, 0}, 0.2, glm::dvec3(0.0));
        ffd_system(reg, {});
    }
    EXPECT_EQ(reg.resource<FfdStats>().gpu_runs, 7u);
    EXPECT_EQ(reg.resource<FfdStats>().cpu_splat_passes, 1u);
    EXPECT_EQ(reg.resource<FfdStats>().gpu_sync_readbacks, 0u);
    // A mirror in x on top: the splats inside invert. Their count arrives once the GPU is done.
    {
        Lattice& l = reg.patch<Lattice>(le);
        for (std::size_t i = 0; i < l.size(); ++i) l.current[i].x = -l.current[i].x;
    }
    ffd_system(reg, {});
    const DeformedSplats& d = reg.get<DeformedSplats>(cloud);
    const std::uint64_t version = d.version;
    glFinish();           // the test waits, the system never does
    ffd_system(reg, {});  // nothing changed: no dispatch, but the statistics are collected
    EXPECT_EQ(reg.resource<FfdStats>().gpu_runs, 8u);
    EXPECT_EQ(d.version, version);
    EXPECT_EQ(d.inverted_version, version);
    EXPECT_EQ(reg.resource<FfdStats>().gpu_sync_readbacks, 0u);
    EXPECT_EQ(reg.resource<FfdStats>().cpu_splat_passes, 1u);
    // Against the CPU path: same inverted count, same bounds, and the GPU output lies inside them.
    std::vector<gpu::GpuSplat> back(c.size());
    glGetNamedBufferSubData(store.clouds[cloud].deformed.id(), 0,
                            GLsizeiptr(back.size() * sizeof(gpu::GpuSplat)), back.data());
    const std::size_t gpu_inverted = d.inverted;
    const glm::dvec3 gpu_lo = d.bounds_min, gpu_hi = d.bounds_max;
    settings.force_cpu = true;
    ffd_system(reg, {});
    EXPECT_EQ(reg.resource<FfdStats>().cpu_runs, 1u);
    const DeformedSplats& cpu = reg.get<DeformedSplats>(cloud);
    EXPECT_GT(cpu.inverted, 100u);
    EXPECT_EQ(gpu_inverted, cpu.inverted);
    EXPECT_EQ(gpu_lo, cpu.bounds_min);
    EXPECT_EQ(gpu_hi, cpu.bounds_max);
    std::size_t moved = 0;
    for (std::size_t i = 0; i < c.size(); ++i) {
        const glm::dvec3 p(back[i].center[0], back[i].center[1], back[i].center[2]);
        moved += glm::length(p - glm::dvec3(c.p[i])) > 1e-3;
        ASSERT_TRUE(glm::all(glm::greaterThanEqual(p, gpu_lo)) && glm::all(glm::lessThanEqual(p, gpu_hi)))
            << i;
    }
    EXPECT_GT(moved, 1000u);
    ffd_release_gpu(reg);
    reg.erase_resource<gfx::GpuSplatStore>();
}

TEST_F(FfdGl, SoftwareRasterizerGetsTheCpuPathUnlessTheGpuIsForced) {
    const std::string renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    if (renderer.find("llvmpipe") == std::string::npos && renderer.find("softpipe") == std::string::npos)
        GTEST_SKIP() << "hardware renderer: " << renderer;
    ecs::Registry reg;
    const ffd::test::Cloud c = ffd::test::fibonacci_sphere(2000);
    const auto [cloud, le] = add_cloud_and_lattice(reg, c, box_lattice({3, 3, 3}));
    auto& settings = reg.set_resource<FfdSettings>();
    auto& store = reg.set_resource<gfx::GpuSplatStore>();
    gfx::GpuSplats& s = store.clouds[cloud];
    s.rest = gfx::Buffer::create("test.rest");
    glNamedBufferData(s.rest.id(), GLsizeiptr(c.size() * sizeof(gpu::GpuSplat)), nullptr, GL_STATIC_DRAW);
    s.count = std::uint32_t(c.size());
    s.rest_version = reg.version<SplatCloud>(cloud);
    ffd::stretch(reg.patch<Lattice>(le), {0}, {0.2, 0, 0});
    ffd_system(reg, {});
    EXPECT_EQ(reg.resource<FfdStats>().cpu_runs, 1u);
    EXPECT_EQ(reg.resource<FfdStats>().gpu_runs, 0u);
    EXPECT_TRUE(reg.get<DeformedSplats>(cloud).cpu_valid);
    EXPECT_EQ(s.state, gfx::Residency::deformed_cpu);  // the CPU output was uploaded for the render
    EXPECT_EQ(s.deformed_version, 1u);
    settings.force_gpu = true;  // a policy change re-runs the cloud on the compute pass
    ffd_system(reg, {});
    EXPECT_EQ(reg.resource<FfdStats>().gpu_runs, 1u);
    EXPECT_TRUE(ffd::output_on_gpu(reg, cloud));
    EXPECT_EQ(s.state, gfx::Residency::deformed_gpu);
    EXPECT_EQ(s.deformed_version, 2u);
    ffd_release_gpu(reg);
    reg.erase_resource<gfx::GpuSplatStore>();
}

TEST_F(FfdGl, PaperModeDrawsTheSameImageAsTheComputePass) {
    auto paper = ffd::PaperModeRenderer::create();
    ASSERT_TRUE(paper.ok()) << paper.message();
    auto gpu = ffd::GpuDeformer::create();
    ASSERT_TRUE(gpu.ok());
    const ffd::test::Cloud c = ffd::test::fibonacci_sphere(20000);
    std::vector<gpu::GpuSplat> packed(c.size());
    for (std::size_t i = 0; i < c.size(); ++i)
        packed[i] = {{c.p[i].x, c.p[i].y, c.p[i].z, 0},
                     {c.n[i].x, c.n[i].y, c.n[i].z, 1},
                     {c.u[i].x, c.u[i].y, c.u[i].z, 0},
                     {c.v[i].x, c.v[i].y, c.v[i].z, 0}};
    const GLsizeiptr bytes = GLsizeiptr(packed.size() * sizeof(gpu::GpuSplat));
    gfx::Buffer rest = gfx::Buffer::create("test.rest"), deformed = gfx::Buffer::create("test.deformed");
    glNamedBufferData(rest.id(), bytes, packed.data(), GL_STATIC_DRAW);
    glNamedBufferData(deformed.id(), bytes, nullptr, GL_DYNAMIC_COPY);
    Lattice l = ffd::make_lattice(glm::dvec3(-1.1),
                                  {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)},
                                  {10, 10, 10});
    ffd::twist_graded(l, ffd::all_control_points(l), {0, 1, 0}, 1.2, glm::dvec3(0.0));
    ffd::stretch(l, ffd::select_range(l, {0, 8, 0}, {10, 10, 10}), {0.3, 0.2, 0});
    ASSERT_TRUE(gpu->dispatch(l, 1, 1, {}, rest.id(), deformed.id(), std::uint32_t(c.size())).ok());
    auto target = gfx::RenderTarget::create(
        {.label = "test.paper", .width = 128, .height = 128, .color = {{"color", gfx::ColorFormat::rgba8}}});
    ASSERT_TRUE(target.ok()) << target.message();
    const glm::mat4 vp = glm::mat4(glm::scale(glm::mat4(1.0f), glm::vec3(0.6f, 0.6f, -0.3f)));
    const float black[4] = {0, 0, 0, 1};
    auto render = [&](bool paper_mode) {
        target->bind();
        target->clear_color("color", black);
        target->clear_depth();
        if (paper_mode) {
            EXPECT_TRUE(paper->draw(l, 1, {}, rest.id(), std::uint32_t(c.size()), vp, 2.0f).ok());
        } else {
            paper->draw_deformed(deformed.id(), std::uint32_t(c.size()), vp, 2.0f);
        }
        return target->read_rgba8("color");
    };
    const auto a = render(true), b = render(false);
    std::size_t covered = 0, different = 0;
    for (std::size_t i = 0; i < a.size(); i += 4) {
        covered += a[i] > 0;
        different += std::abs(int(a[i]) - int(b[i])) > 2;
    }
    EXPECT_GT(covered, 128u * 128u / 5);  // the deformed sphere covers a good part of the image
    EXPECT_LT(different, covered / 200);  // same splats, same place, same shading (float rounding aside)
    // And it is deformed: the undeformed sphere differs.
    paper->draw_deformed(rest.id(), 0, vp, 2.0f);
    const auto und = [&] {
        target->bind();
        target->clear_color("color", black);
        target->clear_depth();
        paper->draw_deformed(rest.id(), std::uint32_t(c.size()), vp, 2.0f);
        return target->read_rgba8("color");
    }();
    std::size_t moved = 0;
    for (std::size_t i = 0; i < a.size(); i += 4) moved += (a[i] > 0) != (und[i] > 0);
    EXPECT_GT(moved, 200u);
}

}  // namespace
}  // namespace sffd
