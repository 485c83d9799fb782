// Headless EGL context (llvmpipe) shared by the GL render tests of one process, plus helpers that render
// a registry and compute analytic references (ray-sphere / ray-ellipsoid per pixel).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <optional>

#include <glm/glm.hpp>

#include "runtime/ecs/registry.h"
#include "runtime/gfx/context.h"
#include "runtime/scene/lattice.h"
#include "runtime/scene/components.h"
#include "systems/splat_render/camera_math.h"
#include "systems/splat_render/image_io.h"
#include "systems/splat_render/splat_render.h"
#include "systems/residency/residency_system.h"

namespace sffd::render::test {

class GlRenderTest : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        auto ctx = gfx::create_context({.headless = true, .width = 64, .height = 64});
        ASSERT_TRUE(ctx.ok()) << ctx.message();
        context().emplace(std::move(ctx.value()));
    }
    static void TearDownTestSuite() { context().reset(); }
    static std::optional<gfx::GlContext>& context() {
        static std::optional<gfx::GlContext> c;
        return c;
    }
    void TearDown() override { release_render_state(reg); }

    // Camera at (0, 0, distance) looking at the origin, 45 degrees vertical field of view.
    Camera& add_camera(double distance = 3.0) {
        const ecs::Entity e = reg.create();
        Camera c;
        c.eye = glm::dvec3(0.0, 0.0, distance);
        c.near_plane = 0.05f;
        c.far_plane = 20.0f;
        return reg.emplace<Camera>(e, c);
    }
    void add_light(glm::vec3 direction, float ambient = 0.1f) {
        reg.emplace<DirectionalLight>(reg.create(), DirectionalLight{direction, glm::vec3(1.0f), 1.0f});
        reg.emplace<AmbientLight>(reg.create(), AmbientLight{glm::vec3(1.0f), ambient});
    }
    ecs::Entity add_cloud(SplatCloud cloud, const SplatMaterial& material = {}) {
        const ecs::Entity e = reg.create();
        reg.emplace<SplatCloud>(e, std::move(cloud));
        reg.emplace<SplatMaterial>(e, material);
        return e;
    }
    // A Bernstein lattice of `divisions`³ around the unit sphere (box [-1.1, 1.1]³) deforming `cloud`.
    ecs::Entity add_lattice(ecs::Entity cloud, int divisions = 4) {
        const ecs::Entity le = reg.create();
        reg.emplace<Lattice>(
            le, make_lattice({-1.1, -1.1, -1.1},
                             {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)},
                             {divisions, divisions, divisions}));
        reg.emplace<Deformers>(cloud, Deformers{{le}});
        return le;
    }

    // path: automatic is the CPU cull on llvmpipe; CullPath::compute runs the compute pass.
    FrameImage render(Quality quality, int w, int h, bool culling = true, CullPath path = CullPath::automatic,
                      RasterPath raster = RasterPath::automatic) {
        RenderSettings s;
        s.quality = quality, s.width = w, s.height = h, s.culling = culling, s.time_passes = true;
        s.cull_path = path, s.raster_path = raster;
        s.aux_outputs = true;
        s.preview_divider = preview_divider;
        s.reduced_preview_flat_texture = reduced_preview_flat_texture;
        s.sprite_path = sprite_path;
        reg.set_resource<RenderSettings>(s);
        residency_system(reg, FrameContext{});
        render_system(reg, FrameContext{});
        auto img = capture_frame(reg);
        EXPECT_TRUE(img.ok()) << (img.ok() ? "" : img.message());
        if (const char* dir = std::getenv("SFFD_RENDER_TEST_OUT");
            dir && img.ok()) {  // for looking at the images
            const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
            const std::string name = std::string(info->test_suite_name()) + "." + info->name() + "." +
                                     (quality == Quality::hq ? "hq" : "preview") +
                                     (path == CullPath::compute ? ".compute" : "") + ".png";
            (void)write_png(std::filesystem::path(dir) / name, to_rgba8(img.value()));
        }
        return img.ok() ? std::move(img.value()) : FrameImage{};
    }

    ecs::Registry reg;
    int preview_divider = 1;                   // RenderSettings::preview_divider of the frames render() draws
    bool reduced_preview_flat_texture = true;  // and RenderSettings::reduced_preview_flat_texture
    SpritePath sprite_path = SpritePath::automatic;  // and RenderSettings::sprite_path
};

