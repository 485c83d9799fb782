// CPU parts of the renderer: image files, sRGB, splat packing, camera matrices, sprite bounds, CPU cull.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstring>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <random>

#include <glm/gtc/matrix_transform.hpp>

#include "runtime/gfx/point_marks.h"
#include "systems/splat_render/camera_math.h"
#include "systems/splat_render/cpu_raster.h"
#include "systems/splat_render/cpu_cull.h"
#include "systems/splat_render/image_io.h"
#include "systems/splat_render/splat_pack.h"
#include "systems/splat_render/splat_render.h"
#include "tests/systems/splat_render/test_scenes.h"

namespace fs = std::filesystem;
using namespace sffd;
using namespace sffd::render;

namespace {

fs::path temp_dir() {
    fs::path d = fs::temp_directory_path() / ("sffd_render_cpu_" + std::to_string(::getpid()));
    fs::create_directories(d);
    return d;
}

FrameImage gradient(int w, int h) {
    FrameImage img;
    img.width = w, img.height = h;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const bool bg = x == 0 && y == 0;
            img.color.push_back(bg ? glm::vec4(0)
                                   : glm::vec4(float(x) / float(w), float(y) / float(h), 0.25f, 1.0f));
            img.depth.push_back(bg ? std::numeric_limits<float>::infinity()
                                   : 1.0f + float(x) * 0.01f + float(y));
            img.normal.push_back(bg ? glm::vec3(0)
                                    : glm::normalize(glm::vec3(float(x) - 3.5f, float(y) - 2.5f, 4.0f)));
        }
    return img;
}

}  // namespace

TEST(RenderSrgb, MatchesTheStandardCurve) {
    EXPECT_NEAR(linear_to_srgb(0.0f), 0.0f, 1e-7);
    EXPECT_NEAR(linear_to_srgb(1.0f), 1.0f, 1e-6);
    EXPECT_NEAR(linear_to_srgb(0.0031308f), 0.0031308f * 12.92f, 1e-6);
    EXPECT_NEAR(linear_to_srgb(0.5f), 0.735357f, 1e-5);  // IEC 61966-2-1
    EXPECT_EQ(encode_srgb8(0.2158605f), 128);
    for (float v = 0.0f; v <= 1.0f; v += 0.01f) EXPECT_NEAR(srgb_to_linear(linear_to_srgb(v)), v, 1e-5);
}

// The window part the display copy fills: UI units scaled to framebuffer pixels (a HiDPI window has two per
// unit), every touched pixel, rows flipped to GL's bottom-up order, clipped; no window size: everything.
TEST(RenderDisplayViewport, ScalesFlipsAndClipsToTheWindow) {
    // The editor's layout at 1280x720: columns 258 and 320 wide, menu 19 high, the Timeline from y = 622.
    const DisplayViewport view{258.0f, 19.0f, 702.0f, 603.0f, 1280.0f, 720.0f};
    EXPECT_EQ(display_viewport_pixels(view, 1280, 720), glm::ivec4(258, 98, 702, 603));
    EXPECT_EQ(display_viewport_pixels(view, 2560, 1440), glm::ivec4(516, 196, 1404, 1206)) << "HiDPI";
    const DisplayViewport fractional{10.5f, 0.25f, 20.0f, 10.0f, 100.0f, 50.0f};
    EXPECT_EQ(display_viewport_pixels(fractional, 100, 50), glm::ivec4(10, 39, 21, 11)) << "touched pixels";
    const DisplayViewport outside{-20.0f, 40.0f, 200.0f, 30.0f, 100.0f, 50.0f};
    EXPECT_EQ(display_viewport_pixels(outside, 100, 50), glm::ivec4(0, 0, 100, 10)) << "clipped";
    EXPECT_EQ(display_viewport_pixels(DisplayViewport{}, 64, 32), glm::ivec4(0, 0, 64, 32)) << "no UI";
    const DisplayViewport nan_size{0.0f, 0.0f, 10.0f, 10.0f, std::numeric_limits<float>::quiet_NaN(), 50.0f};
    EXPECT_EQ(display_viewport_pixels(nan_size, 64, 32), glm::ivec4(0, 0, 64, 32));
}

TEST(RenderImageIo, PngRoundTripKeepsSrgbBytesAndAlpha) {
    const FrameImage img = gradient(8, 6);
    const Rgba8Image rgba = to_rgba8(img);
    EXPECT_EQ(rgba.at(0, 0)[3], 0);  // background stays transparent
    EXPECT_EQ(rgba.at(5, 3)[3], 255);
    EXPECT_EQ(rgba.at(5, 3)[0], encode_srgb8(5.0f / 8.0f));
    const fs::path path = temp_dir() / "round.png";
    ASSERT_TRUE(write_png(path, rgba).ok());
    auto back = read_png(path);
    ASSERT_TRUE(back.ok()) << back.message();
    EXPECT_EQ(back->width, 8);
    EXPECT_EQ(back->height, 6);
    EXPECT_EQ(back->pixels, rgba.pixels);
}

TEST(RenderImageIo, BackgroundFillsTransparentPixels) {
    const Rgba8Image rgba = to_rgba8(gradient(4, 4), glm::vec3(1.0f, 0.0f, 0.0f));
    EXPECT_EQ(rgba.at(0, 0)[0], 255);
    EXPECT_EQ(rgba.at(0, 0)[1], 0);
    EXPECT_EQ(rgba.at(0, 0)[3], 255);
}

