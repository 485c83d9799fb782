// The two cull paths (RenderSettings::cull_path): the compute pass and its CPU twin (cpu_cull.h) render
// the same images, and the automatic choice takes the CPU path on llvmpipe only while the splats are on the
// CPU (a cloud deformed by the FFD compute pass falls back to the compute cull).
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "runtime/gfx/dispatch.h"
#include "runtime/gfx/splat_store.h"
#include "systems/ffd/components.h"
#include "systems/ffd/ffd_system.h"
#include "systems/ffd/lattice.h"
#include "systems/ffd/operations.h"
#include "systems/splat_render/splat_render_detail.h"
#include "tests/systems/splat_render/gl_fixture.h"
#include "tests/systems/splat_render/test_scenes.h"

using namespace sffd;
using namespace sffd::render;
using namespace sffd::render::test;

namespace {

// A textured sphere with some splats too large for sprites (drawn as quads) and a few splats straddling
// the frame's border (quads too: sprites are clipped by their centre).
SplatCloud mixed_sphere() {
    SplatCloud s = fibonacci_sphere(20000, 1.0, 0.8);
    add_checker(s);
    for (std::size_t i = 0; i < s.size(); i += 211)
        if (s.normals[i].z > 0.5f) s.axis_u[i] *= 25.0f, s.axis_v[i] *= 25.0f;
    return s;
}

class CullPath_ : public GlRenderTest {};

// How many splats the compute cull may classify differently from its C++ twin: each decision (in front,
// facing, sprite or quad, inside the frame) compares float expressions that a GPU evaluates with
// approximate inversesqrt (2 ULP), 2.5-ULP division and fused multiply-adds, so a splat whose margin is
// within a few ULP can flip. On these spheres of 20,000 splats that is a handful; 0.25% leaves room on
// any conforming implementation while a wrong test (a sign, a missed plane) moves hundreds. llvmpipe
// agrees exactly.
constexpr std::uint32_t kBorderlineSplats = 50;

std::uint32_t count_difference(std::uint32_t a, std::uint32_t b) { return a > b ? a - b : b - a; }

// Preview (lit per splat in the cull) and HQ, culling on and off, textured: the CPU cull and the compute
// pass produce the same visible sets and the same pixels (up to float rounding and, in the preview, the
// draw order of splats at equal depth).
TEST_F(CullPath_, CpuAndComputeCullsRenderTheSameImage) {
    add_camera(2.6);
    add_light({-0.5f, -0.4f, -0.6f}, 0.15f);
    add_cloud(mixed_sphere());
    for (bool culling : {true, false})
        for (Quality q : {Quality::hq, Quality::preview}) {
            const char* what = q == Quality::hq ? (culling ? "hq" : "hq, no culling")
                                                : (culling ? "preview" : "preview, no culling");
            const FrameImage gpu = render(q, 480, 320, culling, CullPath::compute);
            const RenderStats gs = reg.resource<RenderStats>();
            const FrameImage cpu = render(q, 480, 320, culling, CullPath::cpu);
            const RenderStats cs = reg.resource<RenderStats>();
            EXPECT_EQ(gs.compute_culled_clouds, 1u) << what;
            EXPECT_EQ(cs.cpu_culled_clouds, 1u) << what;
            EXPECT_LE(count_difference(cs.visible_points, gs.visible_points), kBorderlineSplats) << what;
            EXPECT_LE(count_difference(cs.visible_quads, gs.visible_quads), kBorderlineSplats) << what;
            EXPECT_GE(cs.visible_quads, 5u) << what;
            if (culling) {
                EXPECT_LT(cs.visible_points, 20000u / 2) << what;
            } else {
                EXPECT_EQ(cs.visible_points + cs.visible_quads, 20000u) << what;
            }
            const ImageDiff d = image_diff(gpu, cpu);
            EXPECT_GT(d.covered_a, 30000) << what;
            EXPECT_LE(d.coverage_mismatch, 2) << what;
            // Measured: the CPU's float-weight texture filtering and llvmpipe's differ by <= 1/512 (mean
            // 7e-4 HQ, 1.1e-3 preview); in the preview a splat drawn first at an exact depth tie wins the
            // pixel, and the CPU cull draws a textured cloud's one-colour sprites in a list of their own
            // (a few pixels). On a GPU borderline splats may flip (kBorderlineSplats): a pixel per flipped
            // splat may differ, so the bound on pixels over 2% is the borderline count there.
            EXPECT_LT(d.mean_color, 2e-3) << what;
            EXPECT_LE(d.over_2_percent,
                      gfx::software_rasterizer() ? (q == Quality::hq ? 0 : 10) : int(kBorderlineSplats))
                << what;
            EXPECT_LT(d.max_depth, 1e-3) << what;
        }
}

// Both paths are deterministic: two frames are bit-identical, HQ (float sums in draw order) on either
// rasteriser and preview (depth ties won by the first drawn). The compute cull's lists and the compute
// rasteriser's list of large sprites keep splat order (cull.comp, compute_visibility.comp); compacted by
// atomic appends, two frames differed on an NVIDIA H200 in whole pixels.
TEST_F(CullPath_, FramesAreBitIdenticalOnBothPaths) {
    add_camera(2.6);
    add_light({-0.5f, -0.4f, -0.6f}, 0.15f);
    add_cloud(mixed_sphere());
    for (CullPath path : {CullPath::cpu, CullPath::compute})
        for (RasterPath raster : {RasterPath::raster, RasterPath::compute})
            for (Quality q : {Quality::hq, Quality::preview}) {
                if (q == Quality::preview && raster == RasterPath::compute) continue;  // preview rasterises
                SCOPED_TRACE(path == CullPath::cpu ? "cpu cull" : "compute cull");
                SCOPED_TRACE(raster == RasterPath::raster ? "rasteriser" : "compute rasteriser");
                SCOPED_TRACE(q == Quality::hq ? "hq" : "preview");
                const FrameImage a = render(q, 320, 240, true, path, raster);
                const RenderStats stats = reg.resource<RenderStats>();
                const FrameImage b = render(q, 320, 240, true, path, raster);
                EXPECT_EQ(stats.compute_rastered_clouds, raster == RasterPath::compute ? 1u : 0u);
                ASSERT_EQ(a.color.size(), b.color.size());
                EXPECT_TRUE(a.color == b.color);
                EXPECT_TRUE(a.depth == b.depth);
            }
}

// Splats that cover no area draw nothing: one seen exactly edge-on (the eye in its plane: the camera at
// y = 0, its normal along y) and two whose axes collapsed (one axis zero, two parallel axes: what a
// lattice that flattens a cell does to them; the cull drops these as degenerate). The edge-on one's
// ray-cast plane n / (c · n) would divide by zero: every pixel of its sprite would cast against an
// infinite plane and write a NaN depth, which llvmpipe's depth test happens to reject and a GPU may clamp
// to the nearest depth. They sit in front of the sphere, so any such pixel would cover it. Each path,
// culling on and off: the same image as the sphere alone, and the compute cull's records all finite.
TEST_F(CullPath_, SplatsSeenEdgeOnOrWithNoAreaDrawNothing) {
    add_camera(2.6);
    add_light({-0.5f, -0.4f, -0.6f}, 0.15f);
    const SplatCloud sphere = fibonacci_sphere(5000, 1.0, 0.8);
    SplatCloud with = sphere;
    const glm::vec3 centres[] = {{0.0f, 0.0f, 1.5f}, {0.25f, 0.1f, 1.5f}, {-0.25f, -0.1f, 1.5f}};
    const glm::vec3 us[] = {{0.3f, 0.0f, 0.0f}, {0.3f, 0.0f, 0.0f}, {0.2f, 0.1f, 0.0f}};
    const glm::vec3 vs[] = {{0.0f, 0.0f, 0.3f}, {0.0f, 0.0f, 0.0f}, {0.2f, 0.1f, 0.0f}};
    const glm::vec3 ns[] = {{0.0f, 1.0f, 0.0f}, {0.0f, 0.0f, 1.0f}, {0.0f, 0.0f, 1.0f}};
    for (int k = 0; k < 3; ++k) {
        with.positions.push_back(centres[k]), with.normals.push_back(ns[k]);
        with.axis_u.push_back(us[k]), with.axis_v.push_back(vs[k]);
        with.colors.push_back(0xff0000ffu), with.uvs.push_back(glm::vec2(0.0f));
    }
    const ecs::Entity cloud = add_cloud(sphere);
    for (bool culling : {true, false})
        for (CullPath path : {CullPath::cpu, CullPath::compute})
            for (RasterPath raster : {RasterPath::raster, RasterPath::compute})
                for (Quality q : {Quality::hq, Quality::preview}) {
                    if (q == Quality::preview && raster == RasterPath::compute) continue;
                    SCOPED_TRACE(std::string(culling ? "culling" : "no culling") +
                                 (path == CullPath::cpu ? ", cpu cull" : ", compute cull") +
                                 (raster == RasterPath::raster ? ", rasteriser" : ", compute rasteriser") +
                                 (q == Quality::hq ? ", hq" : ", preview"));
                    reg.patch<SplatCloud>(cloud) = sphere;
                    const FrameImage a = render(q, 240, 160, culling, path, raster);
                    reg.patch<SplatCloud>(cloud) = with;
                    const FrameImage b = render(q, 240, 160, culling, path, raster);
                    if (path == CullPath::compute) {
                        // Every sprite record finite (llvmpipe happens to drop NaN depths; a GPU may not).
                        const detail::CloudGpu& gpu = reg.get<detail::CloudGpu>(cloud);
                        std::vector<std::uint32_t> commands(detail::draw_command_words);
                        glGetNamedBufferSubData(gpu.commands.id(), 0, GLsizeiptr(commands.size() * 4),
                                                commands.data());
                        std::vector<SplatRecord> records(commands[0]);
                        glGetNamedBufferSubData(gpu.records.id(), 0,
                                                GLsizeiptr(records.size() * sizeof(SplatRecord)),
                                                records.data());
                        std::size_t not_finite = 0;
                        for (const SplatRecord& r : records)
                            for (int j = 0; j < 20; ++j) not_finite += !std::isfinite((&r.center.x)[j]);
                        EXPECT_EQ(not_finite, 0u);
                    }
                    ASSERT_EQ(a.color.size(), b.color.size());
                    const ImageDiff d = image_diff(a, b);
                    EXPECT_GT(d.covered_a, 5000);
                    EXPECT_EQ(d.coverage_mismatch, 0);
                    EXPECT_EQ(d.over_2_percent, 0);
                    EXPECT_LT(d.max_depth, 1e-6);
                }
}

// Clouds beyond 65,535 work groups (8.4M splats at 128 per group) are culled over a 2D grid
// (gfx::dispatch_1d). With 4 groups per row, 20,000 splats take a 4 x 40 grid (the last row partly empty):
// the visible counts are exactly the one-row dispatch's and the CPU cull's (culling off: every splat
// exactly once), and the image is exactly the same (the lists keep splat order, however the groups run).
TEST_F(CullPath_, GridDispatchCullsTheSameSplatsAsOneRow) {
    add_camera(2.6);
    add_light({-0.5f, -0.4f, -0.6f}, 0.15f);
    add_cloud(mixed_sphere());
    for (bool culling : {true, false}) {
        const char* what = culling ? "culling" : "no culling";
        const FrameImage row = render(Quality::hq, 320, 240, culling, CullPath::compute);
        const RenderStats rs = reg.resource<RenderStats>();
        const FrameImage cpu = render(Quality::hq, 320, 240, culling, CullPath::cpu);
        const RenderStats cs = reg.resource<RenderStats>();
        FrameImage grid;
        RenderStats gs;
        {
            gfx::ScopedDispatchLimit four(4);
            grid = render(Quality::hq, 320, 240, culling, CullPath::compute);
            gs = reg.resource<RenderStats>();
        }
        ASSERT_TRUE(gs.counts_valid && rs.counts_valid && cs.counts_valid) << what;
        EXPECT_EQ(gs.compute_culled_clouds, 1u) << what;
        // One program, the same expressions per splat: the grid and the row agree exactly anywhere; the
        // C++ twin up to the borderline splats.
        EXPECT_EQ(gs.visible_points, rs.visible_points) << what;
        EXPECT_EQ(gs.visible_quads, rs.visible_quads) << what;
        EXPECT_LE(count_difference(gs.visible_points, cs.visible_points), kBorderlineSplats) << what;
        EXPECT_LE(count_difference(gs.visible_quads, cs.visible_quads), kBorderlineSplats) << what;
        if (!culling) {
            EXPECT_EQ(gs.visible_points + gs.visible_quads, 20000u) << what;
        }
        const ImageDiff d = image_diff(grid, row);
        EXPECT_GT(d.covered_a, 10000) << what;
        EXPECT_TRUE(grid.color == row.color) << what;
        EXPECT_TRUE(grid.depth == row.depth) << what;
    }
}

// automatic = CPU cull on a software rasterizer while the splats are on the CPU: at rest, and when the
// FFD system deformed them on the CPU; the compute cull when the FFD compute pass wrote them (force_gpu),
// and always on a hardware GPU (gfx::software_rasterizer() false). Both deformations render the same image.
// The CPU cull knows the square of every sprite it keeps, so the frame's drawn pixels (drawn_pixels(),
// what the display copies; the rest of the window is cleared) are their union: every covered pixel lies
// inside it, and it hugs them (a pixel of margin, and a square's corners past a disc seen at a slant).
// The sphere sits off the frame's centre, so a centred guess would miss it. The compute cull keeps the
// squares on the GPU: the whole frame. include_drawn_pixels() widens the rectangle, within the frame.
TEST_F(CullPath_, DrawnPixelsHoldEveryCoveredPixelAndHugThem) {
    add_camera(5.0);
    add_light({-0.5f, -0.4f, -0.6f}, 0.15f);
    SplatCloud sphere = fibonacci_sphere(20000);
    for (glm::vec3& p : sphere.positions) p += glm::vec3(0.9f, 0.5f, 0.0f);
    add_cloud(std::move(sphere));
    const int w = 320, h = 240;
    for (const Quality q : {Quality::preview, Quality::hq}) {
        const FrameImage img = render(q, w, h, true, CullPath::cpu);
        const glm::ivec4 d = drawn_pixels(reg);
        int covered = 0, outside = 0;
        glm::ivec2 lo(w, h), hi(-1, -1);  // covered pixels' box, GL rows (from the bottom)
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                if (!(img.color[img.index(x, y)].w > 0.0f)) continue;
                const int gl_y = h - 1 - y;
                ++covered;
                outside += x < d.x || x >= d.x + d.z || gl_y < d.y || gl_y >= d.y + d.w ? 1 : 0;
                lo = glm::min(lo, glm::ivec2(x, gl_y)), hi = glm::max(hi, glm::ivec2(x, gl_y));
            }
        const char* name = q == Quality::hq ? "hq" : "preview";
        ASSERT_GT(covered, 3000) << name;
        EXPECT_EQ(outside, 0) << name << ": covered pixels outside the drawn rectangle";
        EXPECT_LE(lo.x - d.x, 4) << name;
        EXPECT_LE(lo.y - d.y, 4) << name;
        EXPECT_LE(d.x + d.z - 1 - hi.x, 4) << name;
        EXPECT_LE(d.y + d.w - 1 - hi.y, 4) << name;
        EXPECT_GT(d.x, w / 3) << name << ": the sphere is right of the middle";
    }
    const glm::ivec4 sprites = drawn_pixels(reg);
    include_drawn_pixels(reg, glm::ivec4(10, 20, 30, 40));
    EXPECT_EQ(drawn_pixels(reg),
              glm::ivec4(10, 20, sprites.x + sprites.z - 10, std::max(sprites.y + sprites.w, 60) - 20));
    include_drawn_pixels(reg, glm::ivec4(300, 200, 100, 100));
    const glm::ivec4 clamped = drawn_pixels(reg);
    EXPECT_EQ(clamped.x + clamped.z, w);
    EXPECT_EQ(clamped.y + clamped.w, h);

