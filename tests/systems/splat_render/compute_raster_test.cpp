// The compute rasteriser (compute_raster.h, RenderSettings::raster_path) against the raster path: the same
// image (coverage, colour, depth) for small and large splats, culling on and off, textured, deformed by the
// FFD compute pass; the hybrid split hands exactly the sprites larger than SFFD_RASTER_MAX_SPRITE to the
// rasteriser; the fixed-point sums hold 65,000 contributions in one pixel (bound: 65,535).
#include <algorithm>
#include <cmath>
#include <vector>

#include "runtime/gfx/dispatch.h"
#include "shaders/splat_render/compute_raster.h"
#include "systems/ffd/components.h"
#include "systems/ffd/ffd_system.h"
#include "systems/ffd/lattice.h"
#include "systems/ffd/operations.h"
#include "tests/systems/splat_render/gl_fixture.h"
#include "tests/systems/splat_render/test_scenes.h"
#include "systems/residency/residency_system.h"

using namespace sffd;
using namespace sffd::render;
using namespace sffd::render::test;

namespace {

class ComputeRaster_ : public GlRenderTest {
protected:
    FrameImage render_path(RasterPath raster, bool culling = true, CullPath cull = CullPath::automatic,
                           int w = 480, int h = 320) {
        RenderSettings s;
        s.quality = Quality::hq, s.width = w, s.height = h, s.culling = culling, s.time_passes = true;
        s.cull_path = cull, s.raster_path = raster, s.aux_outputs = true;
        reg.set_resource<RenderSettings>(s);
        residency_system(reg, FrameContext{});
        render_system(reg, FrameContext{});
        auto img = capture_frame(reg);
        EXPECT_TRUE(img.ok());
        return img.ok() ? std::move(img.value()) : FrameImage{};
    }
};

// The sphere from near (sprites up to ~15 px: the hybrid splits) to far (~1 px splats), untextured and
// textured, culling on and off, both cull paths: the two raster paths agree.
TEST_F(ComputeRaster_, RendersTheSameImageAsTheRasterPath) {
    Camera& cam = add_camera(3.0);
    add_light({-0.5f, -0.4f, -0.6f}, 0.15f);
    for (bool textured : {false, true}) {
        SplatCloud cloud = fibonacci_sphere(20000, 1.0, 0.8, 0xff3399ccu);
        if (textured) add_checker(cloud);
        const ecs::Entity e = add_cloud(std::move(cloud));
        for (double distance : {1.8, 2.2, 2.6, 3.0, 8.0, 20.0}) {
            cam.eye = glm::dvec3(0.0, 0.0, distance);
            cam.far_plane = 40.0f;
            for (bool culling : {true, false})
                for (CullPath cull : {CullPath::compute, CullPath::cpu}) {
                    const std::string what = std::string(textured ? "textured" : "untextured") +
                                             ", distance " + std::to_string(distance) +
                                             (culling ? "" : ", no culling") +
                                             (cull == CullPath::cpu ? ", cpu cull" : ", compute cull");
                    const FrameImage raster = render_path(RasterPath::raster, culling, cull);
                    EXPECT_EQ(reg.resource<RenderStats>().compute_rastered_clouds, 0u) << what;
                    const FrameImage compute = render_path(RasterPath::compute, culling, cull);
                    const RenderStats& st = reg.resource<RenderStats>();
                    EXPECT_EQ(st.compute_rastered_clouds, 1u) << what;
                    EXPECT_EQ(st.cpu_culled_clouds, cull == CullPath::cpu ? 1u : 0u) << what;
                    ASSERT_TRUE(st.counts_valid) << what;
                    if (distance >= 8.0) {
                        EXPECT_EQ(st.raster_sprites, 0u) << what;  // every sprite <= 8 px
                    }
                    if (distance <= 1.8 && culling) {
                        EXPECT_EQ(st.raster_sprites, st.visible_points) << what;  // every front sprite > 8 px
                    } else if (distance <= 2.6) {
                        EXPECT_GT(st.raster_sprites, 100u) << what;  // the hybrid split: both paths draw
                        EXPECT_LT(st.raster_sprites + 100u, st.visible_points) << what;
                    }
                    const ImageDiff c = image_diff(raster, compute);
                    EXPECT_GT(c.covered_a, distance >= 20.0 ? 400 : 5000) << what;
                    // Measured on llvmpipe: coverage identical; PSNR 86.5-105 dB where the compute
                    // rasteriser draws (fixed-point rounding of the sums), largest channel difference 0.0039
                    // (a rim pixel of tiny weight), depth within 3.8e-6.
                    EXPECT_LE(c.coverage_mismatch, 2) << what;
                    EXPECT_GT(c.psnr, 60.0) << what;
                    EXPECT_LT(c.max_color, 1e-2) << what;
                    EXPECT_LT(c.max_depth, 1e-4) << what;
                    // No holes: every pixel inside the analytic silhouette is covered.
                    const Coverage cov = ellipsoid_coverage(compute, cam, glm::dvec3(1.0));
                    EXPECT_EQ(cov.holes, 0) << what;
                    EXPECT_EQ(cov.far_side, 0) << what;
                }
        }
        reg.destroy(e);
    }
}

// Two clouds in one frame, one textured and moved by a Transform, one not, overlapping on screen, with
// some large splats: each cloud's lists, draws and counts stay its own, and the image matches the raster
// path (both cull paths).
TEST_F(ComputeRaster_, SeveralCloudsInOneFrame) {
    add_camera(4.0);
    add_light({-0.5f, -0.4f, -0.6f}, 0.15f);
    SplatCloud left = fibonacci_sphere(20000, 1.0, 0.8, 0xff3399ccu);
    add_checker(left);
    for (std::size_t i = 0; i < left.size(); i += 97) left.axis_u[i] *= 6.0f, left.axis_v[i] *= 6.0f;
    const ecs::Entity a = add_cloud(std::move(left));
    reg.emplace<Transform>(a, Transform{.translation = glm::dvec3(-0.6, 0.0, 0.0)});
    const ecs::Entity b = add_cloud(fibonacci_sphere(30000, 0.8, 0.8, 0xffcc6633u));
    reg.emplace<Transform>(b, Transform{.translation = glm::dvec3(0.7, 0.1, 0.3)});
    for (CullPath cull : {CullPath::compute, CullPath::cpu}) {
        const char* what = cull == CullPath::cpu ? "cpu cull" : "compute cull";
        const FrameImage raster = render_path(RasterPath::raster, true, cull);
        const RenderStats rs = reg.resource<RenderStats>();
        const FrameImage compute = render_path(RasterPath::compute, true, cull);
        const RenderStats cs = reg.resource<RenderStats>();
        EXPECT_EQ(cs.compute_rastered_clouds, 2u) << what;
        EXPECT_EQ(cs.visible_points, rs.visible_points) << what;
        EXPECT_GT(cs.raster_sprites, 20u) << what;  // the enlarged splats of the textured cloud
        EXPECT_LT(cs.raster_sprites, cs.visible_points / 4) << what;
        const ImageDiff c = image_diff(raster, compute);
        EXPECT_GT(c.covered_a, 20000) << what;
        EXPECT_LE(c.coverage_mismatch, 2) << what;
        EXPECT_GT(c.psnr, 60.0) << what;
        EXPECT_LT(c.max_depth, 1e-4) << what;
    }
}

// Exactly the sprites larger than SFFD_RASTER_MAX_SPRITE go to the rasteriser: every 211th splat facing
// the camera is 25x larger (~40 px), the others are ~2 px; the big ones are counted independently here.
TEST_F(ComputeRaster_, HybridSendsLargeSpritesToTheRasterPath) {
    add_camera(6.0);
    add_light({-0.5f, -0.4f, -0.6f}, 0.15f);
    SplatCloud cloud = fibonacci_sphere(20000);
    std::uint32_t enlarged = 0;
    for (std::size_t i = 0; i < cloud.size(); i += 211)
        if (cloud.normals[i].z > 0.5f) cloud.axis_u[i] *= 25.0f, cloud.axis_v[i] *= 25.0f, ++enlarged;
    add_cloud(std::move(cloud));
    ASSERT_GT(enlarged, 10u);
    const FrameImage raster = render_path(RasterPath::raster, true, CullPath::compute);
    const RenderStats rs = reg.resource<RenderStats>();
    const FrameImage compute = render_path(RasterPath::compute, true, CullPath::compute);
    const RenderStats cs = reg.resource<RenderStats>();
    ASSERT_TRUE(cs.counts_valid);
    EXPECT_EQ(cs.raster_sprites, enlarged);
    EXPECT_EQ(rs.raster_sprites, 0u);  // the raster path splits nothing
    EXPECT_EQ(cs.visible_points, rs.visible_points);
    const ImageDiff c = image_diff(raster, compute);
    EXPECT_GT(c.covered_a, 5000);
    EXPECT_LE(c.coverage_mismatch, 4);
    EXPECT_GT(c.psnr, 40.0);

    // Through a 2D dispatch grid (2 groups per row) the same split.
    gfx::ScopedDispatchLimit two(2);
    const FrameImage grid = render_path(RasterPath::compute, true, CullPath::compute);
    EXPECT_EQ(reg.resource<RenderStats>().raster_sprites, enlarged);
    EXPECT_GT(image_diff(compute, grid).psnr, 60.0);
}

// 65,535 coincident splats facing the camera, centred on a pixel centre: that pixel gets 65,535
// contributions of weight 1 (w_q = 65,536), sums up to 65,535 x 65,536 = 2^32 - 65,536, the largest that
// fits (SFFD_RASTER_MAX_CONTRIBUTIONS); it and its neighbours shade exactly like one splat. (Measured: 65,537
// splats wrap the words and the centre pixel's colour is wrong.)
TEST_F(ComputeRaster_, FixedPointSumsHoldAtTheBound) {
    static_assert(SFFD_RASTER_MAX_CONTRIBUTIONS == 65535);
    Camera& cam = add_camera(3.0);
    cam.far_plane = 10.0f;
    add_light({-0.3f, -0.2f, -1.0f}, 0.2f);
    const int w = 320, h = 240;
    const glm::dvec3 ray = pixel_ray(cam, w / 2, h / 2, w, h);  // view-axis component 1
    const glm::vec3 centre(cam.eye + 2.0 * ray);
    auto stack = [&](std::size_t n) {
        SplatCloud c;
        c.positions.assign(n, centre);
        c.normals.assign(n, glm::vec3(0.0f, 0.0f, 1.0f));
        c.axis_u.assign(n, glm::vec3(0.01f, 0.0f, 0.0f));  // ~1.5 px radius at depth 2, 240 px tall
        c.axis_v.assign(n, glm::vec3(0.0f, 0.01f, 0.0f));
        c.colors.assign(n, 0xff3366ccu);
        return c;
    };
    const ecs::Entity one = add_cloud(stack(1));
    const FrameImage single = render_path(RasterPath::compute, true, CullPath::compute, w, h);
    reg.destroy(one);
    add_cloud(stack(SFFD_RASTER_MAX_CONTRIBUTIONS));
    const FrameImage many = render_path(RasterPath::compute, true, CullPath::compute, w, h);
    EXPECT_EQ(reg.resource<RenderStats>().compute_rastered_clouds, 1u);
    int covered = 0;
    double max_color = 0.0, max_depth = 0.0;
    for (int y = 0; y < single.height; ++y)
        for (int x = 0; x < single.width; ++x) {
            EXPECT_EQ(single.covered(x, y), many.covered(x, y)) << x << ", " << y;
            if (!single.covered(x, y) || !many.covered(x, y)) continue;
            ++covered;
            const std::size_t i = single.index(x, y);
            const glm::vec4 e = glm::abs(single.color[i] - many.color[i]);
            max_color = std::max(max_color, double(std::max({e.x, e.y, e.z})));
            max_depth = std::max(max_depth, double(std::abs(single.depth[i] - many.depth[i])));
        }
    EXPECT_GE(covered, 4);
    EXPECT_TRUE(many.covered(w / 2, h / 2));
    EXPECT_LT(max_color, 2e-3);
    EXPECT_LT(max_depth, 1e-3);
}

// A sphere twisted by a lattice on the FFD compute pass (its splats exist only on the GPU): the compute
// rasteriser draws the deformed splats like the raster path.
TEST_F(ComputeRaster_, MatchesTheRasterPathOnGpuDeformedSplats) {
    add_camera(3.0);
    add_light({-0.5f, -0.4f, -0.6f}, 0.15f);
    const ecs::Entity cloud = add_cloud(fibonacci_sphere(20000));
    const ecs::Entity le = add_lattice(cloud);
    ffd::twist_graded(reg.patch<Lattice>(le), ffd::all_control_points(reg.get<Lattice>(le)), {0, 1, 0}, 0.9,
                      glm::dvec3(0.0));
    reg.set_resource<FfdSettings>().force_gpu = true;
    residency_system(reg, {});  // the rest splats the compute pass reads
    ffd_system(reg, {});
    ASSERT_TRUE(ffd::output_on_gpu(reg, cloud));
    const FrameImage raster = render_path(RasterPath::raster);
    const FrameImage compute = render_path(RasterPath::compute);
    EXPECT_EQ(reg.resource<RenderStats>().compute_culled_clouds, 1u);
    EXPECT_EQ(reg.resource<RenderStats>().compute_rastered_clouds, 1u);
    const ImageDiff c = image_diff(raster, compute);
    EXPECT_GT(c.covered_a, 10000);
    EXPECT_LE(c.coverage_mismatch, 4);
    EXPECT_GT(c.psnr, 40.0);
    EXPECT_LT(c.max_depth, 5e-3);
    ffd_release_gpu(reg);
}

// automatic: the compute rasteriser when the splats' mean on-screen diameter is at most 6 px on a hardware
// GPU, 1.8 px on a software rasterizer (llvmpipe's measured break-even); else the rasteriser.
TEST_F(ComputeRaster_, AutomaticChoiceFollowsTheSplatSize) {
    const bool software = gfx::software_rasterizer();
    Camera& cam = add_camera(10.0);
    add_light({-0.5f, -0.4f, -0.6f}, 0.15f);
    add_cloud(fibonacci_sphere(20000));  // mean diameter 0.0201 * 2.414 * 320 / distance px
    render_path(RasterPath::automatic);  // 1.6 px
    EXPECT_EQ(reg.resource<RenderStats>().compute_rastered_clouds, 1u);
    cam.eye = glm::dvec3(0.0, 0.0, 4.0);  // 3.9 px
    render_path(RasterPath::automatic);
    EXPECT_EQ(reg.resource<RenderStats>().compute_rastered_clouds, software ? 0u : 1u);
    cam.eye = glm::dvec3(0.0, 0.0, 1.5);  // 10.3 px
    render_path(RasterPath::automatic);
    EXPECT_EQ(reg.resource<RenderStats>().compute_rastered_clouds, 0u);
    // Preview never uses it, whatever the setting.
    RenderSettings s = reg.resource<RenderSettings>();
    s.quality = Quality::preview, s.raster_path = RasterPath::compute;
    reg.set_resource<RenderSettings>(s);
    render_system(reg, FrameContext{});
    EXPECT_EQ(reg.resource<RenderStats>().compute_rastered_clouds, 0u);
}

}  // namespace