TEST(RenderImageIo, BackgroundBlendsInDisplaySpaceAs3dgsViewersDo) {
    FrameImage img = gradient(2, 1);
    img.color[0] = glm::vec4(1.0f, 1.0f, 1.0f, 0.5f);   // a half-covered white edge
    img.color[1] = glm::vec4(0.25f, 0.5f, 1.0f, 1.0f);  // fully covered
    const Rgba8Image black = to_rgba8(img, glm::vec3(0.0f));
    // Display space: 0.5 * 255 = 127.5 (127 or 128 after float rounding); a linear blend would give
    // encode_srgb8(0.5) = 188.
    EXPECT_NEAR(double(black.at(0, 0)[0]), 127.5, 0.5);
    EXPECT_EQ(black.at(0, 0)[3], 255);
    const Rgba8Image white = to_rgba8(img, glm::vec3(1.0f));
    EXPECT_EQ(white.at(0, 0)[0], 255);
    // Covered pixels are the colour itself, whatever the background.
    for (int k = 0; k < 3; ++k) EXPECT_EQ(black.at(1, 0)[k], encode_srgb8(img.color[1][k])) << k;
    EXPECT_EQ(black.at(1, 0)[3], 255);
}

TEST(RenderImageIo, ExrHoldsHalfRgbaFloatZAndNormals) {
    const FrameImage img = gradient(8, 6);
    const fs::path path = temp_dir() / "round.exr";
    ASSERT_TRUE(write_exr(path, img).ok());
    auto back = read_exr(path);
    ASSERT_TRUE(back.ok()) << back.message();
    ASSERT_EQ(back->width, 8);
    ASSERT_EQ(back->height, 6);
    ASSERT_EQ(back->depth.size(), img.depth.size());
    ASSERT_EQ(back->normal.size(), img.normal.size());
    for (std::size_t i = 0; i < img.color.size(); ++i) {
        for (int c = 0; c < 4; ++c) EXPECT_NEAR(back->color[i][c], img.color[i][c], 1e-3);  // half
        EXPECT_EQ(back->depth[i], img.depth[i]);                                            // float: exact
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(back->normal[i][c], img.normal[i][c], 1e-3);
    }
    EXPECT_TRUE(std::isinf(back->depth[0]));
}

TEST(RenderImageIo, BadFilesAreNamedInTheError) {
    const fs::path path = temp_dir() / "garbage.png";
    std::ofstream(path) << "not an image";
    auto png = read_png(path);
    ASSERT_FALSE(png.ok());
    EXPECT_NE(png.message().find(path.string()), std::string::npos);
    auto exr = read_exr(path);
    ASSERT_FALSE(exr.ok());
    EXPECT_NE(exr.message().find(path.string()), std::string::npos);
    Rgba8Image empty;
    auto st = write_png(temp_dir() / "empty.png", empty);
    EXPECT_FALSE(st.ok());
    auto missing_dir = write_png(temp_dir() / "no" / "such" / "dir.png", to_rgba8(gradient(2, 2)));
    EXPECT_FALSE(missing_dir.ok());
}

TEST(RenderPack, GpuSplatLayoutCarriesEveryAttribute) {
    SplatCloud c = test::fibonacci_sphere(10);
    c.colors[3] = 0x80402010u;
    const auto packed = pack_splats(c);
    ASSERT_EQ(packed.size(), 10u);
    const auto& s = packed[3];
    EXPECT_EQ(s.center[0], c.positions[3].x);
    EXPECT_EQ(s.center[2], c.positions[3].z);
    EXPECT_EQ(std::bit_cast<std::uint32_t>(s.center[3]), 0x80402010u);
    EXPECT_EQ(s.normal[1], c.normals[3].y);
    EXPECT_EQ(s.normal[3], 1.0f);
    EXPECT_EQ(s.axis_u[0], c.axis_u[3].x);
    EXPECT_EQ(s.axis_v[2], c.axis_v[3].z);
    EXPECT_EQ(s.axis_u[3], c.uvs[3].x);
    EXPECT_EQ(s.axis_v[3], c.uvs[3].y);
}

// The base colour is the material's, applied when drawing (FrameBlock::base_color): packing does not
// depend on the material, so a material edit re-uploads nothing.
TEST(RenderPack, SplatsWithoutColoursPackWhite) {
    SplatCloud c = test::fibonacci_sphere(4);
    c.colors.clear();
    const auto packed = pack_splats(c);
    for (const gpu::GpuSplat& s : packed) EXPECT_EQ(std::bit_cast<std::uint32_t>(s.center[3]), 0xffffffffu);
}

TEST(RenderCamera, FramingCameraSeesTheWholeSphere) {
    const glm::dvec3 center(5.0, -2.0, 1.0);
    const double radius = 3.0, aspect = 16.0 / 9.0;
    const Camera cam = framing_camera(center, radius, aspect);
    const glm::dmat4 vp = projection_matrix(cam, aspect) * view_matrix(cam);
    for (const glm::dvec3& d : {glm::dvec3(1, 0, 0), glm::dvec3(-1, 0, 0), glm::dvec3(0, 1, 0),
                                glm::dvec3(0, -1, 0), glm::dvec3(0, 0, 1), glm::dvec3(0, 0, -1)}) {
        const glm::dvec4 clip = vp * glm::dvec4(center + d * radius, 1.0);
        EXPECT_LT(std::abs(clip.x / clip.w), 1.0);
        EXPECT_LT(std::abs(clip.y / clip.w), 1.0);
        EXPECT_GT(clip.z / clip.w, -1.0);
        EXPECT_LT(clip.z / clip.w, 1.0);
    }
    EXPECT_NEAR(view_depth(cam, center), glm::length(cam.eye - center), 1e-9);
}

