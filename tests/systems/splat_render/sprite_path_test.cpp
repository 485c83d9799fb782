// The preview's two rasterisers (RenderSettings::sprite_path): point sprites through GL and the CPU
// rasteriser (cpu_raster.h) give the same frames, with GL drawing what the CPU leaves (quads, textured
// sprites) depth-tested over the CPU's part; the automatic choice takes the CPU on software GL only.
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "tests/systems/splat_render/gl_fixture.h"
#include "tests/systems/splat_render/test_scenes.h"

using namespace sffd;
using namespace sffd::render;
using namespace sffd::render::test;

namespace {

// A sphere of per-splat colours (a hue ramp, so a misplaced splat shows), some splats enlarged into quads
// (unless `quads` is false); `fine`: a texture fine enough to be minified.
SplatCloud colored_sphere(bool textured, bool quads = true, bool fine = false) {
    SplatCloud s = fibonacci_sphere(20000, 1.0, 0.8);
    for (std::size_t i = 0; i < s.size(); ++i) {
        const auto r = std::uint32_t(40 + (i * 7) % 200), g = std::uint32_t(40 + (i * 13) % 200),
                   b = std::uint32_t(40 + (i * 29) % 200);
        s.colors[i] = r | (g << 8) | (b << 16) | 0xff000000u;
    }
    if (textured) add_checker(s);
    if (textured && fine) {  // 1024 x 512 texels, 4-texel squares: minified, so lookups blend mip levels
        const int tw = 1024, th = 512;
        s.texture.width = tw, s.texture.height = th;
        s.texture.rgba8.clear();
        for (int y = 0; y < th; ++y)
            for (int x = 0; x < tw; ++x) {
                const bool check = ((x / 4) + (y / 4)) % 2 == 0;
                s.texture.rgba8.insert(s.texture.rgba8.end(),
                                       {std::uint8_t(check ? 230 : 30), std::uint8_t(x / 4),
                                        std::uint8_t(check ? 40 : 220), 255});
            }
        // The uv frame of the longitude / latitude map (its gradients along each splat's axes), so the
        // lookups follow the texture across a splat and pick their mip level from it.
        s.uv_axes.resize(s.size());
        for (std::size_t i = 0; i < s.size(); ++i) {
            const glm::vec3 p = s.positions[i];
            const float rxz2 = std::max(p.x * p.x + p.z * p.z, 1e-6f);
            const glm::vec3 gu = glm::vec3(-p.z, 0.0f, p.x) / (2.0f * 3.14159265f * rxz2);
            const glm::vec3 gv(0.0f, 1.0f / (3.14159265f * std::sqrt(std::max(1.0f - p.y * p.y, 1e-6f))),
                               0.0f);
            s.uv_axes[i] = glm::vec4(glm::dot(gu, s.axis_u[i]), glm::dot(gv, s.axis_u[i]),
                                     glm::dot(gu, s.axis_v[i]), glm::dot(gv, s.axis_v[i]));
        }
    }
    for (std::size_t i = 0; quads && i < s.size(); i += 211)
        if (s.normals[i].z > 0.5f) s.axis_u[i] *= 25.0f, s.axis_v[i] *= 25.0f;
    return s;
}

class SpritePath_ : public GlRenderTest {
public:
    using GlRenderTest::add_camera, GlRenderTest::add_light, GlRenderTest::add_cloud;
    using GlRenderTest::preview_divider, GlRenderTest::sprite_path, GlRenderTest::render, GlRenderTest::reg;
    // One HQ frame through GL's point sprites and one through the CPU's, with their stats.
    struct HqPair {
        FrameImage gl, cpu;
        RenderStats gl_stats, cpu_stats;
    };
    HqPair hq_both(bool culling) {
        HqPair p;
        sprite_path = SpritePath::raster;
        p.gl = render(Quality::hq, 480, 320, culling, CullPath::cpu, RasterPath::raster);
        p.gl_stats = reg.resource<RenderStats>();
        sprite_path = SpritePath::cpu;
        p.cpu = render(Quality::hq, 480, 320, culling, CullPath::cpu, RasterPath::raster);
        p.cpu_stats = reg.resource<RenderStats>();
        return p;
    }
    FrameImage preview(SpritePath path, bool culling, RenderStats& stats) {
        sprite_path = path;
        FrameImage img = render(Quality::preview, 480, 320, culling, CullPath::cpu);
        stats = reg.resource<RenderStats>();
        return img;
    }
};

// Full-size and reduced previews, culling on and off (hidden sprites): the same coverage, colours, view
// depths and normals from either rasteriser.
void compare_rasterisers(SpritePath_& t, bool textured) {
    t.add_camera(2.6);
    t.add_light({-0.5f, -0.4f, -0.6f}, 0.15f);
    t.add_cloud(colored_sphere(textured));
    for (int divider : {1, 2})
        for (bool culling : {true, false}) {
            SCOPED_TRACE(divider == 1 ? "full size" : "half size");
            SCOPED_TRACE(culling ? "culling" : "no culling");
            t.preview_divider = divider;
            RenderStats gs, cs;
            const FrameImage gl = t.preview(SpritePath::raster, culling, gs);
            const FrameImage cpu = t.preview(SpritePath::cpu, culling, cs);
            EXPECT_EQ(gs.cpu_sprites, 0u);
            // Every sprite is the CPU's, less those with no pixel centre in their square and, with culling
            // off, the hidden back faces.
            if (culling) {
                EXPECT_GT(cs.cpu_sprites, cs.visible_points * 9 / 10);
            } else {
                EXPECT_GT(cs.cpu_sprites, cs.visible_points / 4);
                EXPECT_LT(cs.cpu_sprites, cs.visible_points / 2);
            }
            EXPECT_GE(cs.visible_quads, 5u);
            EXPECT_EQ(cs.visible_points, gs.visible_points);
            const ImageDiff d = image_diff(gl, cpu);
            EXPECT_GT(d.covered_a, 20000 / (divider * divider));
            // Pixel centres exactly on a sprite's square edge or a rim: float rounding either way.
            EXPECT_LE(d.coverage_mismatch, d.covered_a / 1000 + 2);
            EXPECT_LE(d.over_2_percent, d.covered_a / 1000 + 2);
            // Per-pixel texture lookups: the CPU's float-weight bilinear filter and llvmpipe's differ by up
            // to 1/512 (as in CullPath_.CpuAndComputeCullsRenderTheSameImage); flat colours differ only where
            // another splat won a pixel (measured: mean 1.2e-4 to 1.7e-4).
            EXPECT_LT(d.mean_color, textured && divider == 1 ? 2e-3 : 1e-3);
            EXPECT_LT(d.max_depth, 1e-3);
            int normal_off = 0;
            for (std::size_t i = 0; i < gl.normal.size(); ++i)
                normal_off += glm::length(gl.normal[i] - cpu.normal[i]) > 1e-3f;
            EXPECT_LE(normal_off, d.covered_a / 1000 + 2);
        }
}

TEST_F(SpritePath_, CpuAndGlRasterisersDrawTheSameUntexturedPreview) { compare_rasterisers(*this, false); }
TEST_F(SpritePath_, CpuAndGlRasterisersDrawTheSameTexturedPreview) { compare_rasterisers(*this, true); }

// HQ: the CPU's visibility pass (depth pushed back by eps) under GL's attribute and shade passes gives
// the same frame as GL's own, textured or not, with quads; the compute rasteriser keeps its own pass.
void compare_hq(SpritePath_& t, bool textured) {
    t.add_camera(2.6);
    t.add_light({-0.5f, -0.4f, -0.6f}, 0.15f);
    t.add_cloud(colored_sphere(textured));
    for (bool culling : {true, false}) {
        SCOPED_TRACE(culling ? "culling" : "no culling");
        const auto [gl, cpu, gs, cs] = t.hq_both(culling);
        EXPECT_EQ(gs.cpu_sprites, 0u);
        EXPECT_GT(cs.cpu_sprites, culling ? cs.visible_points * 9 / 10 : cs.visible_points / 4);
        EXPECT_GE(cs.visible_quads, 5u);
        const ImageDiff d = image_diff(gl, cpu);
        EXPECT_GT(d.covered_a, 20000);
        EXPECT_LE(d.coverage_mismatch, d.covered_a / 1000 + 2);
        EXPECT_LE(d.over_2_percent, d.covered_a / 1000 + 2);
        EXPECT_LT(d.mean_color, 1e-3);
        EXPECT_LT(d.max_depth, 1e-3);
        t.sprite_path = SpritePath::cpu;
        (void)t.render(Quality::hq, 480, 320, culling, CullPath::cpu, RasterPath::compute);
        EXPECT_EQ(t.reg.resource<RenderStats>().compute_rastered_clouds, 1u);
        EXPECT_EQ(t.reg.resource<RenderStats>().cpu_sprites, 0u);
    }
}

TEST_F(SpritePath_, CpuVisibilityPassGivesTheSameUntexturedHqFrame) { compare_hq(*this, false); }
TEST_F(SpritePath_, CpuVisibilityPassGivesTheSameTexturedHqFrame) { compare_hq(*this, true); }

// Without quads the CPU runs the attribute pass too (its sums uploaded, GL only shades): the same HQ frame,
// textured (trilinear lookups) or not, culling on and off.
void compare_cpu_hq(SpritePath_& t, bool textured) {
    t.add_camera(3.2);  // the whole sphere in the frame: no sprite centred outside it (those are quads)
    t.add_light({-0.5f, -0.4f, -0.6f}, 0.15f);
    t.add_cloud(colored_sphere(textured, false, true));
    for (bool culling : {true, false}) {
        SCOPED_TRACE(culling ? "culling" : "no culling");
        const auto [gl, cpu, gs, cs] = t.hq_both(culling);
        EXPECT_FALSE(gs.cpu_attribute);
        EXPECT_TRUE(cs.cpu_attribute);
        EXPECT_EQ(cs.visible_quads, 0u);
        const ImageDiff d = image_diff(gl, cpu);
        EXPECT_GT(d.covered_a, 15000);
        EXPECT_LE(d.coverage_mismatch, d.covered_a / 1000 + 2);
        EXPECT_LE(d.over_2_percent, d.covered_a / 1000 + 2);
        // Textured: the CPU's float-weight trilinear filter against llvmpipe's (see the previews above).
        EXPECT_LT(d.mean_color, textured ? 2e-3 : 1e-3);
        EXPECT_LT(d.max_depth, 1e-3);
    }
}

TEST_F(SpritePath_, CpuAttributePassGivesTheSameUntexturedHqFrame) { compare_cpu_hq(*this, false); }
TEST_F(SpritePath_, CpuAttributePassGivesTheSameTexturedHqFrame) { compare_cpu_hq(*this, true); }

// automatic: the CPU on a software rasteriser (llvmpipe), GL on a hardware GPU, in preview and HQ frames.
TEST_F(SpritePath_, AutomaticTakesTheCpuOnSoftwareGlOnly) {
    add_camera(2.6);
    add_light({-0.5f, -0.4f, -0.6f}, 0.15f);
    add_cloud(colored_sphere(false));
    RenderStats stats;
    (void)preview(SpritePath::automatic, true, stats);
    const bool software = gfx::software_rasterizer();
    if (software) EXPECT_GT(stats.cpu_sprites, 1000u);
    else EXPECT_EQ(stats.cpu_sprites, 0u);
    (void)render(Quality::hq, 480, 320, true, CullPath::cpu, RasterPath::raster);
    if (software) EXPECT_GT(reg.resource<RenderStats>().cpu_sprites, 1000u);
    else EXPECT_EQ(reg.resource<RenderStats>().cpu_sprites, 0u);
}

}  // namespace
