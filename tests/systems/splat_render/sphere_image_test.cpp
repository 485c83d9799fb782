// Image tests on the unit sphere of 59,650 splats (the paper's): coverage inside the silhouette, depth
// continuity (no far side through gaps), EXR depth against the analytic sphere, lighting and smoothness.
#include <algorithm>
#include <filesystem>
#include <vector>

#include "tests/systems/splat_render/gl_fixture.h"
#include "tests/systems/splat_render/test_scenes.h"

using namespace sffd;
using namespace sffd::render;
using namespace sffd::render::test;

namespace {

constexpr std::size_t paper_splats = 59650;

struct CoverageReport {
    int inside = 0;    // pixels whose ray hits the shrunken analytic surface
    int holes = 0;     // of those, not covered
    int far_side = 0;  // of those, depth off the analytic surface by more than the tolerance
    double max_depth_error = 0.0;
};

// Every pixel whose ray hits the analytic ellipsoid shrunk by `shrink` must be covered, and its depth must
// match the unshrunk ellipsoid's within `tolerance` (a far-side splat seen through a gap is ~1 unit deeper).
CoverageReport check_coverage(const FrameImage& img, const Camera& cam, glm::dvec3 scale,
                              double shrink = 0.97, double tolerance = 0.03) {
    CoverageReport r;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            const glm::dvec3 d = pixel_ray(cam, x, y, img.width, img.height);
            if (!hit_ellipsoid(cam.eye, d, scale * shrink)) continue;
            ++r.inside;
            if (!img.covered(x, y)) {
                ++r.holes;
                continue;
            }
            const double expected = *hit_ellipsoid(cam.eye, d, scale);
            const double err = std::abs(double(img.depth[img.index(x, y)]) - expected);
            r.max_depth_error = std::max(r.max_depth_error, err);
            if (err > tolerance) ++r.far_side;
        }
    return r;
}

}  // namespace

class SphereImage : public GlRenderTest {};

TEST_F(SphereImage, HqCoversTheSilhouetteWithContinuousDepth) {
    const Camera cam = add_camera(3.0);
    add_light({-1.0f, -0.3f, -0.5f});
    add_cloud(fibonacci_sphere(paper_splats));
    const FrameImage img = render(Quality::hq, 512, 512);
    const CoverageReport r = check_coverage(img, cam, glm::dvec3(1.0));
    EXPECT_GT(r.inside, 100000);
    EXPECT_EQ(r.holes, 0);
    EXPECT_EQ(r.far_side, 0) << "max depth error " << r.max_depth_error;
    // Nothing drawn well outside the silhouette.
    int outside = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
            if (!hit_ellipsoid(cam.eye, pixel_ray(cam, x, y, 512, 512), glm::dvec3(1.03)) &&
                img.covered(x, y))
                ++outside;
    EXPECT_EQ(outside, 0);
}

TEST_F(SphereImage, PreviewCoversTheSilhouetteWithContinuousDepth) {
    const Camera cam = add_camera(3.0);
    add_light({-1.0f, -0.3f, -0.5f});
    add_cloud(fibonacci_sphere(paper_splats));
    const FrameImage img = render(Quality::preview, 512, 512);
    const CoverageReport r = check_coverage(img, cam, glm::dvec3(1.0));
    EXPECT_EQ(r.holes, 0);
    EXPECT_EQ(r.far_side, 0) << "max depth error " << r.max_depth_error;
}

