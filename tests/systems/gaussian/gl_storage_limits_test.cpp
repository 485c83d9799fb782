// The Gaussian GL renderer against the storage-block limits of GL 4.5 (runtime/gfx/limits.h), simulated
// with gfx::ScopedLimits: every per-Gaussian buffer is bound in element ranges (the projection, its
// depth-ordered copy, the order, the keys, the tile counts), the blend runs range by range front to back,
// and a cloud split across 3+ blocks of every buffer gives the image of the unlimited run bit for bit (the
// same shaders compute each value from the same inputs in the same order; only the bindings and the number
// of dispatches and draws change). Buffers bound whole (the GPU sort's keys, the tile path's counts and
// entries) are checked: the frame sorts on the CPU or blends with quads, saying which buffer and limit.
// Every program keeps to the storage blocks and binding points the engine requires of an implementation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

#include "runtime/core/log.h"
#include "runtime/gfx/barrier.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/limits.h"
#include "runtime/gfx/ssbo_batch.h"
#include "shaders/gaussian/gaussian_layout.h"
#include "systems/splat_render/gaussian_draw.h"
#include "systems/gaussian/reference_render.h"
#include "systems/gaussian/sh.h"
#include "tests/systems/gaussian/random_cloud.h"
#include "tests/systems/gaussian/gl_renderer_fixture.h"

namespace {

using namespace sffd;
using namespace sffd::gaussian;
using render::BlendPath;
using render::draw_gaussians;
using render::GaussianView;
using render::SortPath;
using test::draw_gl;
using test::render_gl;
using test::resident_buffers;
using test::upload_gl;

class GaussianGlLimits : public sffd::test::GaussianGlRendererTest<sffd::test::HeadlessGlTest> {};

Camera camera_at(glm::dvec3 eye) {
    Camera c;
    c.eye = eye, c.target = glm::dvec3(0.0), c.up = {0, 1, 0}, c.fov_y_degrees = 40.0f;
    return c;
}

GaussianCloud random_cloud(std::size_t n, int degree) { return test::seeded_random_cloud(23, n, degree); }

constexpr std::size_t kCount = 3000;
// 48 bytes a Gaussian (the projection as one array of records) would be 144,000 bytes in one block;
// 16 bytes (each of the three arrays) are 48,000.
constexpr std::int64_t kBetween = 100'000;

// Pixels whose colour or transmittance differ (bitwise) between two images, and the largest difference.
struct ImageDiff {
    std::size_t pixels = 0;
    float largest = 0.0f;
};
ImageDiff differ(const ReferenceImage& a, const ReferenceImage& b) {
    ImageDiff d;
    if (a.color.size() != b.color.size()) return {std::max(a.color.size(), b.color.size()), 1e30f};
    for (std::size_t i = 0; i < a.color.size(); ++i) {
        const float e =
            std::max(glm::length(a.color[i] - b.color[i]), std::abs(a.transmittance[i] - b.transmittance[i]));
        const bool same = a.color[i] == b.color[i] && a.transmittance[i] == b.transmittance[i];
        d.pixels += same ? 0 : 1;
        d.largest = std::max(d.largest, e);
    }
    return d;
}

std::int64_t bound_size(GLuint binding) {
    GLint64 size = -1;
    glGetInteger64i_v(GL_SHADER_STORAGE_BUFFER_SIZE, binding, &size);
    return size;
}

}  // namespace