TEST(RenderCamera, ModelMatrixAppliesOriginThenTransform) {
    Transform t;
    t.translation = glm::dvec3(1, 2, 3);
    t.scale = glm::dvec3(2.0);
    const glm::dmat4 m = model_matrix(&t, glm::dvec3(1e6, 0, 0));
    const glm::dvec3 p = glm::dvec3(m * glm::dvec4(0.5, 0, 0, 1));
    EXPECT_NEAR(p.x, 1.0 + 2.0 * (1e6 + 0.5), 1e-6);
    EXPECT_NEAR(p.y, 2.0, 1e-12);
}

TEST(RenderPack, BoundingSphereContainsEverySplat) {
    const SplatCloud c = test::fibonacci_sphere(1000, 2.0);
    const BoundingSphere b = bounding_sphere(c);
    EXPECT_NEAR(glm::length(b.center), 0.0, 0.01);
    EXPECT_GE(b.radius, 2.0);
    EXPECT_LT(b.radius, 2.3);
}

namespace {

// A frame block for a camera at (0, 0, distance) looking down -z, 45 degrees, 1280x720.
gpu::FrameBlock test_frame(double distance = 3.0) {
    Camera cam;
    cam.eye = glm::dvec3(0.0, 0.0, distance);
    cam.near_plane = 0.1f, cam.far_plane = 10.0f;
    gpu::FrameBlock f = camera_frame_block(view_matrix(cam), projection_matrix(cam, 1280.0 / 720.0), 1280,
                                           720, 1.0f, 255.0f, true);
    f.light_dir[0] = glm::vec4(glm::normalize(glm::vec3(0.3f, 0.5f, 1.0f)), 0.0f);
    f.light_color[0] = glm::vec4(1.0f);
    f.material = glm::vec4(0.3f, 32.0f, 0.0f, 0.0f);
    f.counts = glm::uvec4(0u, 1u, 0u, 0u);
    return f;
}

}  // namespace

// The sprite box against brute force: project 4096 points of the ellipse's rim in double precision.
// The square must hold every projected rim point (in pixels) and be no larger than the rim's box
// (tight: its side is the box's larger side, its centre the box's centre).
TEST(RenderSprite, EllipseBoxHoldsTheProjectedRimAndIsTight) {
    const gpu::FrameBlock f = test_frame();
    const glm::dmat4 proj(f.projection);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    int checked = 0;
    for (int trial = 0; trial < 500; ++trial) {
        // Random view-space centre in front of the camera, random orientation and radii (some tiny, far).
        const glm::dvec3 c(uni(rng) * 1.2, uni(rng) * 0.7, -2.0 - 3.0 * (uni(rng) + 1.0));
        const glm::dvec3 n = glm::normalize(glm::dvec3(uni(rng), uni(rng), uni(rng)));
        const glm::dvec3 t = glm::normalize(glm::cross(n, glm::dvec3(uni(rng), uni(rng), uni(rng))));
        const double scale = trial % 3 == 0 ? 0.002 : 0.05;
        const glm::dvec3 u = t * scale * (0.5 + 0.5 * (uni(rng) + 1.0)),
                         v = glm::cross(n, t) * scale * (0.3 + (uni(rng) + 1.0));
        const glm::vec3 box = ellipse_sprite(f, glm::vec3(c), glm::vec3(u), glm::vec3(v));
        ASSERT_GT(box.z, 0.0f);
        glm::dvec2 lo(1e30), hi(-1e30);
        for (int k = 0; k < 4096; ++k) {
            const double a = 2.0 * std::numbers::pi * k / 4096.0;
            const glm::dvec4 clip = proj * glm::dvec4(c + u * std::cos(a) + v * std::sin(a), 1.0);
            const glm::dvec2 px = (glm::dvec2(clip) / clip.w * 0.5 + 0.5) * glm::dvec2(1280.0, 720.0);
            lo = glm::min(lo, px), hi = glm::max(hi, px);
        }
        const glm::dvec2 centre = (glm::dvec2(box.x, box.y) * 0.5 + 0.5) * glm::dvec2(1280.0, 720.0);
        const double half = 0.5 * double(box.z);
        const double tol = 1e-3 + 1e-5 * glm::length(centre);  // float evaluation
        EXPECT_LE(centre.x - half, lo.x + tol) << trial;
        EXPECT_GE(centre.x + half, hi.x - tol) << trial;
        EXPECT_LE(centre.y - half, lo.y + tol) << trial;
        EXPECT_GE(centre.y + half, hi.y - tol) << trial;
        const glm::dvec2 extent = hi - lo;
        EXPECT_NEAR(box.z, std::max(extent.x, extent.y), 2e-3 * std::max(1.0, std::max(extent.x, extent.y)))
            << trial;
        ++checked;
    }
    EXPECT_EQ(checked, 500);
    // Reaching the near plane: no box.
    EXPECT_LT(ellipse_sprite(f, glm::vec3(0.0f, 0.0f, -0.12f), glm::vec3(0.0f, 0.0f, 0.05f),
                             glm::vec3(0.05f, 0.0f, 0.0f))
                  .z,
              0.0f);
}

