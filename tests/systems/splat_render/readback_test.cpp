// The frame path never waits for the GPU: render_system reads the compute cull's visible counts
// through fences polled with a zero timeout and a persistently mapped ring, so in steady state a frame makes
// no synchronous read-back, no glFinish and no map, and flushes once (after its counts' fence, which a
// headless loop has no swap to submit); the counts still arrive, a few frames late.
//
// The GL entry points that would stall are interposed here: this executable defines them, so the renderer's
// calls (a static library linked into it) land here, are counted, and go on to the real driver (RTLD_NEXT).
#include <dlfcn.h>

#include <atomic>
#include <vector>

#include "runtime/gfx/residency.h"
#include "systems/ffd/components.h"
#include "systems/ffd/ffd_system.h"
#include "systems/ffd/lattice.h"
#include "systems/ffd/operations.h"
#include "tests/systems/splat_render/gl_fixture.h"
#include "tests/systems/splat_render/test_scenes.h"
#include "systems/residency/residency_system.h"

namespace {

std::atomic<int> g_buffer_reads{0};    // glGet(Named)BufferSubData
std::atomic<int> g_finishes{0};        // glFinish
std::atomic<int> g_blocking_waits{0};  // glClientWaitSync with a timeout, glWaitSync
std::atomic<int> g_maps{0};            // glMap(Named)Buffer(Range)
std::atomic<int> g_flushes{0};         // glFlush, glClientWaitSync with GL_SYNC_FLUSH_COMMANDS_BIT

template <class Fn>
Fn real(const char* name) {
    return reinterpret_cast<Fn>(dlsym(RTLD_NEXT, name));
}

// What a window's swap chain does to a frame loop: at most two frames in flight, the CPU waiting for the
// older one. A headless loop without it runs ahead of a fast GPU without bound, and counts read "a few
// frames late" arrive as late as the driver queues. The test's own waits go to the driver directly, past
// the counters.
class SwapThrottle {
public:
    ~SwapThrottle() {
        for (GLsync f : m_fences) glDeleteSync(f);
    }
    void frame_done() {
        m_fences.push_back(glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0));
        if (m_fences.size() <= 2) return;
        static const auto wait = real<PFNGLCLIENTWAITSYNCPROC>("glClientWaitSync");
        wait(m_fences.front(), GL_SYNC_FLUSH_COMMANDS_BIT, 5'000'000'000ull);
        glDeleteSync(m_fences.front());
        m_fences.erase(m_fences.begin());
    }

private:
    std::vector<GLsync> m_fences;
};

}  // namespace

extern "C" {
void APIENTRY glGetNamedBufferSubData(GLuint buffer, GLintptr offset, GLsizeiptr size, void* data) {
    ++g_buffer_reads;
    static const auto fn = real<PFNGLGETNAMEDBUFFERSUBDATAPROC>("glGetNamedBufferSubData");
    fn(buffer, offset, size, data);
}
void APIENTRY glGetBufferSubData(GLenum target, GLintptr offset, GLsizeiptr size, void* data) {
    ++g_buffer_reads;
    static const auto fn = real<PFNGLGETBUFFERSUBDATAPROC>("glGetBufferSubData");
    fn(target, offset, size, data);
}
void APIENTRY glFinish() {
    ++g_finishes;
    static const auto fn = real<PFNGLFINISHPROC>("glFinish");
    fn();
}
GLenum APIENTRY glClientWaitSync(GLsync sync, GLbitfield flags, GLuint64 timeout) {
    if (timeout != 0) ++g_blocking_waits;
    if (flags & GL_SYNC_FLUSH_COMMANDS_BIT) ++g_flushes;
    static const auto fn = real<PFNGLCLIENTWAITSYNCPROC>("glClientWaitSync");
    return fn(sync, flags, timeout);
}
void APIENTRY glFlush() {
    ++g_flushes;
    static const auto fn = real<PFNGLFLUSHPROC>("glFlush");
    fn();
}
void APIENTRY glWaitSync(GLsync sync, GLbitfield flags, GLuint64 timeout) {
    ++g_blocking_waits;
    static const auto fn = real<PFNGLWAITSYNCPROC>("glWaitSync");
    fn(sync, flags, timeout);
}
void* APIENTRY glMapNamedBufferRange(GLuint buffer, GLintptr offset, GLsizeiptr length, GLbitfield access) {
    ++g_maps;
    static const auto fn = real<PFNGLMAPNAMEDBUFFERRANGEPROC>("glMapNamedBufferRange");
    return fn(buffer, offset, length, access);
}
void* APIENTRY glMapBufferRange(GLenum target, GLintptr offset, GLsizeiptr length, GLbitfield access) {
    ++g_maps;
    static const auto fn = real<PFNGLMAPBUFFERRANGEPROC>("glMapBufferRange");
    return fn(target, offset, length, access);
}
void* APIENTRY glMapNamedBuffer(GLuint buffer, GLenum access) {
    ++g_maps;
    static const auto fn = real<PFNGLMAPNAMEDBUFFERPROC>("glMapNamedBuffer");
    return fn(buffer, access);
}
void* APIENTRY glMapBuffer(GLenum target, GLenum access) {
    ++g_maps;
    static const auto fn = real<PFNGLMAPBUFFERPROC>("glMapBuffer");
    return fn(target, access);
}
}

