// 3D Gaussians in the render system: render_system's image of a Gaussian scene against the
// Gaussian GL renderer and the CPU reference, compositing with surface splats (a Gaussian behind an
// opaque splat is hidden; one in front is blended over it exactly as G + (1 - A) S), deformed Gaussians.
// Headless EGL (llvmpipe here).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <limits>
#include <optional>
#include <random>

#include <glm/gtc/quaternion.hpp>

#include "runtime/core/log.h"
#include "runtime/gfx/context.h"
#include "runtime/gfx/limits.h"
#include "runtime/gfx/residency.h"
#include "runtime/scene/camera.h"
#include "runtime/scene/components.h"
#include "systems/gaussian/gaussian_system.h"
#include "systems/splat_render/gaussian_draw.h"
#include "tests/systems/gaussian/gl_renderer_fixture.h"
#include "systems/gaussian/gpu_store.h"
#include "systems/gaussian/gpu_upload.h"
#include "systems/gaussian/reference_render.h"
#include "systems/gaussian/sh.h"
#include "systems/residency/residency_system.h"
#include "systems/splat_render/gaussian_pass.h"
#include "systems/splat_render/image_io.h"
#include "systems/splat_render/splat_render.h"
#include "tests/systems/gaussian/random_cloud.h"
#include "tests/systems/splat_render/test_scenes.h"
#include "tests/test_util/gl_required.h"

namespace {

using namespace sffd;
using namespace sffd::gaussian;
using render::kQuadCoverageBudget;
using render::kQuadCoverageBudgetHardware;
using render::quad_coverage_budget;
using test::render_gl;

class GaussianRenderSystem : public testing::Test {
protected:
    static void SetUpTestSuite() {
        auto c = gfx::create_context({.headless = true, .width = 16, .height = 16});
        if (c) context().emplace(std::move(*c));
    }
    static void TearDownTestSuite() { context().reset(); }
    static std::optional<gfx::GlContext>& context() {
        static std::optional<gfx::GlContext> c;
        return c;
    }
    void SetUp() override {
        if (!context()) SFFD_GL_UNAVAILABLE("no headless GL 4.5 context");
    }
    void TearDown() override { render::release_render_state(reg); }

    Camera camera() const {
        Camera c;
        c.eye = {0.3, 0.4, 4.0}, c.target = {0.0, 0.0, 0.0}, c.up = {0, 1, 0};
        c.fov_y_degrees = 40.0f, c.near_plane = 0.1f, c.far_plane = 20.0f;
        return c;
    }
    void add_camera() { reg.emplace<Camera>(reg.create(), camera()); }

    render::FrameImage frame(int w, int h, render::Quality q = render::Quality::hq, bool aux = true) {
        render::RenderSettings s;
        s.width = w, s.height = h, s.quality = q, s.aux_outputs = aux;
        reg.set_resource<render::RenderSettings>(s);
        residency_system(reg, FrameContext{});
        render::render_system(reg, FrameContext{});
        auto img = render::capture_frame(reg);
        EXPECT_TRUE(img.ok()) << (img.ok() ? "" : img.message());
        return img.ok() ? std::move(*img) : render::FrameImage{};
    }
    ecs::Registry reg;
};

GaussianCloud random_cloud(std::size_t n, int degree, float extent = 1.0f) {
    return test::seeded_random_cloud(29, n, degree, extent);
}

// One Gaussian of a flat colour (DC only), isotropic scale `sigma`.
GaussianCloud blob(glm::vec3 at, float sigma, float opacity, glm::vec3 rgb) {
    GaussianCloud g;
    g.positions = {at};
    g.scales = {glm::vec3(sigma)};
    g.rotations = {glm::quat(1, 0, 0, 0)};
    g.opacities = {opacity};
    g.sh = {(rgb.x - 0.5f) / 0.28209479f, (rgb.y - 0.5f) / 0.28209479f, (rgb.z - 0.5f) / 0.28209479f};
    return g;
}

// `count` large overlapping Gaussians of different colours (order matters), stretched and turned at random:
// past the quads' coverage budget of a small frame.
GaussianCloud overlapping_blobs(unsigned seed, int count) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0, 1);
    GaussianCloud g;
    for (int i = 0; i < count; ++i) {
        const GaussianCloud one = blob({2 * u(rng) - 1, 2 * u(rng) - 1, 2 * u(rng) - 1}, 0.3f + 0.3f * u(rng),
                                       0.1f + 0.3f * u(rng), {u(rng), u(rng), u(rng)});
        g.positions.push_back(one.positions[0]);
        g.scales.push_back(one.scales[0] * glm::vec3(1.0f, 0.5f + u(rng), 1.0f));
        g.rotations.push_back(glm::normalize(glm::quat(u(rng), u(rng), u(rng), u(rng))));
        g.opacities.push_back(one.opacities[0]);
        g.sh.insert(g.sh.end(), one.sh.begin(), one.sh.end());
    }
    return g;
}