TEST_F(SphereImage, ExrDepthAtTheCentrePixelMatchesTheAnalyticSphere) {
    const Camera cam = add_camera(3.0);
    add_light({-1.0f, -0.3f, -0.5f});
    add_cloud(fibonacci_sphere(paper_splats));
    for (Quality q : {Quality::hq, Quality::preview}) {
        const FrameImage img = render(q, 640, 360);
        const std::filesystem::path path =
            std::filesystem::temp_directory_path() / ("sffd_centre_" + std::to_string(::getpid()) + ".exr");
        ASSERT_TRUE(write_exr(path, img).ok());
        auto back = read_exr(path);
        ASSERT_TRUE(back.ok()) << back.message();
        const int x = 320, y = 180;
        const double expected = *hit_ellipsoid(cam.eye, pixel_ray(cam, x, y, 640, 360), glm::dvec3(1.0));
        EXPECT_NEAR(expected, 2.0, 1e-3);
        // Within 1% of the radius (1.0).
        EXPECT_NEAR(double(back->depth[back->index(x, y)]), expected, 0.01)
            << (q == Quality::hq ? "hq" : "preview");
        // The normal there faces the camera.
        EXPECT_GT(double(back->normal[back->index(x, y)].z), 0.99);
        std::filesystem::remove(path);
    }
}

TEST_F(SphereImage, LitSideIsBrighterThanTheUnlitSide) {
    add_camera(3.0);
    add_light({-1.0f, 0.0f, 0.0f}, 0.1f);  // light travels towards -x: the +x half is lit
    add_cloud(fibonacci_sphere(paper_splats, 1.0, 0.8, 0xffb4b4b4u));
    for (Quality q : {Quality::hq, Quality::preview}) {
        const FrameImage img = render(q, 256, 256);
        double left = 0, right = 0;
        int nl = 0, nr = 0;
        for (int y = 0; y < 256; ++y)
            for (int x = 0; x < 256; ++x) {
                if (!img.covered(x, y)) continue;
                (x < 128 ? left : right) += luminance(img.color[img.index(x, y)]);
                ++(x < 128 ? nl : nr);
            }
        ASSERT_GT(nl, 1000);
        ASSERT_GT(nr, 1000);
        EXPECT_GT(right / nr, 3.0 * (left / nl));
    }
}

// Deferred shading of blended normals against Blinn-Phong of the analytic sphere's normals: close per
// pixel, and neighbouring pixels differ no more than the analytic image's do (no disc edges).
TEST_F(SphereImage, HqShadingIsSmoothAndMatchesTheAnalyticSphere) {
    const Camera cam = add_camera(3.0);
    const glm::dvec3 light_travel = glm::normalize(glm::dvec3(-0.5, -0.4, -0.6));
    add_light(glm::vec3(light_travel), 0.1f);
    const ecs::Entity e = add_cloud(fibonacci_sphere(paper_splats, 1.0, 0.8, 0xffb4b4b4u));
    const SplatMaterial material = reg.get<SplatMaterial>(e);
    const int w = 384, h = 384;
    const FrameImage hq = render(Quality::hq, w, h);
    const FrameImage preview = render(Quality::preview, w, h);

    const double albedo = double(srgb_to_linear(float(0xb4) / 255.0f));
    const glm::dvec3 l = -light_travel;
    std::vector<double> analytic(std::size_t(w) * h, -1.0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const glm::dvec3 d = pixel_ray(cam, x, y, w, h);
            if (!hit_ellipsoid(cam.eye, d, glm::dvec3(0.95))) continue;
            const double t = *hit_ellipsoid(cam.eye, d, glm::dvec3(1.0));
            const glm::dvec3 n = glm::normalize(cam.eye + t * d);
            const glm::dvec3 hv = glm::normalize(l + -glm::normalize(d));
            const double ndl = std::max(glm::dot(n, l), 0.0);
            const double spec = ndl > 0
                                    ? std::pow(std::max(glm::dot(n, hv), 0.0), double(material.shininess)) *
                                          double(material.specular)
                                    : 0.0;
            analytic[std::size_t(y) * w + x] = albedo * 0.1 + albedo * ndl + spec;
        }
    auto srgb8 = [](double v) { return double(encode_srgb8(float(v))); };
    double max_err = 0, sum_err = 0;
    int n = 0;
    double max_step_analytic = 0, max_step_hq = 0, max_step_preview = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x + 1 < w; ++x) {
            const std::size_t i = std::size_t(y) * w + x;
            if (analytic[i] < 0 || analytic[i + 1] < 0) continue;
            const double got = double(hq.color[i].y);  // grey: any channel
            max_err = std::max(max_err, std::abs(got - analytic[i]));
            sum_err += std::abs(got - analytic[i]);
            ++n;
            max_step_analytic =
                std::max(max_step_analytic, std::abs(srgb8(analytic[i + 1]) - srgb8(analytic[i])));
            max_step_hq = std::max(max_step_hq,
                                   std::abs(srgb8(double(hq.color[i + 1].y)) - srgb8(double(hq.color[i].y))));
            max_step_preview = std::max(max_step_preview, std::abs(srgb8(double(preview.color[i + 1].y)) -
                                                                   srgb8(double(preview.color[i].y))));
        }
    ASSERT_GT(n, 50000);
    EXPECT_LT(sum_err / n, 0.01);
    EXPECT_LT(max_err, 0.06);
    EXPECT_LE(max_step_hq, max_step_analytic + 3.0) << "analytic " << max_step_analytic;
    RecordProperty("max_step_hq", std::to_string(max_step_hq));
    RecordProperty("max_step_preview", std::to_string(max_step_preview));
    std::printf("max neighbouring step (8-bit sRGB): analytic %.0f, hq %.0f, preview %.0f; mean |err| %.4f\n",
                max_step_analytic, max_step_hq, max_step_preview, sum_err / n);
}