// The CPU cull against its definition: each splat classified by an independent double-precision
// evaluation (back face, frustum ball, sprite vs quad), records in splat order, counts consistent.
TEST(RenderCpuCull, ClassifiesEverySplatLikeTheDefinition) {
    SplatCloud cloud = test::fibonacci_sphere(5000);
    // A few splats too large for a sprite (quads) and one whose centre is off-screen left.
    for (std::size_t i = 0; i < 5000; i += 53)
        if (cloud.normals[i].z > 0.6f) cloud.axis_u[i] *= 40.0f, cloud.axis_v[i] *= 40.0f;
    cloud.positions[1] = glm::vec3(-2.3f, 0.0f, 0.9f), cloud.normals[1] = glm::vec3(0, 0, 1);
    cloud.axis_u[1] = glm::vec3(0.3f, 0, 0), cloud.axis_v[1] = glm::vec3(0, 0.3f, 0);
    // Non-finite centres (a broken deformation) are dropped, not drawn.
    const std::size_t front = std::size_t(std::find_if(cloud.normals.begin(), cloud.normals.end(),
                                                       [](const glm::vec3& n) { return n.z > 0.9f; }) -
                                          cloud.normals.begin());
    cloud.positions[front].x = std::numeric_limits<float>::quiet_NaN();
    cloud.positions[front + 1].y = std::numeric_limits<float>::infinity();
    const std::vector<gpu::GpuSplat> splats = pack_splats(cloud);
    for (bool lit : {false, true}) {
        gpu::FrameBlock f = test_frame();
        f.counts.w = lit ? 1u : 0u;
        CpuCullResult out;
        cull_splats_cpu(splats, f, {}, out);
        const glm::dmat4 mv(f.model_view), proj(f.projection);
        std::vector<std::uint32_t> sprites, quads;
        for (std::uint32_t i = 0; i < splats.size(); ++i) {
            const glm::dvec3 c = glm::dvec3(mv * glm::dvec4(glm::dvec3(cloud.positions[i]), 1.0));
            if (!std::isfinite(c.x + c.y + c.z)) continue;
            if (glm::dot(glm::dvec3(cloud.normals[i]), c) > 0.0) continue;  // back-facing (view = world here)
            const double r =
                std::max(glm::length(glm::dvec3(cloud.axis_u[i])), glm::length(glm::dvec3(cloud.axis_v[i])));
            // The symmetric frustum's side planes through the eye, as a ball test.
            const double p00 = proj[0][0], p11 = proj[1][1], depth = -c.z;
            if ((depth - p00 * std::abs(c.x)) / std::sqrt(p00 * p00 + 1.0) < -r ||
                (depth - p11 * std::abs(c.y)) / std::sqrt(p11 * p11 + 1.0) < -r)
                continue;
            const glm::vec3 box =
                ellipse_sprite(f, glm::vec3(c), glm::vec3(cloud.axis_u[i]), glm::vec3(cloud.axis_v[i]));
            (box.z > 255.0f || std::abs(box.x) > 1.0f || std::abs(box.y) > 1.0f ? quads : sprites)
                .push_back(i);
        }
        ASSERT_EQ(out.visible_records, sprites.size());
        ASSERT_EQ(out.visible_quads, quads.size());
        EXPECT_GE(quads.size(), 3u);  // the enlarged splats on the visible side, and the off-screen one
        std::vector<std::uint32_t> got_quads;
        std::vector<SplatRecord> got;
        CpuCullResult::for_each_run(out.quads, out.quad_counts, out.block,
                                    [&](std::size_t, const std::uint32_t* p, std::size_t k) {
                                        got_quads.insert(got_quads.end(), p, p + k);
                                    });
        CpuCullResult::for_each_run(
            out.records, out.record_counts, out.block,
            [&](std::size_t, const SplatRecord* p, std::size_t k) { got.insert(got.end(), p, p + k); });
        EXPECT_EQ(got_quads, quads);
        ASSERT_EQ(got.size(), sprites.size());
        for (std::size_t k = 0; k < got.size(); ++k) {
            const std::uint32_t i = sprites[k];
            const glm::dvec3 c = glm::dvec3(mv * glm::dvec4(glm::dvec3(cloud.positions[i]), 1.0));
            // The record's ray cast hits the splat centre: the ray through the centre gives t = depth,
            // s = q = 0; and the plane is the splat's plane (normal . (p - c) = 0 <=> plane . p = 1).
            const glm::dvec3 ray = c / -c.z;
            const double t = 1.0 / glm::dot(glm::dvec3(got[k].plane), ray);
            // (float set-up: near the silhouette the ray grazes the plane and rounding grows; 1e-2 of the
            // splat's radius is far below a pixel here)
            EXPECT_NEAR(t, -c.z, 1e-4 * -c.z) << i;
            EXPECT_NEAR(t * glm::dot(glm::dvec3(got[k].dual_u), ray) - double(got[k].dual_u.w), 0.0, 1e-2)
                << i;
            EXPECT_NEAR(t * glm::dot(glm::dvec3(got[k].dual_v), ray) - double(got[k].dual_v.w), 0.0, 1e-2)
                << i;
            // The rim point c + u has elliptical radius 1.
            const glm::dvec3 rim = c + glm::dvec3(cloud.axis_u[i]);
            const double s = glm::dot(glm::dvec3(got[k].dual_u), rim) - double(got[k].dual_u.w),
                         q = glm::dot(glm::dvec3(got[k].dual_v), rim) - double(got[k].dual_v.w);
            EXPECT_NEAR(s * s + q * q, 1.0, 1e-2) << i;
            EXPECT_NEAR(got[k].plane.w, f.params.x * glm::length(cloud.axis_u[i]), 1e-6) << i;
            EXPECT_NEAR(glm::dot(glm::dvec3(got[k].normal), glm::dvec3(cloud.normals[i])), 1.0, 1e-5) << i;
        }
    }
}

