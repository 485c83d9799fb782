// Each GPU pass issues the memory barriers GL 4.5 §7.12.2 requires for how its output is used next
// (runtime/gfx/barrier.h records them): llvmpipe finishes every command before the next, so a missing bit
// never shows in an image here, only on a hardware GPU. And the passes whose storage blocks would exceed
// GL_MAX_SHADER_STORAGE_BLOCK_SIZE take their fallback paths (storage_limits.h), simulated with a small
// limit (gfx::ScopedLimits).
#include <algorithm>
#include <string>
#include <vector>

#include "runtime/core/log.h"
#include "runtime/gfx/barrier.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/limits.h"
#include "systems/ffd/ffd_gpu.h"
#include "systems/ffd/lattice.h"
#include "tests/systems/splat_render/gl_fixture.h"
#include "tests/systems/splat_render/test_scenes.h"

using namespace sffd;
using namespace sffd::render;
using namespace sffd::render::test;

namespace {

constexpr std::uint32_t vertex_attrib = GL_VERTEX_ATTRIB_ARRAY_BARRIER_BIT,
                        element = GL_ELEMENT_ARRAY_BARRIER_BIT, storage = GL_SHADER_STORAGE_BARRIER_BIT,
                        command = GL_COMMAND_BARRIER_BIT, update = GL_BUFFER_UPDATE_BARRIER_BIT;

// Index of the first record at `site` at or after `from` (records().size() when none).
std::size_t find_site(const gfx::BarrierLog& log, std::string_view site, std::size_t from = 0) {
    const auto& r = log.records();
    for (std::size_t i = from; i < r.size(); ++i)
        if (r[i].site == site) return i;
    return r.size();
}

std::string describe(const gfx::BarrierLog& log) {
    std::string out;
    for (const gfx::BarrierRecord& r : log.records())
        out += r.site + " " + gfx::barrier_bit_names(r.bits) + "\n";
    return out;
}

class Barriers_ : public GlRenderTest {
protected:
    void frame(Quality q, CullPath cull, RasterPath raster, int w = 160, int h = 120) {
        RenderSettings s;
        s.quality = q, s.width = w, s.height = h, s.cull_path = cull, s.raster_path = raster;
        reg.set_resource<RenderSettings>(s);
        residency_system(reg, FrameContext{});  // the clouds are uploaded in the phase before rendering
        render_system(reg, FrameContext{});
    }
};

// Compute cull and compute rasteriser, two frames: every barrier the spec asks for, in order.
TEST_F(Barriers_, ComputeCullAndRasteriserIssueTheRequiredBits) {
    add_camera(3.0);
    add_light({-0.5f, -0.4f, -0.6f});
    add_cloud(fibonacci_sphere(5000, 1.0, 0.8));
    gfx::BarrierLog log;
    for (int f = 0; f < 2; ++f) frame(Quality::hq, CullPath::compute, RasterPath::compute);
    ASSERT_EQ(reg.resource<RenderStats>().compute_culled_clouds, 1u);
    ASSERT_EQ(reg.resource<RenderStats>().compute_rastered_clouds, 1u);
    const std::string all = describe(log);
    // The cull's records are fetched as vertex attributes (the bit the pass once lacked), quads and
    // records read as SSBOs, the commands drawn indirectly and copied into the counts ring.
    EXPECT_TRUE(log.issued("render.cull", vertex_attrib | storage | command | update)) << all;
    // Write-after-read: the last frame's draws read what this frame's cull overwrites.
    EXPECT_TRUE(log.issued("render.cull.reuse", storage | update)) << all;
    // The big lists feed indexed indirect draws over the records; the counters are copied.
    EXPECT_TRUE(log.issued("render.compute.visibility", storage | command | element | vertex_attrib | update))
        << all;
    EXPECT_TRUE(log.issued("render.compute.visibility.reuse", update | storage)) << all;
    EXPECT_TRUE(log.issued("render.compute.attribute", storage)) << all;
    EXPECT_TRUE(log.issued("render.compute.resolve", storage)) << all;
    EXPECT_TRUE(log.issued("render.counts", update)) << all;
    // Order within each frame: reuse, cull, compute visibility, then the counts copy (its source is
    // written by both), then the attribute pass.
    std::size_t at = 0;
    for (int f = 0; f < 2; ++f) {
        const std::size_t reuse = find_site(log, "render.cull.reuse", at),
                          cull = find_site(log, "render.cull", at),
                          vis = find_site(log, "render.compute.visibility", at),
                          counts = find_site(log, "render.counts", at),
                          attribute = find_site(log, "render.compute.attribute", at);
        ASSERT_LT(attribute, log.records().size()) << "frame " << f << "\n" << all;
        EXPECT_LT(reuse, cull) << all;
        EXPECT_LT(cull, vis) << all;
        EXPECT_LT(vis, counts) << all;
        EXPECT_LT(counts, attribute) << all;
        at = attribute + 1;
    }
}

// The raster path with the compute cull: the counts copy follows the cull's barrier.
TEST_F(Barriers_, RasterPathCountsFollowTheCull) {
    add_camera(3.0);
    add_cloud(fibonacci_sphere(3000, 1.0, 0.8));
    for (Quality q : {Quality::preview, Quality::hq}) {
        gfx::BarrierLog log;
        frame(q, CullPath::compute, RasterPath::raster);
        const std::string all = describe(log);
        EXPECT_TRUE(log.issued("render.cull", vertex_attrib | storage | command | update)) << all;
        EXPECT_LT(find_site(log, "render.cull"), find_site(log, "render.counts")) << all;
        EXPECT_LT(find_site(log, "render.counts"), log.records().size()) << all;
        EXPECT_EQ(log.count("render.compute.visibility"), 0u) << all;
    }
}

// The CPU cull uploads into buffers the compute cull of an earlier frame may have written: the reuse
// barrier (BUFFER_UPDATE) comes first there too.
TEST_F(Barriers_, CpuCullWaitsForEarlierShaderWrites) {
    add_camera(3.0);
    add_cloud(fibonacci_sphere(3000, 1.0, 0.8));
    frame(Quality::hq, CullPath::compute, RasterPath::raster);
    gfx::BarrierLog log;
    frame(Quality::hq, CullPath::cpu, RasterPath::raster);
    ASSERT_EQ(reg.resource<RenderStats>().cpu_culled_clouds, 1u);
    EXPECT_TRUE(log.issued("render.cull.reuse", update)) << describe(log);
}

// The FFD compute pass: its output is next read as SSBOs (cull), vertex attributes and read-backs, and it
// overwrites what the last frame read.
TEST_F(Barriers_, FfdDispatchIssuesTheRequiredBits) {
    auto gpu = ffd::GpuDeformer::create();
    ASSERT_TRUE(gpu.ok()) << gpu.message();
    const SplatCloud c = fibonacci_sphere(500, 1.0, 0.8);
    Lattice l = ffd::make_lattice(
        glm::dvec3(-1.1), {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)}, {3, 3, 3});
    std::vector<glm::vec3> p(c.size()), n(c.size()), u(c.size()), v(c.size());
    gfx::BarrierLog log;
    auto st = gpu->deform(
        l,
        {c.positions.data(), c.normals.data(), c.axis_u.data(), c.axis_v.data(), c.size(), glm::dvec3(0.0)},
        {p.data(), n.data(), u.data(), v.data()});
    ASSERT_TRUE(st.ok()) << st.message();
    const std::string all = describe(log);
    EXPECT_TRUE(log.issued("ffd.dispatch", storage | vertex_attrib | update)) << all;
    EXPECT_TRUE(log.issued("ffd.dispatch.reuse", storage)) << all;
    EXPECT_LT(find_site(log, "ffd.dispatch.reuse"), find_site(log, "ffd.dispatch")) << all;
}