// Two spheres side by side, one matte (specular 0) and one glossy (specular 0.8, shininess 48): the deferred
// shading gives each its own material (blended per pixel by the attribute pass), checked against analytic
// Blinn-Phong of each sphere with its own material; the matte one must show no highlight.
TEST_F(SphereImage, DeferredShadingKeepsEachCloudsMaterial) {
    const Camera cam = add_camera(5.0);
    const glm::dvec3 light_travel = glm::normalize(glm::dvec3(-0.3, -0.3, -1.0));
    add_light(glm::vec3(light_travel), 0.1f);
    const glm::dvec3 centres[2] = {glm::dvec3(-1.1, 0.0, 0.0), glm::dvec3(1.1, 0.0, 0.0)};
    const float specular[2] = {0.0f, 0.8f}, shininess[2] = {8.0f, 48.0f};
    for (int k = 0; k < 2; ++k) {
        SplatCloud c = fibonacci_sphere(20000, 1.0, 0.8, 0xffb4b4b4u);
        c.origin = centres[k];
        add_cloud(std::move(c), SplatMaterial{.specular = specular[k], .shininess = shininess[k]});
    }
    const int w = 400, h = 240;
    const FrameImage hq = render(Quality::hq, w, h);
    const double albedo = double(srgb_to_linear(float(0xb4) / 255.0f));
    const glm::dvec3 l = -light_travel;
    double sum_err[2] = {0, 0}, brightest[2] = {0, 0}, brightest_analytic[2] = {0, 0};
    int n[2] = {0, 0};
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const glm::dvec3 d = pixel_ray(cam, x, y, w, h);
            for (int k = 0; k < 2; ++k) {
                if (!hit_ellipsoid(cam.eye, d, glm::dvec3(0.95), centres[k])) continue;
                const double t = *hit_ellipsoid(cam.eye, d, glm::dvec3(1.0), centres[k]);
                const glm::dvec3 nrm = glm::normalize(cam.eye + t * d - centres[k]);
                const glm::dvec3 hv = glm::normalize(l - glm::normalize(d));
                const double ndl = std::max(glm::dot(nrm, l), 0.0);
                const double spec = ndl > 0
                                        ? std::pow(std::max(glm::dot(nrm, hv), 0.0), double(shininess[k])) *
                                              double(specular[k])
                                        : 0.0;
                const double analytic = albedo * 0.1 + albedo * ndl + spec;
                const double got = double(hq.color[hq.index(x, y)].y);
                sum_err[k] += std::abs(got - analytic);
                ++n[k];
                brightest[k] = std::max(brightest[k], got);
                brightest_analytic[k] = std::max(brightest_analytic[k], analytic);
            }
        }
    for (int k = 0; k < 2; ++k) {
        ASSERT_GT(n[k], 5000) << k;
        EXPECT_LT(sum_err[k] / n[k], 0.01) << "sphere " << k;
        EXPECT_NEAR(brightest[k], brightest_analytic[k], 0.06) << "sphere " << k;
    }
    EXPECT_GT(brightest[1], brightest[0] + 0.5);  // the glossy highlight; the matte sphere has none
}

