// Clouds whose splats exceed GL_MAX_SHADER_STORAGE_BLOCK_SIZE (simulated with a small limit,
// gfx::ScopedLimits): the CPU cull's quad pass draws range by range (storage_limits.h) and gives the image
// of the unlimited path. The same quads are drawn in the same order, only split over several draws, so
// coverage is identical and colours agree to rounding (1e-5; llvmpipe gives equal bits).
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "runtime/core/log.h"
#include "runtime/gfx/limits.h"
#include "systems/ffd/components.h"
#include "systems/ffd/ffd_system.h"
#include "systems/ffd/operations.h"
#include "systems/splat_render/splat_render_detail.h"
#include "systems/splat_render/storage_limits.h"
#include "tests/systems/splat_render/gl_fixture.h"
#include "tests/systems/splat_render/test_scenes.h"

using namespace sffd;
using namespace sffd::render;
using namespace sffd::render::test;

namespace {

void expect_same_image(const FrameImage& a, const FrameImage& b, const std::string& what) {
    ASSERT_EQ(a.color.size(), b.color.size()) << what;
    std::size_t covered = 0;
    float worst = 0.0f;
    for (std::size_t i = 0; i < a.color.size(); ++i) {
        ASSERT_EQ(a.color[i].w > 0.0f, b.color[i].w > 0.0f) << what << " pixel " << i;
        covered += a.color[i].w > 0.0f;
        for (int k = 0; k < 4; ++k) worst = std::max(worst, std::abs(a.color[i][k] - b.color[i][k]));
    }
    EXPECT_GT(covered, a.color.size() / 2) << what;  // the sphere fills most of the image
    EXPECT_LE(worst, 1e-5f) << what;
}

class StorageBatch_ : public GlRenderTest {
protected:
    // A sphere seen from close by: its rim runs off the image, so many splats are drawn as quads.
    ecs::Entity scene(bool textured, std::size_t count = 5000) {
        add_camera(1.7);
        add_light({-0.5f, -0.4f, -0.6f});
        SplatCloud c = fibonacci_sphere(count, 1.0, 0.9);
        if (textured) add_checker(c);
        return add_cloud(std::move(c));
    }
    // CPU cull (unless `cull` says otherwise) and the raster path (the compute rasteriser would fall back
    // under the small limit only).
    FrameImage frame(Quality q, int w, int h, CullPath cull = CullPath::cpu) {
        RenderSettings s;
        s.quality = q, s.width = w, s.height = h, s.time_passes = true;
        s.cull_path = cull, s.raster_path = RasterPath::raster;
        reg.set_resource<RenderSettings>(s);
        residency_system(reg, FrameContext{});
        render_system(reg, FrameContext{});
        auto img = capture_frame(reg);
        EXPECT_TRUE(img.ok()) << (img.ok() ? "" : img.message());
        return img.ok() ? std::move(img.value()) : FrameImage{};
    }
    // Preview and HQ, each with the real limit and with one that cuts the splats into ranges.
    void check_batched_quads(bool textured) {
        const ecs::Entity e = scene(textured);
        for (const Quality q : {Quality::preview, Quality::hq}) {
            const std::string what =
                std::string(textured ? "textured " : "") + (q == Quality::hq ? "hq" : "preview");
            const FrameImage whole = frame(q, 160, 120);
            ASSERT_EQ(quad_ranges(e), 0u) << what;  // one indirect draw when everything fits
            ASSERT_GT(reg.resource<RenderStats>().visible_quads, 100u) << what;
            gfx::GlLimits small = gfx::limits();
            small.max_ssbo_block_size = 997 * 64;  // splats 5000 x 64 bytes: 6 ranges
            FrameImage batched;
            {
                gfx::ScopedLimits scope(small);
                batched = frame(q, 160, 120);
            }
            EXPECT_GE(quad_ranges(e), 6u) << what;
            expect_same_image(whole, batched, what);
        }
    }
    std::size_t quad_ranges(ecs::Entity e) {
        const detail::CloudGpu* gpu = reg.try_get<detail::CloudGpu>(e);
        return gpu ? gpu->quad_batches.size() : 0u;
    }
};

}  // namespace

TEST_F(StorageBatch_, QuadPassOverTheBlockSizeDrawsTheUnlimitedImage) { check_batched_quads(false); }
TEST_F(StorageBatch_, TexturedQuadPassOverTheBlockSizeDrawsTheUnlimitedImage) { check_batched_quads(true); }

// Not one aligned range of splats fits: the cloud is skipped with a warning naming the limit, not drawn
// past the block.
TEST_F(StorageBatch_, CloudIsSkippedNamingTheLimitWhenNotOneSplatFits) {
    scene(false);
    gfx::GlLimits small = gfx::limits();
    small.max_ssbo_block_size = 32;
    log::ScopedLogCapture capture;
    gfx::ScopedLimits scope(small);
    const FrameImage img = frame(Quality::preview, 64, 48);
    EXPECT_TRUE(capture.contains("GL_MAX_SHADER_STORAGE_BLOCK_SIZE (32)"));
    EXPECT_EQ(
        std::count_if(img.color.begin(), img.color.end(), [](const glm::vec4& c) { return c.w > 0.0f; }), 0);
}