// Sums of 36 bytes per pixel over the block-size limit: the frame stays on the raster path, with a warning
// naming the buffer and the limit, and still renders the cloud.
TEST_F(Barriers_, ComputeRasteriserFallsBackWhenItsBuffersExceedTheBlockSize) {
    add_camera(3.0);
    add_cloud(fibonacci_sphere(1000, 1.0, 0.8));
    gfx::GlLimits small = gfx::limits();
    small.max_ssbo_block_size = 500 * 1000;  // sums: 173 x 131 px x 36 bytes = 815,868; records: 192,000
    log::ScopedLogCapture capture;
    {
        gfx::ScopedLimits scope(small);
        frame(Quality::hq, CullPath::compute, RasterPath::compute, 173, 131);
    }
    const RenderStats& st = reg.resource<RenderStats>();
    EXPECT_EQ(st.compute_rastered_clouds, 0u);
    EXPECT_TRUE(capture.contains(
        "render.compute.sums: 815868 bytes exceed GL_MAX_SHADER_STORAGE_BLOCK_SIZE (500000)"));
    frame(Quality::hq, CullPath::compute, RasterPath::compute, 173, 131);
    EXPECT_EQ(reg.resource<RenderStats>().compute_rastered_clouds, 1u);  // the real limit allows it
}

// The sprite records the compute cull writes (96 bytes per splat) over the limit: the automatic cull path
// takes the CPU cull on any renderer; a forced compute cull skips the cloud with a warning instead of
// writing past the block.
TEST_F(Barriers_, ComputeCullFallsBackWhenItsRecordsExceedTheBlockSize) {
    add_camera(3.0);
    add_cloud(fibonacci_sphere(2345, 1.0, 0.8));
    gfx::GlLimits small = gfx::limits();
    small.max_ssbo_block_size = 200 * 1000;  // records: 2345 x 96 = 225,120 bytes
    log::ScopedLogCapture capture;
    gfx::ScopedLimits scope(small);
    frame(Quality::hq, CullPath::automatic, RasterPath::raster);
    EXPECT_EQ(reg.resource<RenderStats>().cpu_culled_clouds, 1u);
    EXPECT_EQ(reg.resource<RenderStats>().compute_culled_clouds, 0u);
    frame(Quality::hq, CullPath::compute, RasterPath::raster);
    EXPECT_EQ(reg.resource<RenderStats>().compute_culled_clouds, 0u);
    EXPECT_TRUE(capture.contains(
        "render.visible_splats: 225120 bytes exceed GL_MAX_SHADER_STORAGE_BLOCK_SIZE (200000)"));
}

// The records buffer holds two runs (the sprites, then the CPU cull's flat-coloured sprites) and the
// compute cull binds only the first: a limit between one run and both keeps the cloud on the compute cull.
TEST_F(Barriers_, ComputeCullTakesACloudWhoseSpriteRecordsFitTheBlock) {
    add_camera(3.0);
    add_cloud(fibonacci_sphere(2345, 1.0, 0.8));
    gfx::GlLimits small = gfx::limits();
    small.max_ssbo_block_size = 300 * 1000;  // sprite records 225,120 bytes; both runs 450,240
    log::ScopedLogCapture capture;
    gfx::ScopedLimits scope(small);
    frame(Quality::hq, CullPath::compute, RasterPath::raster);
    EXPECT_EQ(reg.resource<RenderStats>().compute_culled_clouds, 1u);
    EXPECT_EQ(reg.resource<RenderStats>().cpu_culled_clouds, 0u);
    EXPECT_FALSE(capture.contains("GL_MAX_SHADER_STORAGE_BLOCK_SIZE"));  // (drivers' messages name buffers)
}

}  // namespace