TEST_F(SphereImage, CullingDropsTheBackHalfAndKeepsTheImage) {
    add_camera(3.0);
    add_light({-1.0f, -0.3f, -0.5f});
    add_cloud(fibonacci_sphere(paper_splats));
    const FrameImage culled = render(Quality::hq, 256, 256, true);
    const RenderStats with = reg.resource<RenderStats>();
    const FrameImage all = render(Quality::hq, 256, 256, false);
    const RenderStats without = reg.resource<RenderStats>();
    EXPECT_EQ(without.visible_points + without.visible_quads, paper_splats);
    const double kept = double(with.visible_points + with.visible_quads) / double(paper_splats);
    // From distance 3 a unit sphere shows the cap with cos(angle) > 1/3 of the normal towards the eye:
    // (1 - 1/3) / 2 = 1/3 of its area.
    EXPECT_NEAR(kept, 1.0 / 3.0, 0.02);
    int coverage_diff = 0;
    double color_diff = 0;
    for (std::size_t i = 0; i < culled.color.size(); ++i) {
        coverage_diff += (culled.color[i].w > 0) != (all.color[i].w > 0);
        color_diff += std::abs(double(culled.color[i].y - all.color[i].y));
    }
    EXPECT_LE(coverage_diff, 10);
    EXPECT_LT(color_diff / double(culled.color.size()), 0.002);
}

// A scene with only a point cloud: the renderer frames it (whole sphere in view, centred) and lights it
// with the default key light (lit and unlit parts differ) plus ambient.
TEST_F(SphereImage, SceneWithoutCameraOrLightsIsFramedAndLit) {
    SplatCloud sphere = fibonacci_sphere(paper_splats, 2.0);
    for (glm::vec3& p : sphere.positions) p += glm::vec3(10.0f, -3.0f, 4.0f);
    add_cloud(std::move(sphere));
    const FrameImage img = render(Quality::hq, 320, 180);
    int covered = 0, min_x = 320, max_x = -1, min_y = 180, max_y = -1;
    double lo = 1e9, hi = -1e9;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            if (!img.covered(x, y)) continue;
            ++covered;
            min_x = std::min(min_x, x), max_x = std::max(max_x, x), min_y = std::min(min_y, y),
            max_y = std::max(max_y, y);
            lo = std::min(lo, luminance(img.color[img.index(x, y)]));
            hi = std::max(hi, luminance(img.color[img.index(x, y)]));
        }
    EXPECT_GT(covered, 5000);
    // Entirely inside the frame (not touching the border) and roughly centred.
    EXPECT_GT(min_x, 0);
    EXPECT_LT(max_x, 319);
    EXPECT_GT(min_y, 0);
    EXPECT_LT(max_y, 179);
    EXPECT_NEAR(0.5 * (min_x + max_x), 160.0, 4.0);
    EXPECT_NEAR(0.5 * (min_y + max_y), 90.0, 4.0);
    EXPECT_GT(lo, 0.0);       // ambient reaches the unlit side
    EXPECT_GT(hi, 4.0 * lo);  // the key light makes a lit side
}