// Culling off keeps back-facing sprites but marks them hidden with the explicit zero plane (splat_record.h),
// never with NaN (GLSL leaves NaN comparisons undefined; NVIDIA folded them and drew nothing): every field
// of every record is finite, the packed colour is a normal float (no denormal a driver may flush), and the
// hidden records are exactly the back-facing sprites.
TEST(RenderCpuCull, CullingOffMarksBackFacesHiddenWithFiniteValuesOnly) {
    const SplatCloud cloud = test::fibonacci_sphere(4000);
    const std::vector<gpu::GpuSplat> splats = pack_splats(cloud);
    for (bool lit : {false, true}) {
        gpu::FrameBlock f = test_frame();
        f.params.z = 0.0f;  // culling off
        f.counts.w = lit ? 1u : 0u;
        CpuCullResult out;
        cull_splats_cpu(splats, f, {}, out);
        EXPECT_EQ(out.visible_records + out.visible_quads, splats.size());
        std::vector<std::uint32_t> quads;
        CpuCullResult::for_each_run(
            out.quads, out.quad_counts, out.block,
            [&](std::size_t, const std::uint32_t* p, std::size_t k) { quads.insert(quads.end(), p, p + k); });
        std::size_t back_sprites = 0;
        const glm::dmat4 mv(f.model_view);
        for (std::uint32_t i = 0; i < splats.size(); ++i) {
            const glm::dvec3 c = glm::dvec3(mv * glm::dvec4(glm::dvec3(cloud.positions[i]), 1.0));
            const bool back = glm::dot(glm::dvec3(cloud.normals[i]), c) > 0.0;  // view = world here
            back_sprites += back && std::find(quads.begin(), quads.end(), i) == quads.end();
        }
        ASSERT_GT(back_sprites, splats.size() / 4);
        std::size_t hidden = 0;
        CpuCullResult::for_each_run(
            out.records, out.record_counts, out.block, [&](std::size_t, const SplatRecord* p, std::size_t k) {
                for (std::size_t r = 0; r < k; ++r) {
                    const float* v = &p[r].center.x;
                    for (int j = 0; j < 20; ++j) ASSERT_TRUE(std::isfinite(v[j])) << "field " << j;
                    EXPECT_TRUE(std::isnormal(p[r].normal.w)) << "packed colour";
                    hidden += p[r].plane.x == 0.0f && p[r].plane.y == 0.0f && p[r].plane.z == 0.0f;
                }
            });
        EXPECT_EQ(hidden, back_sprites);
    }
}

// A splat seen edge-on (the eye in its plane) covers no area: its record is hidden (plane.xyz = 0) with
// every field finite, where n / (c . n) would be infinite and every pixel's ray cast NaN. One at a grazing
// angle of 0.01 rad is kept with its real plane, and one facing the camera is untouched. The compute cull
// runs the same set-up (splat_raycast_setup).
TEST(RenderCpuCull, SplatSeenEdgeOnIsHiddenWithFiniteValues) {
    SplatCloud cloud = test::fibonacci_sphere(3);  // three splats, replaced below
    const double a = 0.01;
    // The camera is at (0, 0, 3) looking down -z (test_frame): view = world up to that translation.
    cloud.positions = {{0.0f, 0.0f, 0.0f}, {0.4f, 0.0f, 0.0f}, {-0.4f, 0.0f, 0.0f}};
    cloud.axis_u = {{0.3f, 0.0f, 0.0f}, {0.3f, 0.0f, 0.0f}, {0.3f, 0.0f, 0.0f}};
    cloud.axis_v = {
        {0.0f, 0.0f, 0.3f}, glm::vec3(0.0, 0.3 * std::sin(a), 0.3 * std::cos(a)), {0.0f, 0.3f, 0.0f}};
    cloud.normals = {{0.0f, 1.0f, 0.0f}, glm::vec3(0.0, -std::cos(a), std::sin(a)), {0.0f, 0.0f, 1.0f}};
    const std::vector<gpu::GpuSplat> splats = pack_splats(cloud);
    for (bool culling : {true, false}) {
        gpu::FrameBlock f = test_frame();
        f.params.z = culling ? 1.0f : 0.0f;
        CpuCullResult out;
        cull_splats_cpu(splats, f, {}, out);
        std::vector<SplatRecord> got;
        CpuCullResult::for_each_run(
            out.records, out.record_counts, out.block,
            [&](std::size_t, const SplatRecord* p, std::size_t k) { got.insert(got.end(), p, p + k); });
        ASSERT_EQ(got.size(), 3u) << "culling " << culling;
        for (const SplatRecord& r : got) {
            const float* v = &r.center.x;
            for (int j = 0; j < 20; ++j) ASSERT_TRUE(std::isfinite(v[j])) << "field " << j;
        }
        EXPECT_EQ(glm::vec3(got[0].plane), glm::vec3(0.0f));
        EXPECT_NE(glm::vec3(got[1].plane), glm::vec3(0.0f));
        // Facing the camera at z = 0, seen from z = 3: the plane z = 0 is p . (0, 0, -1/3) = 1 in view space.
        EXPECT_NEAR(got[2].plane.z, -1.0f / 3.0f, 1e-6f);
    }
}