// The compute rasteriser reads the CPU cull's records (96 bytes a splat; twice that for a textured cloud's
// flat-coloured list) as storage blocks: when they exceed the limit and its per-pixel buffers do not, the
// frame stays on the raster path with a warning naming the buffer and the limit.
TEST_F(StorageBatch_, ComputeRasteriserFallsBackWhenTheRecordsExceedTheBlockSize) {
    scene(false);
    RenderSettings s;
    s.quality = Quality::hq, s.width = 40, s.height = 30, s.time_passes = true;
    s.cull_path = CullPath::cpu, s.raster_path = RasterPath::compute;
    reg.set_resource<RenderSettings>(s);
    residency_system(reg, FrameContext{});
    render_system(reg, FrameContext{});
    ASSERT_EQ(reg.resource<RenderStats>().compute_rastered_clouds, 1u);  // the real limit allows it
    {
        // The sprites' run fits, the whole records buffer (both runs) would not: an untextured cloud has
        // no flat-coloured list, so the compute rasteriser binds only the first run and takes the cloud.
        gfx::GlLimits limit = gfx::limits();
        limit.max_ssbo_block_size = 600'000;  // records 480,000 of 960,000; splats 320,000
        gfx::ScopedLimits scope(limit);
        render_system(reg, FrameContext{});
        EXPECT_EQ(reg.resource<RenderStats>().compute_rastered_clouds, 1u);
    }
    gfx::GlLimits small = gfx::limits();
    small.max_ssbo_block_size = 100'000;  // sums 40 x 30 x 36 = 43,200 fit; records 5000 x 96 do not
    log::ScopedLogCapture capture;
    gfx::ScopedLimits scope(small);
    render_system(reg, FrameContext{});
    EXPECT_EQ(reg.resource<RenderStats>().compute_rastered_clouds, 0u);
    EXPECT_TRUE(capture.contains("render.visible_splats: " + std::to_string(5000 * SFFD_SPLAT_RECORD_BYTES) +
                                 " bytes exceed GL_MAX_SHADER_STORAGE_BLOCK_SIZE (100000)"));
}

// The compute cull's sprite records (96 bytes a splat) over the limit, on the forced compute cull: the CPU
// cull takes the cloud (its quad pass in ranges), saying why once, and the image is the unlimited CPU
// cull's, not an empty frame.
TEST_F(StorageBatch_, ForcedComputeCullOverTheLimitFallsBackToTheCpuCull) {
    const ecs::Entity e = scene(false);
    const FrameImage whole = frame(Quality::hq, 160, 120, CullPath::cpu);
    gfx::GlLimits small = gfx::limits();
    small.max_ssbo_block_size = 829 * 64;  // a limit no other test uses: its warning is new here
    log::ScopedLogCapture capture;
    gfx::ScopedLimits scope(small);
    for (int k = 0; k < 2; ++k) {
        const FrameImage limited = frame(Quality::hq, 160, 120, CullPath::compute);
        EXPECT_EQ(reg.resource<RenderStats>().compute_culled_clouds, 0u);
        EXPECT_EQ(reg.resource<RenderStats>().cpu_culled_clouds, 1u);
        EXPECT_GE(quad_ranges(e), 6u);
        expect_same_image(whole, limited, "forced compute cull over the limit, frame " + std::to_string(k));
    }
    const auto entries = capture.entries();
    EXPECT_EQ(std::count_if(entries.begin(), entries.end(),
                            [](const log::ScopedLogCapture::Entry& m) {
                                return m.message.find(
                                           "GL_MAX_SHADER_STORAGE_BLOCK_SIZE (53056); the CPU "
                                           "cull takes the cloud") != std::string::npos;
                            }),
              1);
}

// A cloud the FFD compute pass deformed exists only on the GPU, so its cull is the compute pass; with its
// records over the limit the splats are read back and CPU-culled (quads in ranges) instead of the cloud
// going undrawn. The image is the compute cull's within the two culls' tolerance (cull_path_test.cpp:
// float rounding can flip a splat at a pixel's edge; llvmpipe agrees exactly).
TEST_F(StorageBatch_, GpuDeformedCloudOverTheLimitIsReadBackAndCpuCulled) {
    const ecs::Entity e = scene(false);
    const ecs::Entity le = add_lattice(e);
    ffd::twist_graded(reg.patch<Lattice>(le), ffd::all_control_points(reg.get<Lattice>(le)), {0, 1, 0}, 0.9,
                      glm::dvec3(0.0));
    reg.set_resource<FfdSettings>().force_gpu = true;
    residency_system(reg, FrameContext{});
    ffd_system(reg, {});
    ASSERT_TRUE(ffd::output_on_gpu(reg, e));
    for (const Quality q : {Quality::preview, Quality::hq}) {
        const std::string what = q == Quality::hq ? "hq" : "preview";
        const FrameImage computed = frame(q, 160, 120, CullPath::automatic);
        ASSERT_EQ(reg.resource<RenderStats>().compute_culled_clouds, 1u) << what;
        gfx::GlLimits small = gfx::limits();
        small.max_ssbo_block_size = 997 * 64;
        log::ScopedLogCapture capture;
        FrameImage limited;
        {
            gfx::ScopedLimits scope(small);
            limited = frame(q, 160, 120, CullPath::automatic);
        }
        EXPECT_EQ(reg.resource<RenderStats>().compute_culled_clouds, 0u) << what;
        EXPECT_EQ(reg.resource<RenderStats>().cpu_culled_clouds, 1u) << what;
        EXPECT_GE(quad_ranges(e), 6u) << what;
        if (q == Quality::preview) {  // read back once: the hq frame reuses the copy
            EXPECT_TRUE(capture.contains("read back from the GPU")) << what;
        }
        const ImageDiff d = image_diff(computed, limited);
        EXPECT_GT(d.covered_a, 160 * 120 / 2) << what;
        EXPECT_LE(d.coverage_mismatch, 4) << what;
        EXPECT_LT(d.mean_color, 1e-3) << what;
    }
    ffd_release_gpu(reg);
}