    render(Quality::hq, w, h, true, CullPath::compute);
    EXPECT_EQ(drawn_pixels(reg), glm::ivec4(0, 0, w, h));
}

TEST_F(CullPath_, AutomaticPathFollowsWhereTheSplatsAre) {
    const bool software =
        gfx::software_rasterizer();  // llvmpipe: the CPU cull while the splats are on the CPU
    add_camera(3.0);
    add_light({-0.5f, -0.4f, -0.6f}, 0.15f);
    const ecs::Entity cloud = add_cloud(fibonacci_sphere(20000));
    render(Quality::hq, 320, 240);
    EXPECT_EQ(reg.resource<RenderStats>().cpu_culled_clouds, software ? 1u : 0u);
    EXPECT_EQ(reg.resource<RenderStats>().compute_culled_clouds, software ? 0u : 1u);

    const ecs::Entity le = add_lattice(cloud);
    ffd::twist_graded(reg.patch<Lattice>(le), ffd::all_control_points(reg.get<Lattice>(le)), {0, 1, 0}, 0.9,
                      glm::dvec3(0.0));
    reg.set_resource<FfdSettings>().force_cpu = true;
    ffd_system(reg, {});
    ASSERT_TRUE(reg.get<DeformedSplats>(cloud).cpu_valid);
    const FrameImage on_cpu = render(Quality::hq, 320, 240);
    EXPECT_EQ(reg.resource<RenderStats>().cpu_culled_clouds, software ? 1u : 0u);
    EXPECT_EQ(reg.resource<RenderStats>().compute_culled_clouds, software ? 0u : 1u);

    reg.resource<FfdSettings>().force_cpu = false;
    reg.resource<FfdSettings>().force_gpu = true;
    ffd_system(reg, {});
    ASSERT_TRUE(ffd::output_on_gpu(reg, cloud));
    const FrameImage on_gpu = render(Quality::hq, 320, 240);
    EXPECT_EQ(reg.resource<RenderStats>().cpu_culled_clouds, 0u);
    EXPECT_EQ(reg.resource<RenderStats>().compute_culled_clouds, 1u);

    const ImageDiff d = image_diff(on_cpu, on_gpu);
    EXPECT_GT(d.covered_a, 10000);
    EXPECT_LE(d.coverage_mismatch, 4);
    EXPECT_LT(d.mean_color, 1e-3);
    EXPECT_LT(d.max_depth, 1e-3);
    ffd_release_gpu(reg);
}

}  // namespace