// The CPU mip levels of a texture (the reduced preview's per-splat lookups): each level is the 2x2 mean of
// the one above in linear light, sRGB-encoded, with GL's sizes (halved, rounded down, to 1); a lookup at a
// texel's centre gives that texel, half-way between two gives their mean, u wraps and v clamps.
TEST(RenderTexturePyramid, LevelsAreLinearMeansAndLookupsFilterLikeGl) {
    const auto srgb = [](float linear) { return gfx::encode_srgb8(linear); };
    const auto linear = [](std::uint8_t c) {
        const double x = c / 255.0;
        return float(x <= 0.04045 ? x / 12.92 : std::pow((x + 0.055) / 1.055, 2.4));
    };
    // 5x3 texels, red ramps with x, green with y; blue 255 in column 0 only.
    const int w = 5, h = 3;
    std::vector<std::uint8_t> rgba(std::size_t(w * h) * 4);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            std::uint8_t* p = &rgba[std::size_t(y * w + x) * 4];
            p[0] = std::uint8_t(40 * x), p[1] = std::uint8_t(100 * y), p[2] = x == 0 ? 255 : 0, p[3] = 255;
        }
    const TexturePyramid pyramid = build_texture_pyramid(rgba.data(), w, h);
    ASSERT_EQ(pyramid.levels.size(), 2u);  // 2x1, then 1x1
    EXPECT_EQ(pyramid.sizes[0], glm::ivec2(2, 1));
    EXPECT_EQ(pyramid.sizes[1], glm::ivec2(1, 1));
    // Level 1 texel (1, 0): the mean of level-0 texels x 2..3, y 0..1.
    const float red = 0.25f * (2.0f * linear(80) + 2.0f * linear(120)),
                green = 0.25f * (2.0f * linear(0) + 2.0f * linear(100));
    EXPECT_EQ(pyramid.levels[0][4 + 0], srgb(red));
    EXPECT_EQ(pyramid.levels[0][4 + 1], srgb(green));
    EXPECT_EQ(pyramid.levels[0][4 + 2], 0);

    const TexelView t{rgba.data(), w, h, nullptr, nullptr, &pyramid};
    const auto at = [&](float u, float v, int level) { return sample_texture(t, glm::vec2(u, v), level); };
    // The centre of texel (3, 1) at level 0.
    EXPECT_NEAR(at(3.5f / w, 1.5f / h, 0).x, linear(120), 1e-6);
    EXPECT_NEAR(at(3.5f / w, 1.5f / h, 0).y, linear(100), 1e-6);
    // Half-way between texels (1, 1) and (2, 1): the mean of their linear values.
    EXPECT_NEAR(at(2.0f / w, 1.5f / h, 0).x, 0.5f * (linear(40) + linear(80)), 1e-6);
    // u wraps: half-way between the last column and the first (blue 0 and 255).
    EXPECT_NEAR(at(0.0f, 1.5f / h, 0).z, 0.5f, 1e-6);
    EXPECT_NEAR(at(1.0f, 1.5f / h, 0).z, 0.5f, 1e-6);
    // v clamps: above the first row reads the first row.
    EXPECT_NEAR(at(3.5f / w, -0.4f, 0).y, 0.0f, 1e-6);
    // Level 1 at its texel (1, 0)'s centre; levels past the last read the last.
    EXPECT_NEAR(at(0.75f, 0.5f, 1).x, linear(srgb(red)), 1e-6);
    EXPECT_EQ(at(0.3f, 0.7f, 9), at(0.9f, 0.1f, 2));
}