// An odd cloud (4999 splats: the last range partial) deformed by the FFD compute pass, which runs in
// element ranges too, with offsets aligned to 256 bytes (6 ranges of the deformation and of the quad
// pass): under the real limit the compute cull draws it, under the small one the CPU cull of the splats
// read back; the images agree within the two culls' tolerance, as above.
TEST_F(StorageBatch_, OddGpuDeformedCloudInRangesDrawsTheUnlimitedImage) {
    const ecs::Entity e = scene(false, 4999);
    const ecs::Entity le = add_lattice(e);
    ffd::twist_graded(reg.patch<Lattice>(le), ffd::all_control_points(reg.get<Lattice>(le)), {0, 1, 0}, 0.9,
                      glm::dvec3(0.0));
    reg.set_resource<FfdSettings>().force_gpu = true;
    gfx::GlLimits small = gfx::limits();
    small.max_ssbo_block_size = 997 * 64;
    small.ssbo_offset_alignment = 256;
    const std::uint64_t stride[] = {sizeof(gpu::GpuSplat)};
    auto ranges = gfx::ssbo_batches(4999, stride, small);
    ASSERT_TRUE(ranges);
    ASSERT_GE(ranges->size(), 3u);
    ASSERT_LT(ranges->back().count, ranges->front().count);
    // The lattice's change stamp moves (its points are rewritten as they are): the deformation runs again.
    const auto deform = [&] {
        reg.patch<Lattice>(le);
        const std::uint64_t runs = reg.resource<FfdStats>().gpu_runs;
        residency_system(reg, FrameContext{});
        ffd_system(reg, {});
        EXPECT_EQ(reg.resource<FfdStats>().gpu_runs, runs + 1);
        EXPECT_TRUE(ffd::output_on_gpu(reg, e));
    };
    residency_system(reg, FrameContext{});
    ffd_system(reg, {});
    for (const Quality q : {Quality::preview, Quality::hq}) {
        const std::string what = q == Quality::hq ? "hq" : "preview";
        deform();
        const FrameImage whole = frame(q, 160, 120, CullPath::automatic);
        EXPECT_EQ(reg.resource<RenderStats>().compute_culled_clouds, 1u) << what;
        FrameImage limited;
        {
            gfx::ScopedLimits scope(small);
            deform();
            limited = frame(q, 160, 120, CullPath::automatic);
        }
        EXPECT_EQ(reg.resource<RenderStats>().cpu_culled_clouds, 1u) << what;
        EXPECT_EQ(quad_ranges(e), ranges->size()) << what;
        const ImageDiff d = image_diff(whole, limited);
        EXPECT_GT(d.covered_a, 160 * 120 / 2) << what;
        EXPECT_LE(d.coverage_mismatch, 4) << what;
        EXPECT_LT(d.mean_color, 1e-3) << what;
    }
    ffd_release_gpu(reg);
}

// CPU only: quads regrouped per range, relative to its first splat, each group aligned.
TEST(StorageBatchLayout, QuadsRegroupedPerRangeAlignedAndRelative) {
    const std::vector<std::uint32_t> quads = {0, 3, 4, 9, 10, 11, 25, 29};
    const std::vector<gfx::SsboBatch> ranges = {{0, 10}, {10, 10}, {20, 10}};
    std::vector<std::uint32_t> out;
    const std::vector<QuadBatch> b = layout_quad_batches(quads, ranges, 4, out);
    ASSERT_EQ(b.size(), 3u);
    EXPECT_EQ(b[0].quad_first, 0u);
    EXPECT_EQ(b[0].quad_count, 4u);
    EXPECT_EQ(b[1].quad_first, 4u);
    EXPECT_EQ(b[1].quad_count, 2u);
    EXPECT_EQ(b[2].quad_first, 8u);  // 6 rounded up to the alignment
    EXPECT_EQ(b[2].quad_count, 2u);
    const std::vector<std::uint32_t> expected = {0, 3, 4, 9, 0, 1, 0, 0, 5, 9};
    EXPECT_EQ(out, expected);
}