// World-space ray through the centre of pixel (x, y) (row 0 at the top), scaled so that its component
// along the view axis is 1: the hit parameter t of eye + t * dir is the view-axis depth.
inline glm::dvec3 pixel_ray(const Camera& cam, int x, int y, int w, int h) {
    const glm::dmat4 p = projection_matrix(cam, double(w) / double(h));
    const double nx = (x + 0.5) / w * 2.0 - 1.0, ny = 1.0 - (y + 0.5) / h * 2.0;
    const glm::dvec3 view_dir(nx / p[0][0], ny / p[1][1], -1.0);
    return glm::dmat3(glm::inverse(view_matrix(cam))) * view_dir;
}

// View-axis depth of the first hit of the ray with the ellipsoid |(p - c) / scale| = 1, or nullopt.
inline std::optional<double> hit_ellipsoid(const glm::dvec3& eye, const glm::dvec3& dir,
                                           const glm::dvec3& scale,
                                           const glm::dvec3& center = glm::dvec3(0.0)) {
    const glm::dvec3 o = (eye - center) / scale, d = dir / scale;
    const double a = glm::dot(d, d), b = 2.0 * glm::dot(o, d), c = glm::dot(o, o) - 1.0;
    const double disc = b * b - 4.0 * a * c;
    if (disc < 0.0) return std::nullopt;
    const double t = (-b - std::sqrt(disc)) / (2.0 * a);
    if (t <= 0.0) return std::nullopt;
    return t;
}

// Pixels inside the image of the ellipsoid |p / scale| = 1 (shrunk 3%), those left uncovered (holes), and
// those whose depth is not the near surface's (the far side showing through a gap).
struct Coverage {
    int inside = 0, holes = 0, far_side = 0;
};

inline Coverage ellipsoid_coverage(const FrameImage& img, const Camera& cam, glm::dvec3 scale) {
    Coverage c;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            const glm::dvec3 d = pixel_ray(cam, x, y, img.width, img.height);
            if (!hit_ellipsoid(cam.eye, d, scale * 0.97)) continue;
            ++c.inside;
            if (!img.covered(x, y)) {
                ++c.holes;
                continue;
            }
            if (std::abs(double(img.depth[img.index(x, y)]) - *hit_ellipsoid(cam.eye, d, scale)) > 0.05)
                ++c.far_side;
        }
    return c;
}

// Two frames compared over the pixels covered in both (after counting coverage and its mismatches).
struct ImageDiff {
    int covered_a = 0, covered_b = 0, coverage_mismatch = 0;
    int over_2_percent = 0;   // pixels whose largest channel difference is over 0.02
    double psnr = 0.0;        // dB, linear rgb (200 when equal)
    double max_color = 0.0;   // largest rgb channel difference
    double mean_color = 0.0;  // mean of the per-pixel largest channel difference
    double max_depth = 0.0;   // largest depth difference (view-axis units)
};

inline ImageDiff image_diff(const FrameImage& a, const FrameImage& b) {
    ImageDiff d;
    double se = 0.0;
    int both = 0;
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x) {
            const bool ca = a.covered(x, y), cb = b.covered(x, y);
            d.covered_a += ca, d.covered_b += cb, d.coverage_mismatch += ca != cb;
            if (!ca || !cb) continue;
            const std::size_t i = a.index(x, y);
            const glm::vec3 e = glm::abs(glm::vec3(a.color[i]) - glm::vec3(b.color[i]));
            const double m = double(std::max({e.x, e.y, e.z}));
            se += double(glm::dot(e, e));
            d.max_color = std::max(d.max_color, m);
            d.over_2_percent += m > 0.02;
            d.mean_color += m;
            d.max_depth = std::max(d.max_depth, double(std::abs(a.depth[i] - b.depth[i])));
            ++both;
        }
    if (both > 0) d.mean_color /= both;
    const double mse = both > 0 ? se / (3.0 * both) : 0.0;
    d.psnr = mse > 0.0 ? 10.0 * std::log10(1.0 / mse) : 200.0;
    return d;
}

inline double luminance(const glm::vec4& c) {
    return 0.2126 * double(c.x) + 0.7152 * double(c.y) + 0.0722 * double(c.z);
}

}  // namespace sffd::render::test