glm::vec3 srgb(glm::vec3 linear) {
    return {render::linear_to_srgb(linear.x), render::linear_to_srgb(linear.y),
            render::linear_to_srgb(linear.z)};
}

// The render system's output (straight linear colour + coverage) as a ReferenceImage over a black
// background: display-referred (sRGB, the 3DGS colours' space) premultiplied colour, transmittance
// 1 - coverage.
ReferenceImage as_reference(const render::FrameImage& f) {
    ReferenceImage r;
    r.width = f.width, r.height = f.height;
    for (const glm::vec4& c : f.color) {
        r.color.push_back(srgb(glm::vec3(c)) * c.w);
        r.transmittance.push_back(1.0f - c.w);
    }
    return r;
}

std::size_t covered(const ReferenceImage& r) {
    std::size_t n = 0;
    for (float t : r.transmittance) n += t < 0.5f;
    return n;
}

TEST_F(GaussianRenderSystem, ImageEqualsGaussianRendererAndReference) {
    add_camera();
    const GaussianCloud g = random_cloud(3000, 3);
    const ecs::Entity e = reg.create();
    reg.emplace<GaussianCloud>(e, g);
    const int w = 200, h = 150;
    const ReferenceImage sys = as_reference(frame(w, h));

    auto renderer = test::create_gaussian_harness();
    ASSERT_TRUE(renderer) << renderer.message();
    ReferenceOptions o;
    o.width = w, o.height = h, o.near_plane = camera().near_plane;
    auto gl = render_gl(*renderer, g, camera(), o);
    ASSERT_TRUE(gl) << gl.message();
    const ReferenceImage ref = render_reference(g, camera(), o);
    const double p_gl = psnr(*gl, sys), p_ref = psnr(ref, sys);
    std::printf(
        "render system vs gaussian GL renderer: PSNR %.1f dB; vs CPU reference: %.1f dB; covered %zu / %zu / "
        "%zu\n",
        p_gl, p_ref, covered(sys), covered(*gl), covered(ref));
    EXPECT_GT(p_gl, 50.0);  // same shaders; the output target is RGBA16F (half-float colour)
    EXPECT_GT(p_ref, 40.0);
    EXPECT_GT(covered(ref), std::size_t(w * h / 20));
    EXPECT_NEAR(double(covered(sys)), double(covered(ref)), 0.01 * double(covered(ref)) + 5);
    const auto& stats = reg.resource<render::RenderStats>();
    EXPECT_EQ(stats.gaussians, 3000u);
    const render::GaussianPassStats pass = render::gaussian_pass_stats(reg);
    // A dense but ordinary scene: within the software rasterizer's budget (quads there), past a hardware
    // GPU's (tiles there).
    EXPECT_LT(pass.covered_pixels, kQuadCoverageBudget * w * h);
    EXPECT_GT(pass.covered_pixels, kQuadCoverageBudgetHardware * w * h);
    EXPECT_EQ(gfx::software_rasterizer() ? pass.quad_clouds : pass.tile_clouds, 1u);
    EXPECT_GT(pass.covered_pixels, std::uint64_t(w * h));
    ASSERT_TRUE(reg.try_resource<GpuGaussianStore>());
    EXPECT_EQ(reg.resource<GpuGaussianStore>().clouds.at(e).count, 3000u);
}

