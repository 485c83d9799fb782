// GL renderer of Gaussians against the CPU reference renderer (headless EGL; llvmpipe here). The two
// share conventions and pixel boxes; they differ by float vs double arithmetic and the reference's early
// stop at T < 1e-4, which the blending hardware cannot do. Stated bound: PSNR > 40 dB on every scene.
#include <gtest/gtest.h>

#include <optional>
#include <random>

#include <glm/gtc/quaternion.hpp>

#include "runtime/assets/builtin_scenes.h"
#include "runtime/gfx/context.h"
#include "systems/ffd/lattice.h"
#include "systems/ffd/operations.h"
#include "systems/gaussian/from_splats.h"
#include "systems/gaussian/gaussian_deform.h"
#include "systems/gaussian/gl_render.h"
#include "systems/gaussian/reference_render.h"
#include "systems/gaussian/sh.h"

namespace {

using namespace sffd;
using namespace sffd::gaussian;

class GaussianGl : public testing::Test {
protected:
    void SetUp() override {
        auto c = gfx::create_context({.headless = true, .width = 16, .height = 16});
        if (!c) GTEST_SKIP() << c.message();
        ctx.emplace(std::move(*c));
        auto r = create_gl_renderer();
        ASSERT_TRUE(r) << r.message();
        renderer.emplace(std::move(*r));
    }
    void TearDown() override { renderer.reset(); }
    std::optional<gfx::GlContext> ctx;
    std::optional<GlRenderer> renderer;
};

Camera camera_at(glm::dvec3 eye, glm::dvec3 target = glm::dvec3(0.0), float fov = 40.0f) {
    Camera c;
    c.eye = eye, c.target = target, c.up = {0, 1, 0}, c.fov_y_degrees = fov;
    return c;
}

GaussianCloud random_cloud(std::size_t n, int degree) {
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> u(-1, 1);
    GaussianCloud g;
    g.sh_degree = degree;
    for (std::size_t i = 0; i < n; ++i) {
        g.positions.emplace_back(u(rng), u(rng), u(rng));
        g.scales.emplace_back(0.08f + 0.06f * u(rng), 0.03f + 0.02f * u(rng), 0.05f);
        g.rotations.push_back(glm::normalize(glm::quat(u(rng), u(rng), u(rng), u(rng))));
        g.opacities.push_back(0.6f + 0.35f * u(rng));
        for (int k = 0; k < sh_coeffs(degree) * 3; ++k) g.sh.push_back(0.6f * u(rng));
    }
    return g;
}

void compare(GlRenderer& r, const GaussianCloud& g, const Camera& cam, ReferenceOptions o, const char* what) {
    auto gl = render_gl(r, g, cam, o);
    ASSERT_TRUE(gl) << gl.message();
    const ReferenceImage ref = render_reference(g, cam, o);
    const double p = psnr(ref, *gl);
    // Coverage must agree too (a blank GL image of a mostly empty scene would still score well).
    std::size_t covered_ref = 0, covered_gl = 0;
    for (std::size_t k = 0; k < ref.transmittance.size(); ++k) {
        covered_ref += ref.transmittance[k] < 0.5f;
        covered_gl += gl->transmittance[k] < 0.5f;
    }
    std::printf("%s: PSNR %.1f dB, covered pixels %zu (reference %zu), sort %.2f ms\n", what, p, covered_gl, covered_ref, r.sort_ms);
    EXPECT_GT(p, 40.0) << what;
    EXPECT_GT(covered_ref, ref.transmittance.size() / 20) << what;
    EXPECT_NEAR(double(covered_gl), double(covered_ref), 0.01 * double(covered_ref) + 5) << what;
}

TEST_F(GaussianGl, MatchesCpuReference) {
    ReferenceOptions o;
    o.width = 160, o.height = 120;
    o.background = {0.1f, 0.2f, 0.3f};
    compare(*renderer, random_cloud(3000, 3), camera_at({0.5, 0.7, 3.5}), o, "random degree 3");
    // The converted sphere, stretched and twisted by a lattice (deformed covariances and SH).
    GaussianCloud sphere = gaussians_from_splats(assets::make_sphere_cloud(20000));
    Lattice l = ffd::make_lattice({-1.1, -1.1, -1.1}, {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)}, {4, 4, 4});
    ffd::twist_graded(l, ffd::all_control_points(l), {0, 1, 0}, 0.8, glm::dvec3(0.0));
    for (glm::dvec3& p : l.current) p.x *= 1.6;
    GaussianCloud deformed;
    ASSERT_TRUE(deform(l, sphere, deformed));
    o.width = 200, o.height = 150;
    compare(*renderer, deformed, camera_at({0.0, 1.0, 5.0}), o, "deformed sphere");
    // View-direction mode: SH evaluated at frameᵀ d on the GPU as in the reference.
    GaussianCloud view;
    DeformOptions vo;
    vo.sh = ShMode::rotate_view;
    GaussianCloud colourful = random_cloud(2000, 2);
    ASSERT_TRUE(deform(l, colourful, view, vo));
    ASSERT_FALSE(view.sh_frames.empty());
    compare(*renderer, view, camera_at({0.0, 1.0, 4.0}), o, "view-direction SH frames");
    // Far from the origin (the view matrix carries the cloud origin in double).
    GaussianCloud far = random_cloud(500, 1);
    far.origin = glm::dvec3(1e5, -2e4, 3e4);
    compare(*renderer, far, camera_at(far.origin + glm::dvec3(0, 0, 3.0), far.origin), o, "far from the origin");
}

TEST_F(GaussianGl, LargeCloudsAreDispatchedAsAGrid) {
    // Clouds beyond 64 x 65,535 Gaussians need a 2D dispatch; with 3 groups per row, 3,000 Gaussians
    // take a 3 x 16 grid (the last row partly empty) and must render exactly as in one row.
    ReferenceOptions o;
    o.width = 96, o.height = 72;
    const GaussianCloud g = random_cloud(3000, 1);
    const Camera cam = camera_at({0.2, 0.3, 3.5});
    auto one_row = render_gl(*renderer, g, cam, o);
    ASSERT_TRUE(one_row) << one_row.message();
    renderer->max_groups_x = 3;
    auto grid = render_gl(*renderer, g, cam, o);
    ASSERT_TRUE(grid) << grid.message();
    EXPECT_EQ(grid->color, one_row->color);
    EXPECT_GT(psnr(*grid, render_reference(g, cam, o)), 40.0);
}

TEST_F(GaussianGl, EmptyCloudGivesTheBackground) {
    ReferenceOptions o;
    o.width = o.height = 8;
    o.background = {0.25f, 0.5f, 1.0f};
    GaussianCloud empty;
    auto img = render_gl(*renderer, empty, camera_at({0, 0, 3}), o);
    ASSERT_TRUE(img) << img.message();
    for (const glm::vec3& c : img->color) EXPECT_EQ(c, o.background);
}

}  // namespace