// With a pyramid (reduced previews) every textured sprite is drawn flat: no sprite is left in the per-pixel
// textured list, and each flat colour is the lookup at the splat's centre uv at its mip level, lit.
TEST(RenderCpuCull, ReducedPreviewColoursEveryTexturedSpriteOnce) {
    SplatCloud cloud = test::fibonacci_sphere(3000);
    // uv from x and y, so the uv frame along the splat's axes is half their x and y.
    cloud.uvs.resize(cloud.size());
    std::vector<glm::vec4> uv_axes(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        cloud.uvs[i] = glm::vec2(0.5f + 0.5f * cloud.positions[i].x, 0.5f + 0.5f * cloud.positions[i].y);
        uv_axes[i] =
            0.5f * glm::vec4(cloud.axis_u[i].x, cloud.axis_u[i].y, cloud.axis_v[i].x, cloud.axis_v[i].y);
    }
    const std::vector<gpu::GpuSplat> splats = pack_splats(cloud);
    const int w = 1024, h = 512;
    std::vector<std::uint8_t> rgba(std::size_t(w * h) * 4);
    for (std::size_t k = 0; k < rgba.size(); ++k) rgba[k] = std::uint8_t((k * 37) % 251);
    const TexturePyramid pyramid = build_texture_pyramid(rgba.data(), w, h);
    gpu::FrameBlock f = test_frame();
    f.params.w = 1.0f;  // textured
    f.counts.w = 0u;    // unlit: the flat colour is the texture's
    CpuCullResult per_pixel, flat;
    cull_splats_cpu(splats, f, TexelView{rgba.data(), w, h, uv_axes.data()}, per_pixel);
    cull_splats_cpu(splats, f, TexelView{rgba.data(), w, h, uv_axes.data(), nullptr, &pyramid}, flat);
    ASSERT_GT(per_pixel.visible_records, 500u);
    EXPECT_EQ(per_pixel.visible_flat, 0u);
    EXPECT_EQ(flat.visible_records, 0u);
    EXPECT_EQ(flat.visible_flat, per_pixel.visible_records);
    std::vector<SplatRecord> textured, coloured;
    CpuCullResult::for_each_run(
        per_pixel.records, per_pixel.record_counts, per_pixel.block,
        [&](std::size_t, const SplatRecord* p, std::size_t k) { textured.insert(textured.end(), p, p + k); });
    CpuCullResult::for_each_run(
        flat.flat_records, flat.flat_counts, flat.block,
        [&](std::size_t, const SplatRecord* p, std::size_t k) { coloured.insert(coloured.end(), p, p + k); });
    ASSERT_EQ(textured.size(), coloured.size());
    const TexelView view{rgba.data(), w, h, nullptr, nullptr, &pyramid};
    int lowest = 99, highest = -1;
    for (std::size_t k = 0; k < textured.size(); k += 7) {
        // The per-pixel record carries the uv and the level (HQ: normal.w); the flat one its colour.
        const glm::vec2 uv(textured[k].uv.x, textured[k].uv.y);
        const int level = int(std::lround(std::max(textured[k].normal.w, 0.0f)));
        lowest = std::min(lowest, level), highest = std::max(highest, level);
        const glm::vec3 want = sample_texture(view, uv, level);
        const std::uint32_t bits = std::bit_cast<std::uint32_t>(coloured[k].normal.w) - (1u << 23);
        const glm::vec3 got(float(bits & 1023u), float((bits >> 10) & 1023u), float((bits >> 20) & 1023u));
        for (int c = 0; c < 3; ++c)  // pack_color: sqrt of the linear value in 10 bits
            EXPECT_NEAR(got[c] / 1023.0f, std::sqrt(std::clamp(want[c], 0.0f, 1.0f)), 1.0f / 1023.0f) << k;
        EXPECT_EQ(coloured[k].center, textured[k].center) << k;
    }
    EXPECT_LT(lowest, highest) << "the splats' mip levels differ (the silhouette's are coarser)";
}