// A limit the old 48-byte records would exceed and the 16-byte arrays fit: the image is exactly the
// unlimited one on each sort and blend path, and each projection array is bound as this cloud's 48,000
// bytes, not as the whole grow-only buffer (sized by a larger cloud drawn first).
TEST_F(GaussianGlLimits, ProjectionPastTheOldRecordSizeDrawsTheUnlimitedImage) {
    ReferenceOptions o;
    o.width = 96, o.height = 72;
    const GaussianCloud g = random_cloud(kCount, 1);
    const Camera cam = camera_at({0.2, 0.3, 3.5});
    gfx::GlLimits small = gfx::limits();
    small.max_ssbo_block_size = kBetween;
    ASSERT_GT(std::int64_t(kCount * 48), kBetween);
    ASSERT_LE(std::int64_t(kCount * SFFD_GPU_PROJECTED_STRIDE), kBetween);
    for (BlendPath blend : {BlendPath::quads, BlendPath::tiles})
        for (SortPath sort : {SortPath::cpu, SortPath::gpu}) {
            const std::string what = std::string(blend == BlendPath::tiles ? "tiles" : "quads") +
                                     (sort == SortPath::gpu ? ", GPU sort" : ", CPU sort");
            renderer->sort_path = sort, renderer->blend_path = blend;
            ASSERT_TRUE(render_gl(*renderer, random_cloud(2 * kCount, 1), cam, o));  // grows the buffers
            auto whole = render_gl(*renderer, g, cam, o);
            ASSERT_TRUE(whole) << whole.message();
            auto limited = [&] {
                gfx::ScopedLimits scope(small);
                return render_gl(*renderer, g, cam, o);
            }();
            ASSERT_TRUE(limited) << what << ": " << limited.message();
            EXPECT_EQ(limited->color, whole->color) << what;
            EXPECT_GT(psnr(*limited, render_reference(g, cam, o)), 40.0) << what;
            if (blend == BlendPath::tiles) {
                EXPECT_LE(std::int64_t(renderer->tile_entries * 4), kBetween);
            }
            // The blend's bindings (the tile blend rebinds points 7 and 8 to the projection last).
            for (GLuint binding :
                 {SFFD_GAUSS_SSBO_PROJ_CENTER, SFFD_GAUSS_SSBO_PROJ_CONIC, SFFD_GAUSS_SSBO_PROJ_COLOR})
                EXPECT_EQ(bound_size(binding), std::int64_t(kCount * SFFD_GPU_PROJECTED_STRIDE))
                    << what << ", binding " << binding;
        }
}