using namespace sffd;
using namespace sffd::render;
using namespace sffd::render::test;

namespace {

class Readback_ : public GlRenderTest {
protected:
    void gpu_deformation_frames_never_wait(RasterPath raster);
};

TEST_F(Readback_, SteadyStateFramesNeverWaitAndCountsStillArrive) {
    add_camera(2.6);
    add_light({-0.5f, -0.4f, -0.6f}, 0.15f);
    add_cloud(fibonacci_sphere(20000));
    for (CullPath path : {CullPath::compute, CullPath::cpu}) {
        const char* what = path == CullPath::compute ? "compute cull" : "cpu cull";
        // Reference counts: a timed frame (glFinish after each pass) has this frame's counts.
        render(Quality::hq, 320, 240, true, path);
        const RenderStats reference = reg.resource<RenderStats>();
        ASSERT_TRUE(reference.counts_valid) << what;
        ASSERT_EQ(reference.counts_frame, reference.frame) << what;
        ASSERT_GT(reference.visible_points, 1000u) << what;
        ASSERT_LT(reference.visible_points, 20000u) << what;

        RenderSettings s = reg.resource<RenderSettings>();
        s.time_passes = false;
        s.aux_outputs = false;
        reg.set_resource<RenderSettings>(s);
        render_system(reg, FrameContext{.frame = 100});  // warm-up (a new draw path may allocate)
        g_buffer_reads = g_finishes = g_blocking_waits = g_maps = g_flushes = 0;
        const std::uint64_t first = 101, last = 130;
        std::uint64_t arrived = 0;
        SwapThrottle swap;
        for (std::uint64_t f = first; f <= last; ++f) {
            render_system(reg, FrameContext{.frame = f});
            swap.frame_done();
            const RenderStats& st = reg.resource<RenderStats>();
            EXPECT_EQ(path == CullPath::compute ? st.compute_culled_clouds : st.cpu_culled_clouds, 1u)
                << what;
            ASSERT_TRUE(st.counts_valid) << what;
            EXPECT_LE(st.counts_frame, f) << what;
            if (st.counts_frame >= first) {
                ++arrived;
                EXPECT_EQ(st.visible_points, reference.visible_points)
                    << what << ", frame " << st.counts_frame;
                EXPECT_EQ(st.visible_quads, reference.visible_quads) << what << ", frame " << st.counts_frame;
            }
        }
        EXPECT_EQ(g_buffer_reads.load(), 0) << what;
        EXPECT_EQ(g_finishes.load(), 0) << what;
        EXPECT_EQ(g_blocking_waits.load(), 0) << what;
        // The CPU cull reads the resident splats in place: one read mapping of the draw buffer per frame
        // (gfx::read_splats_on_cpu; on a software rasterizer a pointer into host memory, which waits only
        // for commands still writing that buffer, and a steady-state frame issues none); elsewhere none.
        const bool maps = path == CullPath::cpu && gfx::cpu_reads_in_place();
        EXPECT_EQ(g_maps.load(), maps ? int(last - first + 1) : 0) << what;
        EXPECT_LE(g_flushes.load(), int(last - first + 1)) << what;
        // Counts of the steady-state frames did come back (not only the reference frame's).
        EXPECT_GT(arrived, (last - first) / 2) << what;
        EXPECT_GE(reg.resource<RenderStats>().counts_frame + 8, last) << what;
    }
}

// The same with the FFD compute pass in the frame (ffd_system's GPU path, forced on llvmpipe): a lattice
// edited every frame is re-uploaded and the cloud re-deformed on the GPU, the compute cull draws it, and
// still nothing waits; the deformer's statistics arrive late through fences (DeformedSplats::
// inverted_version moves on), and neither system makes a pass over the splats on the CPU. With the compute
// rasteriser (raster_path compute) the same holds, and its hybrid counts arrive through the ring too.
void Readback_::gpu_deformation_frames_never_wait(RasterPath raster) {
    add_camera(2.6);
    add_light({-0.5f, -0.4f, -0.6f}, 0.15f);
    const ecs::Entity cloud = add_cloud(fibonacci_sphere(20000));
    const ecs::Entity le = add_lattice(cloud);
    reg.set_resource<FfdSettings>().force_gpu = true;
    RenderSettings s;
    s.width = 320, s.height = 240, s.cull_path = CullPath::compute, s.raster_path = raster;
    reg.set_resource<RenderSettings>(s);
    const auto frame = [&](std::uint64_t f) {
        ffd::twist_graded(reg.patch<Lattice>(le), ffd::all_control_points(reg.get<Lattice>(le)), {0, 1, 0},
                          0.02, glm::dvec3(0.0));
        residency_system(reg, FrameContext{.frame = f});
        ffd_system(reg, FrameContext{.frame = f});
        render_system(reg, FrameContext{.frame = f});
    };
    residency_system(reg, FrameContext{.frame = 1});  // the rest buffer the compute pass reads
    render_system(reg, FrameContext{.frame = 1});
    SwapThrottle swap;
    for (std::uint64_t f = 2; f < 10; ++f) {  // warm-up: programs, buffers, read-back slots
        frame(f);
        swap.frame_done();
    }
    ASSERT_TRUE(ffd::output_on_gpu(reg, cloud));
    const FfdStats before = reg.resource<FfdStats>();
    const std::uint64_t stats_before = reg.get<DeformedSplats>(cloud).inverted_version;
    g_buffer_reads = g_finishes = g_blocking_waits = g_maps = g_flushes = 0;
    std::uint32_t render_cpu_passes = 0;
    for (std::uint64_t f = 10; f < 40; ++f) {
        frame(f);
        swap.frame_done();
        const RenderStats& st = reg.resource<RenderStats>();
        render_cpu_passes += st.cpu_splat_passes;
        EXPECT_EQ(st.compute_rastered_clouds, raster == RasterPath::compute ? 1u : 0u);
    }
    EXPECT_EQ(render_cpu_passes, 0u);
    EXPECT_EQ(g_buffer_reads.load(), 0);
    EXPECT_EQ(g_finishes.load(), 0);
    EXPECT_EQ(g_blocking_waits.load(), 0);
    EXPECT_EQ(g_maps.load(), 0);
    // The render's one flush a frame and no other: the deformer's statistics fences ride on it (a flush of
    // its own each frame would be CPU time charged to the deformation).
    EXPECT_LE(g_flushes.load(), 30);
    const FfdStats& after = reg.resource<FfdStats>();
    EXPECT_EQ(after.gpu_runs, before.gpu_runs + 30);
    EXPECT_EQ(after.cpu_runs, before.cpu_runs);
    EXPECT_EQ(after.cpu_splat_passes, before.cpu_splat_passes);
    EXPECT_EQ(after.gpu_sync_readbacks, before.gpu_sync_readbacks);
    EXPECT_GT(reg.get<DeformedSplats>(cloud).inverted_version, stats_before);  // statistics still arrive
    EXPECT_EQ(reg.resource<RenderStats>().compute_culled_clouds, 1u);
    EXPECT_TRUE(reg.resource<RenderStats>().counts_valid);
    EXPECT_GE(reg.resource<RenderStats>().counts_frame, 30u);  // the counts kept arriving
    ffd_release_gpu(reg);
}

TEST_F(Readback_, GpuDeformationFramesNeverWait) { gpu_deformation_frames_never_wait(RasterPath::raster); }

TEST_F(Readback_, GpuDeformationFramesNeverWaitOnTheComputeRasteriser) {
    gpu_deformation_frames_never_wait(RasterPath::compute);
}

// The interposition is live: a read-back in this process is seen (else the test above could not fail).
TEST_F(Readback_, InterposedEntryPointsSeeTheCalls) {
    GLuint b = 0;
    glCreateBuffers(1, &b);
    const std::uint32_t v = 7;
    glNamedBufferData(b, sizeof v, &v, GL_STATIC_DRAW);
    const int before = g_buffer_reads.load();
    std::uint32_t got = 0;
    glGetNamedBufferSubData(b, 0, sizeof got, &got);
    glDeleteBuffers(1, &b);
    EXPECT_EQ(got, 7u);
    EXPECT_EQ(g_buffer_reads.load(), before + 1);
}

}  // namespace