// Point marks in the CPU cull (runtime/gfx/point_marks.h): gone splats are dropped exactly like a cloud
// without them, the records of the others unchanged; a preview subset reads its points' marks through its
// indices; the overlays change only the colour slot: the selected splats half way to yellow, the weight
// ramp's blue (0) and red (1).
TEST(RenderCpuCull, MarksDropGoneSplatsAndColourTheOthers) {
    const SplatCloud cloud = test::fibonacci_sphere(5000, 1.0, 0.8, 0xff806040u);
    const std::vector<gpu::GpuSplat> splats = pack_splats(cloud);
    std::vector<std::uint8_t> flags(cloud.size(), 0);
    std::vector<float> weights(cloud.size(), 0.0f);
    std::vector<gpu::GpuSplat> kept_splats;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        flags[i] = i % 3 == 0 ? kPointHidden : i % 3 == 1 ? kPointSelected : 0;
        if (i % 5 == 0) flags[i] |= kPointDeleted;
        weights[i] = i % 2 ? 1.0f : 0.0f;
        if (!(flags[i] & kPointGone)) kept_splats.push_back(splats[i]);
    }
    const MarksView marks{flags.data(), weights.data(), nullptr, 0, cloud.size()};
    const auto records = [](const CpuCullResult& r) {
        std::vector<SplatRecord> out;
        CpuCullResult::for_each_run(
            r.records, r.record_counts, r.block,
            [&](std::size_t, const SplatRecord* p, std::size_t k) { out.insert(out.end(), p, p + k); });
        return out;
    };
    for (const bool lit : {false, true}) {
        gpu::FrameBlock f = test_frame();
        f.counts.w = lit ? 1u : 0u;
        CpuCullResult plain_out, marked_out;
        cull_splats_cpu(kept_splats, f, {}, plain_out);
        f.counts.z = SFFD_MARKS_PRESENT;
        cull_splats_cpu(splats, f, {}, marked_out, marks);
        const std::vector<SplatRecord> plain = records(plain_out), marked = records(marked_out);
        ASSERT_EQ(plain.size(), marked.size());
        ASSERT_GT(plain.size(), 500u);
        EXPECT_EQ(std::memcmp(plain.data(), marked.data(), plain.size() * sizeof(SplatRecord)), 0);

        // Overlays: the same records but for the colour, which follows the marks.
        CpuCullResult tinted_out, weighted_out;
        f.counts.z = SFFD_MARKS_PRESENT | SFFD_MARKS_SELECTION;
        cull_splats_cpu(splats, f, {}, tinted_out, marks);
        f.counts.z = SFFD_MARKS_PRESENT | SFFD_MARKS_WEIGHTS;
        cull_splats_cpu(splats, f, {}, weighted_out, marks);
        const std::vector<SplatRecord> tinted = records(tinted_out), weighted = records(weighted_out);
        ASSERT_EQ(tinted.size(), plain.size());
        ASSERT_EQ(weighted.size(), plain.size());
        // Kept splats in splat order: their indices, to know which is selected and what it weighs.
        std::vector<std::size_t> kept_index;
        {
            CpuCullResult probe;
            f.counts.z = 0;
            std::vector<gpu::GpuSplat> one(1);
            for (std::size_t i = 0; i < cloud.size(); ++i) {
                if (flags[i] & kPointGone) continue;
                one[0] = splats[i];
                cull_splats_cpu(one, f, {}, probe);
                if (probe.visible_records == 1) kept_index.push_back(i);
            }
        }
        ASSERT_EQ(kept_index.size(), plain.size());
        int tinted_selected = 0, unchanged_other = 0, selected = 0;
        for (std::size_t k = 0; k < plain.size(); ++k) {
            const std::size_t i = kept_index[k];
            EXPECT_EQ(tinted[k].center, plain[k].center);
            EXPECT_EQ(glm::vec3(tinted[k].normal), glm::vec3(plain[k].normal));
            const glm::vec3 p = unpack_color(plain[k].normal.w), t = unpack_color(tinted[k].normal.w),
                            w = unpack_color(weighted[k].normal.w);
            if (flags[i] & kPointSelected) {
                ++selected;
                tinted_selected += lit || (t.x > p.x && t.z < p.z);  // lit colours may saturate or be black
            } else {
                unchanged_other += tinted[k].normal.w == plain[k].normal.w;
            }
            if (lit) {
                continue;
            } else if (weights[i] == 0.0f) {
                EXPECT_TRUE(w.x == 0.0f && w.y == 0.0f && w.z > 0.9f) << k;
            } else {
                EXPECT_TRUE(w.x > 0.9f && w.y == 0.0f && w.z == 0.0f) << k;
            }
        }
        EXPECT_GT(selected, 100);
        EXPECT_EQ(tinted_selected, selected);
        EXPECT_EQ(unchanged_other, int(plain.size()) - selected);
    }
    // A preview subset: element k is point index[k].
    std::vector<std::uint32_t> index;
    std::vector<gpu::GpuSplat> subset;
    for (std::uint32_t i = 0; i < cloud.size(); i += 2) index.push_back(i), subset.push_back(splats[i]);
    gpu::FrameBlock f = test_frame();
    CpuCullResult all, indexed;
    cull_splats_cpu(subset, f, {}, all);
    f.counts.z = SFFD_MARKS_PRESENT | SFFD_MARKS_INDEXED;
    cull_splats_cpu(subset, f, {}, indexed,
                    MarksView{flags.data(), weights.data(), index.data(), index.size(), cloud.size()});
    std::size_t gone_front = 0;
    for (std::uint32_t i : index)
        gone_front += (flags[i] & kPointGone) && cloud.normals[i].z > 0.4f;  // surely front-facing
    EXPECT_GT(gone_front, 50u);
    EXPECT_LE(indexed.visible_records + gone_front, all.visible_records);
}

// The marks' packing and colours, as the shaders compute them (point_marks.glsl).
TEST(RenderPointMarks, PackingAndOverlayColours) {
    EXPECT_EQ(gfx::pack_point_mark(0, 1.0f), gfx::kDefaultPointMark);
    EXPECT_EQ(gfx::pack_point_mark(kPointSelected | kPointHidden, 0.0f), 3u);
    EXPECT_EQ(gfx::pack_point_mark(0, 0.5f) >> 8, 128u);
    EXPECT_EQ(gfx::pack_point_mark(0, std::numeric_limits<float>::quiet_NaN()), gfx::kDefaultPointMark);
    EXPECT_EQ(gfx::pack_point_mark(0, 7.0f), gfx::kDefaultPointMark);
    EXPECT_EQ(gfx::weight_ramp(0.0f), glm::vec3(0, 0, 1));
    EXPECT_EQ(gfx::weight_ramp(0.5f), glm::vec3(0, 1, 0));
    EXPECT_EQ(gfx::weight_ramp(1.0f), glm::vec3(1, 0, 0));
    const glm::vec3 grey(0.5f);
    EXPECT_EQ(gfx::mark_overlay(grey, SFFD_MARK_SELECTED, 0), grey);
    EXPECT_EQ(gfx::mark_overlay(grey, SFFD_MARK_SELECTED, SFFD_MARKS_SELECTION),
              glm::mix(grey, gfx::kSelectionTint, 0.5f));
    EXPECT_EQ(gfx::mark_overlay(grey, 0, SFFD_MARKS_SELECTION), grey);
    EXPECT_EQ(gfx::mark_overlay(grey, gfx::kDefaultPointMark, SFFD_MARKS_WEIGHTS), glm::vec3(1, 0, 0));
}