TEST_F(GaussianRenderSystem, TransformMovesTheCloudLikeTheCamera) {
    // A cloud under a rigid Transform seen from the camera equals the untransformed cloud seen from the
    // inversely moved camera (view-dependent colour included: the SH are evaluated in the cloud's frame).
    const GaussianCloud g = random_cloud(1500, 2, 0.8f);
    Transform t;
    t.translation = {0.4, -0.2, 0.3};
    t.rotation = glm::angleAxis(0.7, glm::normalize(glm::dvec3(1, 2, 0.5)));
    const ecs::Entity e = reg.create();
    reg.emplace<GaussianCloud>(e, g);
    reg.emplace<Transform>(e, t);
    add_camera();
    const ReferenceImage sys = as_reference(frame(160, 120));
    const glm::dmat4 inv = glm::inverse(model_matrix(&t, glm::dvec3(0.0)));
    Camera moved = camera();
    moved.eye = glm::dvec3(inv * glm::dvec4(moved.eye, 1.0));
    moved.target = glm::dvec3(inv * glm::dvec4(moved.target, 1.0));
    moved.up = glm::dmat3(inv) * moved.up;
    ReferenceOptions o;
    o.width = 160, o.height = 120, o.near_plane = moved.near_plane;
    const ReferenceImage ref = render_reference(g, moved, o);
    const double p = psnr(ref, sys);
    std::printf("transformed cloud vs reference from the moved camera: PSNR %.1f dB\n", p);
    EXPECT_GT(p, 40.0);
    EXPECT_GT(covered(ref), std::size_t(160 * 120 / 20));
}

TEST_F(GaussianRenderSystem, GaussianBehindOpaqueSplatsIsHiddenInFrontIsBlended) {
    add_camera();
    reg.emplace<DirectionalLight>(reg.create(), DirectionalLight{glm::vec3(0, 0, -1), glm::vec3(1.0f), 1.0f});
    const ecs::Entity sphere = reg.create();
    reg.emplace<SplatCloud>(sphere, render::test::fibonacci_sphere(20000, 1.0));
    const int w = 160, h = 120;
    for (render::Quality q : {render::Quality::hq, render::Quality::preview}) {
        SCOPED_TRACE(q == render::Quality::hq ? "hq" : "preview");
        const render::FrameImage surface = frame(w, h, q);
        // Behind: a bright red Gaussian at the sphere's centre (inside the opaque surface).
        const ecs::Entity inside = reg.create();
        reg.emplace<GaussianCloud>(inside, blob({0, 0, 0}, 0.3f, 0.95f, {1, 0, 0}));
        const render::FrameImage hidden = frame(w, h, q);
        std::size_t sphere_pixels = 0, differing = 0;
        for (std::size_t k = 0; k < surface.color.size(); ++k) {
            if (surface.color[k].w < 1.0f) continue;
            ++sphere_pixels;
            differing += glm::length(hidden.color[k] - surface.color[k]) > 1e-6f;
        }
        EXPECT_GT(sphere_pixels, std::size_t(w * h / 10));
        EXPECT_EQ(differing, 0u) << "a Gaussian inside the opaque sphere shows through";
        reg.destroy(inside);

        // In front: the Gaussian alone gives (G, A); over the surface S the frame must be G + (1 - A) S,
        // blended in display space (sRGB, the space of 3DGS colours).
        const ecs::Entity front = reg.create();
        reg.emplace<GaussianCloud>(front, blob({0, 0, 1.6f}, 0.15f, 0.8f, {1, 0, 0}));
        const render::FrameImage both = frame(w, h, q);
        reg.remove<SplatCloud>(sphere);
        const render::FrameImage alone = frame(w, h, q);
        reg.emplace<SplatCloud>(sphere, render::test::fibonacci_sphere(20000, 1.0));
        reg.destroy(front);
        std::size_t blended = 0;
        float worst = 0.0f;
        for (std::size_t k = 0; k < surface.color.size(); ++k) {
            const float a = alone.color[k].w;
            if (surface.color[k].w < 1.0f || a < 0.05f) continue;
            ++blended;
            const glm::vec3 expected =
                srgb(glm::vec3(alone.color[k])) * a + (1.0f - a) * srgb(glm::vec3(surface.color[k]));
            worst = std::max(worst, glm::length(srgb(glm::vec3(both.color[k])) - expected));
            EXPECT_NEAR(both.color[k].w, 1.0f, 1e-3f);
        }
        std::printf("Gaussian over the sphere: %zu blended pixels, worst colour error %.2e\n", blended,
                    double(worst));
        EXPECT_GT(blended, 50u);
        EXPECT_LT(worst, 4e-3f);  // RGBA16F targets
    }
}