// A limit under which the order and keys (4 bytes a Gaussian) need 3+ blocks, and so does every wider
// buffer (the Gaussians, SH of degree 3, the projection and its depth-ordered copy: 10001 Gaussians, the
// last range partial), with offsets aligned to 256 bytes (no divisor of the 48-byte Gaussians): the quads
// draw the unlimited image, on either sort (the GPU sort's keys, bound whole, fall back to the CPU sort:
// the same order, ties broken by index); the tile path binds its counts whole and is refused naming them.
TEST_F(GaussianGlLimits, EveryPerGaussianBufferAcrossBlocksDrawsTheUnlimitedImage) {
    ReferenceOptions o;
    o.width = 96, o.height = 72;
    constexpr std::size_t n = 10001;
    const Camera cam = camera_at({0.2, 0.3, 3.5});
    gfx::GlLimits small = gfx::limits();
    small.max_ssbo_block_size = 12288;
    small.ssbo_offset_alignment = 256;
    const std::uint64_t widths[] = {sizeof(std::uint32_t), SFFD_GPU_PROJECTED_STRIDE, SFFD_GPU_GAUSSIAN_BYTES,
                                    std::uint64_t(sh_coeffs(3)) * 3 * sizeof(float)};
    for (const std::uint64_t w : widths) ASSERT_GT(n * w, 2 * std::uint64_t(small.max_ssbo_block_size)) << w;
    const std::uint64_t blend_strides[] = {SFFD_GPU_PROJECTED_STRIDE, sizeof(std::uint32_t)};
    auto ranges = gfx::ssbo_batches(n, blend_strides, small);
    ASSERT_TRUE(ranges);
    ASSERT_GE(ranges->size(), 3u);
    ASSERT_LT(ranges->back().count, ranges->front().count);  // the last range partial
    for (int degree : {0, 3}) {
        const GaussianCloud g = random_cloud(n, degree);
        for (SortPath sort : {SortPath::cpu, SortPath::gpu}) {
            const std::string what =
                "degree " + std::to_string(degree) + (sort == SortPath::gpu ? ", GPU sort" : ", CPU sort");
            renderer->sort_path = sort, renderer->blend_path = BlendPath::quads;
            auto whole = render_gl(*renderer, g, cam, o);
            ASSERT_TRUE(whole) << what << ": " << whole.message();
            log::ScopedLogCapture capture;
            gfx::ScopedLimits scope(small);
            renderer->sort_fallback_warned = false;
            auto limited = render_gl(*renderer, g, cam, o);
            ASSERT_TRUE(limited) << what << ": " << limited.message();
            const ImageDiff d = differ(*limited, *whole);
            EXPECT_EQ(d.pixels, 0u) << what << ": largest difference " << d.largest;
            EXPECT_FALSE(capture.contains("not drawn")) << what;
            if (sort == SortPath::gpu) {
                EXPECT_FALSE(renderer->gpu_sort_used) << what;
                EXPECT_TRUE(
                    capture.contains("gaussian.depth_keys: 40004 bytes exceed "
                                     "GL_MAX_SHADER_STORAGE_BLOCK_SIZE (12288)"))
                    << what;
            }
            // The tiles asked for, but their counts are bound whole and exceed the block: the quads
            // blend the cloud instead (the same image), saying which buffer and limit.
            renderer->blend_path = BlendPath::tiles;
            renderer->tile_fallback_warned = false;
            auto tiles = draw_gl(*renderer, cam, o);
            ASSERT_TRUE(tiles) << what << ": " << tiles.message();
            EXPECT_EQ(renderer->last_blend, BlendPath::quads) << what;
            EXPECT_EQ(differ(*tiles, *whole).pixels, 0u) << what;
            EXPECT_TRUE(
                capture.contains("gaussian.tile_touched: 40008 bytes exceed "
                                 "GL_MAX_SHADER_STORAGE_BLOCK_SIZE (12288) (the tile path binds it "
                                 "whole); blending with quads"))
                << what;
        }
    }
}

