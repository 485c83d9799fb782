// The FFD compute pass over a cloud larger than GL_MAX_SHADER_STORAGE_BLOCK_SIZE (simulated with a small
// limit, gfx::ScopedLimits): it runs in element ranges (runtime/gfx/ssbo_batch.h) and deforms exactly as
// one dispatch does. Exact equality holds on any implementation: the same program computes each splat
// from the same inputs; only which range a splat is bound in differs. The batches make no buffer writes of
// their own (each has its block in the one upload): a write between two dispatches lands in storage the
// first one reads, and a driver may make the CPU wait for it.
//
// glNamedBufferSubData and glBufferSubData are interposed in this executable (counted, then passed to the
// driver through RTLD_NEXT), as tests/systems/splat_render/readback_test.cpp does for the render's waits.
#include <dlfcn.h>
#include <gtest/gtest.h>

#include <atomic>
#include <string>
#include <vector>

#include "runtime/gfx/barrier.h"
#include "runtime/gfx/context.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/limits.h"
#include "systems/ffd/ffd_gpu.h"
#include "systems/ffd/lattice.h"
#include "systems/ffd/operations.h"
#include "tests/systems/ffd/test_util.h"
#include "tests/test_util/headless_gl.h"

namespace {
std::atomic<int> g_buffer_writes{0};
template <class Fn>
Fn real(const char* name) {
    return reinterpret_cast<Fn>(dlsym(RTLD_NEXT, name));
}
}  // namespace

extern "C" {
void APIENTRY glNamedBufferSubData(GLuint buffer, GLintptr offset, GLsizeiptr size, const void* data) {
    ++g_buffer_writes;
    static const auto fn = real<PFNGLNAMEDBUFFERSUBDATAPROC>("glNamedBufferSubData");
    fn(buffer, offset, size, data);
}
void APIENTRY glBufferSubData(GLenum target, GLintptr offset, GLsizeiptr size, const void* data) {
    ++g_buffer_writes;
    static const auto fn = real<PFNGLBUFFERSUBDATAPROC>("glBufferSubData");
    fn(target, offset, size, data);
}
}

namespace sffd {
namespace {

class FfdBatchGl : public test::HeadlessGlTest {};

struct Deformed {
    std::vector<glm::vec3> p, n, u, v;
    ffd::DeformStats stats;
};

Result<Deformed> deform(ffd::GpuDeformer& gpu, const Lattice& l, const ffd::test::Cloud& c) {
    const std::size_t n = c.size();
    Deformed d;
    d.p.resize(n), d.n.resize(n), d.u.resize(n), d.v.resize(n);
    const ffd::PointsIn in{c.p.data(), c.n.data(), c.u.data(), c.v.data(), n, c.origin};
    auto st = gpu.deform(l, in, {d.p.data(), d.n.data(), d.u.data(), d.v.data()});
    if (!st) return st.error();
    d.stats = *st;
    return d;
}

TEST_F(FfdBatchGl, CloudOverTheBlockSizeDeformsInRangesExactlyAsOneDispatch) {
    if (IsSkipped() || HasFatalFailure()) return;
    auto gpu = ffd::GpuDeformer::create();
    ASSERT_TRUE(gpu.ok()) << gpu.message();
    const ffd::test::Cloud c = ffd::test::fibonacci_sphere(5000);
    // B-spline: the generic program (no per-shape compile).
    Lattice l = ffd::make_lattice(c.origin + glm::dvec3(-1.1),
                                  {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)},
                                  {4, 5, 3}, LatticeBasis::bspline);
    ffd::twist_graded(l, ffd::all_control_points(l), {0, 1, 0}, 0.6, c.origin);
    (void)deform(*gpu, l, c);  // warm-up: the program and the scratch buffers
    g_buffer_writes = 0;
    auto whole = deform(*gpu, l, c);
    ASSERT_TRUE(whole) << whole.message();
    const int whole_writes = g_buffer_writes.exchange(0);
    EXPECT_GT(whole_writes, 0) << "the interposed entry points saw no call";

    gfx::GlLimits small = gfx::limits();
    small.max_ssbo_block_size = 997 * 64;  // about 1,000 splats a batch: 6 batches, the last one short
    const std::uint64_t errors = gfx::debug_error_count();
    gfx::BarrierLog log;
    auto batched = [&] {
        gfx::ScopedLimits scope(small);
        return deform(*gpu, l, c);
    }();
    ASSERT_TRUE(batched) << batched.message();
    EXPECT_EQ(g_buffer_writes.load(), whole_writes) << "writes between the batches' dispatches";
    EXPECT_EQ(gfx::debug_error_count(), errors) << "a range bound past the buffer or misaligned";
    // One dispatch's barriers, whatever the number of batches (the ranges are disjoint).
    EXPECT_EQ(log.count("ffd.dispatch"), 1u);
    EXPECT_EQ(batched->stats.inside, whole->stats.inside);
    EXPECT_EQ(batched->stats.inverted, whole->stats.inverted);
    EXPECT_EQ(whole->stats.inside, c.size());
    std::size_t moved = 0;
    for (std::size_t i = 0; i < c.size(); ++i) {
        ASSERT_EQ(batched->p[i], whole->p[i]) << i;
        ASSERT_EQ(batched->n[i], whole->n[i]) << i;
        ASSERT_EQ(batched->u[i], whole->u[i]) << i;
        ASSERT_EQ(batched->v[i], whole->v[i]) << i;
        moved += whole->p[i] != c.p[i];
    }
    EXPECT_GT(moved, c.size() / 2);  // the splats of every batch were deformed, not copied
}

TEST_F(FfdBatchGl, RefusesNamingTheLimitWhenNotOneSplatFits) {
    if (IsSkipped() || HasFatalFailure()) return;
    auto gpu = ffd::GpuDeformer::create();
    ASSERT_TRUE(gpu.ok()) << gpu.message();
    const ffd::test::Cloud c = ffd::test::fibonacci_sphere(100);
    const Lattice l = ffd::make_lattice(c.origin + glm::dvec3(-1.1),
                                        {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)},
                                        {3, 3, 3}, LatticeBasis::bspline);
    gfx::GlLimits small = gfx::limits();
    small.max_ssbo_block_size = 32;  // less than one 64-byte splat
    gfx::ScopedLimits scope(small);
    auto r = deform(*gpu, l, c);
    ASSERT_FALSE(r);
    EXPECT_NE(r.message().find("GL_MAX_SHADER_STORAGE_BLOCK_SIZE"), std::string::npos) << r.message();
}

}  // namespace
}  // namespace sffd