TEST_F(GaussianRenderSystem, DeformedCloudIsDrawnAndFollowsTheStore) {
    add_camera();
    const GaussianCloud g = random_cloud(2000, 1);
    const ecs::Entity e = reg.create();
    reg.emplace<GaussianCloud>(e, g);
    const ReferenceImage rest = as_reference(frame(128, 96));
    // CPU deformation output uploaded into the store's `deformed` (as gaussian_deform_system's CPU path
    // does): the render system draws it.
    DeformedGaussians d;
    d.cloud = g;
    for (auto& p : d.cloud.positions) p.x += 0.5f;
    d.cloud.opacities.clear();
    d.version = 1;
    reg.emplace<Deformers>(e);
    reg.emplace<DeformedGaussians>(e, d);
    upload_cpu_deformed(reg.resource<GpuGaussianStore>().clouds.at(e), d, g);
    const ReferenceImage moved = as_reference(frame(128, 96));
    const auto& gpu = reg.resource<GpuGaussianStore>().clouds.at(e);
    EXPECT_EQ(gpu.state, gfx::Residency::deformed_cpu);
    GaussianCloud expected = d.cloud;
    expected.opacities = g.opacities;
    ReferenceOptions o;
    o.width = 128, o.height = 96, o.near_plane = camera().near_plane;
    const double p_moved = psnr(render_reference(expected, camera(), o), moved);
    const double p_rest = psnr(rest, moved);
    std::printf("deformed: PSNR %.1f dB vs the reference of the deformed cloud, %.1f dB vs rest\n", p_moved,
                p_rest);
    EXPECT_GT(p_moved, 40.0);
    EXPECT_LT(p_rest, 30.0);
    // The deformers go away: back to the authored cloud.
    reg.remove<Deformers>(e);
    const ReferenceImage back = as_reference(frame(128, 96));
    EXPECT_GT(psnr(rest, back), 60.0);
}

TEST_F(GaussianRenderSystem, DrawsWhatTheGpuDeformationWroteIntoTheStore) {
    // The GpuGaussianStore contract with a GPU deformation: when it has written `deformed` and says so
    // (state deformed_gpu), the render system draws that buffer; it never uploads a CPU result itself.
    add_camera();
    const GaussianCloud g = random_cloud(1500, 0);
    const ecs::Entity e = reg.create();
    reg.emplace<GaussianCloud>(e, g);
    reg.emplace<Deformers>(e);
    DeformedGaussians stale;  // a CPU result that must not be drawn
    stale.cloud = g;
    for (auto& p : stale.cloud.positions) p.y -= 0.7f;
    stale.version = 1;
    reg.emplace<DeformedGaussians>(e, stale);
    (void)frame(128, 96);  // residency uploads rest
    GaussianCloud moved = g;
    for (auto& p : moved.positions) p.x += 0.4f;
    GpuGaussians& gpu = reg.resource<GpuGaussianStore>().clouds.at(e);
    const std::vector<gpu::GpuGaussian> packed = pack_gaussians(moved, g.opacities);
    EXPECT_EQ(gpu.state, gfx::Residency::rest);
    gfx::fill_buffer(gpu.deformed, "test.deformed", packed.data(), packed.size() * sizeof(gpu::GpuGaussian));
    gpu.sh_source = ShSource::authored;
    gfx::set_deformed(gpu, gfx::Residency::deformed_gpu);
    reg.patch<DeformedGaussians>(e).version = 2;  // even a newer CPU result stays out
    const ReferenceImage img = as_reference(frame(128, 96));
    ReferenceOptions o;
    o.width = 128, o.height = 96, o.near_plane = camera().near_plane;
    const double p = psnr(render_reference(moved, camera(), o), img);
    std::printf("GPU-written deformed buffer drawn: PSNR %.1f dB vs the reference of that cloud\n", p);
    EXPECT_GT(p, 40.0);
    EXPECT_EQ(reg.resource<GpuGaussianStore>().clouds.at(e).state, gfx::Residency::deformed_gpu);
}

}  // namespace

// Bounded work: quads blend every covered pixel (no early termination), so a cloud covering more than
// quad_coverage_budget() images goes to the tile renderer, which stops at saturated transmittance.