// 10001 Gaussians whose projection needs 3 blocks (the last range partial) while the keys, counts and
// tile entries fit: most Gaussians are behind the camera, so the drawn ones fill the first range and the
// later ranges draw few or none. Every sort and blend path draws the unlimited image bit for bit, the tile
// blend carrying each pixel across the ranges (its stopped pixels included: the Gaussians are opaque
// enough to saturate), and the cloud's visible Gaussians keep to the reference.
TEST_F(GaussianGlLimits, ProjectionAcrossBlocksOnEverySortAndBlendPath) {
    ReferenceOptions o;
    o.width = 96, o.height = 72;
    constexpr std::size_t n = 10001, visible = 4000;
    GaussianCloud g = random_cloud(n, 1);
    for (std::size_t i = 0; i < n; ++i) {
        g.scales[i] *= 0.35f;
        if (i % (n / (n - visible)) != 0 || i >= 2 * visible) g.positions[i].z += 8.0f;  // behind the eye
    }
    const Camera cam = camera_at({0.2, 0.3, 3.5});
    gfx::GlLimits small = gfx::limits();
    small.max_ssbo_block_size = 64000;
    small.ssbo_offset_alignment = 256;
    const std::uint64_t blend_strides[] = {SFFD_GPU_PROJECTED_STRIDE, sizeof(std::uint32_t)};
    auto ranges = gfx::ssbo_batches(n, blend_strides, small);
    ASSERT_TRUE(ranges);
    ASSERT_EQ(ranges->size(), 3u);
    ASSERT_LT(ranges->back().count, ranges->front().count);
    for (BlendPath blend : {BlendPath::quads, BlendPath::tiles})
        for (SortPath sort : {SortPath::cpu, SortPath::gpu}) {
            const std::string what = std::string(blend == BlendPath::tiles ? "tiles" : "quads") +
                                     (sort == SortPath::gpu ? ", GPU sort" : ", CPU sort");
            renderer->sort_path = sort, renderer->blend_path = blend;
            auto whole = render_gl(*renderer, g, cam, o);
            ASSERT_TRUE(whole) << what << ": " << whole.message();
            gfx::BarrierLog log;
            auto limited = [&] {
                gfx::ScopedLimits scope(small);
                return render_gl(*renderer, g, cam, o);
            }();
            ASSERT_TRUE(limited) << what << ": " << limited.message();
            EXPECT_EQ(renderer->gpu_sort_used, sort == SortPath::gpu) << what;
            const ImageDiff d = differ(*limited, *whole);
            EXPECT_EQ(d.pixels, 0u) << what << ": largest difference " << d.largest;
            EXPECT_GT(psnr(*limited, render_reference(g, cam, o)), 40.0) << what;
            std::size_t covered = 0, stopped = 0;
            for (float t : limited->transmittance) covered += t < 0.5f, stopped += t < 1e-3f;
            EXPECT_GT(covered, limited->transmittance.size() / 4) << what;
            EXPECT_GT(stopped, 0u) << what << ": no pixel near saturation (early termination untested)";
            if (blend == BlendPath::tiles) {
                EXPECT_LE(std::int64_t(renderer->tile_entries * 4), small.max_ssbo_block_size) << what;
                std::size_t range_passes = 0;
                for (const gfx::BarrierRecord& r : log.records())
                    range_passes += r.site == "gaussian.tiles.blend_range";
                EXPECT_EQ(range_passes, ranges->size() - 1) << what;
            }
            // The blend's bindings, last the final range of the depth-ordered arrays.
            for (GLuint binding :
                 {SFFD_GAUSS_SSBO_PROJ_CENTER, SFFD_GAUSS_SSBO_PROJ_CONIC, SFFD_GAUSS_SSBO_PROJ_COLOR})
                EXPECT_EQ(bound_size(binding), std::int64_t(ranges->back().count * SFFD_GPU_PROJECTED_STRIDE))
                    << what << ", binding " << binding;
        }
}

// A limit under which not one aligned range of Gaussians fits: refused before anything runs (no
// projection dispatched, so no barrier recorded), naming the limit, the count and the buffer, on both
// entry points.
TEST_F(GaussianGlLimits, CloudWhoseRangesCannotFitIsRefusedNamingTheLimitCountAndBuffer) {
    ReferenceOptions o;
    o.width = 64, o.height = 48;
    const GaussianCloud g = random_cloud(kCount, 0);
    gfx::GlLimits small = gfx::limits();
    small.max_ssbo_block_size = 32;
    const auto expect_refusal = [](const std::string& message) {
        EXPECT_NE(message.find("GL_MAX_SHADER_STORAGE_BLOCK_SIZE (32)"), std::string::npos) << message;
        EXPECT_NE(message.find("3000 Gaussians"), std::string::npos) << message;
        EXPECT_NE(message.find("gaussian.proj_center"), std::string::npos) << message;
    };
    ASSERT_TRUE(upload_gl(*renderer, g));
    gfx::ScopedLimits scope(small);
    for (SortPath sort : {SortPath::cpu, SortPath::gpu}) {
        renderer->sort_path = sort;
        gfx::BarrierLog log;
        auto refused = draw_gl(*renderer, camera_at({0.2, 0.3, 3.5}), o);
        ASSERT_FALSE(refused);
        expect_refusal(refused.message());
        GaussianView v;
        v.width = o.width, v.height = o.height;
        v.view = glm::lookAt(glm::dvec3(0.2, 0.3, 3.5), glm::dvec3(0.0), glm::dvec3(0, 1, 0));
        const Status drawn = draw_gaussians(*renderer, resident_buffers(*renderer), v);
        ASSERT_FALSE(drawn);
        expect_refusal(drawn.message());
        EXPECT_TRUE(log.records().empty()) << "GL work was issued before the refusal";
    }
}