// `n` Gaussians of colour `rgb`, isotropic `sigma`, centres spread over z in [z0, z0 + 1] near the axis.
GaussianCloud wall(std::size_t n, float z0, float sigma, float opacity, glm::vec3 rgb) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0, 1);
    GaussianCloud g;
    for (std::size_t i = 0; i < n; ++i) {
        const GaussianCloud one =
            blob({0.2f * u(rng) - 0.1f, 0.2f * u(rng) - 0.1f, z0 + u(rng)}, sigma, opacity, rgb);
        g.positions.push_back(one.positions[0]);
        g.scales.push_back(one.scales[0]);
        g.rotations.push_back(one.rotations[0]);
        g.opacities.push_back(opacity);
        g.sh.insert(g.sh.end(), one.sh.begin(), one.sh.end());
    }
    return g;
}

TEST_F(GaussianRenderSystem, ScreenFillingCloudIsBlendedByTilesThatStopAtSaturation) {
    add_camera();
    const std::size_t n = 20000;
    const glm::vec3 red(0.9f, 0.1f, 0.1f);
    reg.emplace<GaussianCloud>(reg.create(), wall(n, -0.5f, 10.0f, 0.5f, red));
    const int w = 640, h = 480;
    const render::FrameImage f = frame(w, h);
    const render::GaussianPassStats s = render::gaussian_pass_stats(reg);
    EXPECT_EQ(s.tile_clouds, 1u);
    EXPECT_EQ(s.quad_clouds, 0u);
    EXPECT_EQ(s.covered_pixels, std::numeric_limits<std::uint64_t>::max());  // 6.1e9: past 2^32
    // Every Gaussian covers every 16x16 tile (40 x 30): 24M entries prepared, but each tile's pixels
    // saturate within the first 256 (0.5^14 < 1e-4), so the groups stage one batch each: quads would
    // have blended 20,000 x 640 x 480 = 6.1e9 fragments.
    const std::uint64_t tiles = 40 * 30;
    EXPECT_EQ(s.tile_entries, n * tiles);
    EXPECT_LE(s.tile_entries_staged, 256 * tiles);
    EXPECT_GT(s.tile_entries_staged, 0u);
    float worst = 0.0f;
    for (const glm::vec4& c : f.color) {
        worst = std::max(worst, glm::length(srgb(glm::vec3(c)) - red));
        EXPECT_NEAR(c.w, 1.0f, 1e-3f);
    }
    std::printf("20,000 screen-filling Gaussians: %llu entries, %llu staged, worst colour error %.2e\n",
                static_cast<unsigned long long>(s.tile_entries),
                static_cast<unsigned long long>(s.tile_entries_staged), double(worst));
    EXPECT_LT(worst, 4e-3f);  // RGBA16F
}

TEST_F(GaussianRenderSystem, TileRouteMatchesTheReference) {
    // Large overlapping Gaussians of different colours (order matters), past the quads' budget.
    add_camera();
    const GaussianCloud g = overlapping_blobs(11, 1000);
    reg.emplace<GaussianCloud>(reg.create(), g);
    const int w = 160, h = 120;
    const ReferenceImage sys = as_reference(frame(w, h));
    const render::GaussianPassStats pass = render::gaussian_pass_stats(reg);
    EXPECT_EQ(pass.tile_clouds, 1u);
    EXPECT_GT(pass.covered_pixels, kQuadCoverageBudget * w * h);
    ReferenceOptions o;
    o.width = w, o.height = h, o.near_plane = camera().near_plane;
    const double p = psnr(render_reference(g, camera(), o), sys);
    std::printf("tile route vs reference: PSNR %.1f dB\n", p);
    EXPECT_GT(p, 40.0);
}

TEST_F(GaussianRenderSystem, FramesWithoutAuxOutputsBlendTheSameColours) {
    // Without aux outputs the pass blends only the colour target (no depth sum): the same colours, on both
    // routes (quads: a small ordinary cloud; tiles: large overlapping Gaussians past the quads' budget).
    add_camera();
    const GaussianCloud big = overlapping_blobs(5, 600);
    const int w = 160, h = 120;
    for (const bool tiles : {false, true}) {
        SCOPED_TRACE(tiles ? "tiles" : "quads");
        // A fresh entity per route (the first one's is destroyed): nothing of the last frame is reused.
        std::vector<ecs::Entity> old;
        reg.view<const GaussianCloud>().each([&](ecs::Entity x, const GaussianCloud&) { old.push_back(x); });
        for (ecs::Entity x : old) reg.destroy(x);
        reg.emplace<GaussianCloud>(reg.create(), tiles ? big : random_cloud(2000, 3));
        const render::FrameImage with_aux = frame(w, h, render::Quality::hq, true);
        const render::FrameImage without = frame(w, h, render::Quality::hq, false);
        const render::GaussianPassStats pass = render::gaussian_pass_stats(reg);
        EXPECT_EQ(tiles ? pass.tile_clouds : pass.quad_clouds, 1u);
        ASSERT_EQ(with_aux.color.size(), std::size_t(w * h));
        ASSERT_EQ(without.color.size(), with_aux.color.size());
        std::size_t seen = 0;
        float worst = 0.0f;
        for (std::size_t i = 0; i < with_aux.color.size(); ++i) {
            seen += with_aux.color[i].w > 0.0f;
            for (int c = 0; c < 4; ++c)
                worst = std::max(worst, std::abs(with_aux.color[i][c] - without.color[i][c]));
        }
        EXPECT_GT(seen, std::size_t(w * h / 10));
        EXPECT_EQ(worst, 0.0f);
    }
}