// Every program of the renderer within what runtime/gfx/limits.h requires of an implementation (and
// create_context() checks): storage blocks per stage and in all, binding points. GL 4.5 itself
// guarantees no storage block in a vertex shader, 8 per compute shader and 8 binding points.
TEST_F(GaussianGlLimits, ProgramsStayWithinTheRequiredStorageBlocks) {
    const gfx::GlRequirements need;
    const std::pair<const gfx::Program*, const char*> programs[] = {
        {&renderer->project, "project"},           {&renderer->splat, "splat"},
        {&renderer->tile_count, "tile_count"},     {&renderer->tile_emit, "tile_emit"},
        {&renderer->tile_ranges, "tile_ranges"},   {&renderer->tile_blend, "tile_blend"},
        {&renderer->sort_payload, "sort_payload"}, {&renderer->gather, "gather"}};
    for (const auto& [program, name] : programs) {
        GLint blocks = 0;
        glGetProgramInterfaceiv(program->id(), GL_SHADER_STORAGE_BLOCK, GL_ACTIVE_RESOURCES, &blocks);
        int vertex = 0, fragment = 0, compute = 0;
        for (GLint i = 0; i < blocks; ++i) {
            const GLenum props[] = {GL_BUFFER_BINDING, GL_REFERENCED_BY_VERTEX_SHADER,
                                    GL_REFERENCED_BY_FRAGMENT_SHADER, GL_REFERENCED_BY_COMPUTE_SHADER};
            GLint v[4] = {};
            glGetProgramResourceiv(program->id(), GL_SHADER_STORAGE_BLOCK, GLuint(i), 4, props, 4, nullptr,
                                   v);
            EXPECT_LT(v[0], need.ssbo_bindings) << name;
            vertex += v[1] != 0, fragment += v[2] != 0, compute += v[3] != 0;
        }
        EXPECT_GT(blocks, 0) << name;
        EXPECT_LE(vertex, need.vertex_ssbo_blocks) << name;
        EXPECT_LE(fragment, need.fragment_ssbo_blocks) << name;
        EXPECT_LE(compute, need.compute_ssbo_blocks) << name;
        EXPECT_LE(blocks, need.combined_ssbo_blocks) << name;
    }
}

// The GPU sort writes the order through storage blocks, read by the gather (the sort's own barrier);
// the gather writes the depth-ordered projection and the range commands, which the quads read as storage
// blocks and indirect draws: GL 4.5 §7.12.2 orders those only after SHADER_STORAGE and COMMAND barriers
// (llvmpipe would draw the right image without them).
TEST_F(GaussianGlLimits, QuadsReadTheGatheredProjectionAfterStorageAndCommandBarriers) {
    ReferenceOptions o;
    o.width = 64, o.height = 48;
    renderer->sort_path = SortPath::gpu, renderer->blend_path = BlendPath::quads;
    gfx::BarrierLog log;
    ASSERT_TRUE(render_gl(*renderer, random_cloud(500, 0), camera_at({0.2, 0.3, 3.5}), o));
    std::size_t last_sort = 0, gather = 0;
    const GLbitfield needed = GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT;
    for (std::size_t k = 0; k < log.records().size(); ++k) {
        if (log.records()[k].site == "radix.sort") last_sort = k + 1;
        if (log.records()[k].site == "gaussian.gather" && (log.records()[k].bits & needed) == needed)
            gather = k + 1;
    }
    ASSERT_GT(last_sort, 0u);
    EXPECT_GT(gather, last_sort) << "no SHADER_STORAGE | COMMAND barrier after the gather";
}