TEST_F(GaussianRenderSystem, TileRouteKeepsTheDepthTestAndTheAuxDepth) {
    // Screen-filling Gaussians behind an opaque sphere: hidden where it is, saturated elsewhere, and the
    // aux depth there is their mean view depth.
    add_camera();
    reg.emplace<DirectionalLight>(reg.create(), DirectionalLight{glm::vec3(0, 0, -1), glm::vec3(1.0f), 1.0f});
    const ecs::Entity sphere = reg.create();
    reg.emplace<SplatCloud>(sphere, render::test::fibonacci_sphere(20000, 1.0));
    const int w = 160, h = 120;
    const render::FrameImage surface = frame(w, h);
    const glm::vec3 blue(0.1f, 0.2f, 0.9f);
    reg.emplace<GaussianCloud>(reg.create(), wall(2000, -3.0f, 5.0f, 0.6f, blue));
    const render::FrameImage both = frame(w, h);
    EXPECT_EQ(render::gaussian_pass_stats(reg).tile_clouds, 1u);
    std::size_t sphere_pixels = 0, differing = 0, background = 0;
    for (std::size_t k = 0; k < surface.color.size(); ++k) {
        if (surface.color[k].w >= 1.0f) {
            ++sphere_pixels;
            differing += glm::length(both.color[k] - surface.color[k]) > 1e-6f;
            continue;
        }
        if (surface.color[k].w > 0.0f) continue;  // the sphere's soft rim
        ++background;
        EXPECT_LT(glm::length(srgb(glm::vec3(both.color[k])) - blue), 4e-3f);
        // The camera is 4 from the origin, the Gaussians at z in [-3, -2]: view depth 6..7.
        EXPECT_GT(both.depth[k], 5.9f);
        EXPECT_LT(both.depth[k], 7.1f);
    }
    EXPECT_GT(sphere_pixels, std::size_t(w * h / 10));
    EXPECT_GT(background, std::size_t(w * h / 4));
    EXPECT_EQ(differing, 0u) << "a Gaussian behind the opaque sphere shows through on the tile path";
}

// A limit under which not one aligned range of Gaussians fits a storage block: the cloud is refused
// every frame, the log says so once, not once a frame, and the cloud is drawn again when it fits. (A
// cloud merely larger than one block is drawn in ranges: render_system_limits_test.cpp.)
TEST_F(GaussianRenderSystem, CloudPastTheStorageLimitIsLoggedOnceAndDrawnWhenItFits) {
    add_camera();
    reg.emplace<GaussianCloud>(reg.create(), random_cloud(3000, 1));
    gfx::GlLimits small = gfx::limits();
    small.max_ssbo_block_size = 32;  // not one aligned range of Gaussians
    {
        log::ScopedLogCapture capture;
        gfx::ScopedLimits scope(small);
        for (int k = 0; k < 3; ++k) {
            frame(64, 48);
            EXPECT_EQ(reg.resource<render::RenderStats>().gaussians, 0u) << "frame " << k;
        }
        const auto entries = capture.entries();
        EXPECT_EQ(std::count_if(entries.begin(), entries.end(),
                                [](const log::ScopedLogCapture::Entry& m) {
                                    return m.level == log::Level::error &&
                                           m.message.find("GL_MAX_SHADER_STORAGE_BLOCK_SIZE") !=
                                               std::string::npos;
                                }),
                  1);
    }
    frame(64, 48);
    EXPECT_EQ(reg.resource<render::RenderStats>().gaussians, 3000u);
}
