// CPU reference renderer: analytic EWA footprints, blending order, view-dependent colour, and images of
// deformed Gaussian scenes (rigid motion renders the same picture; a stretched sphere stays closed).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <glm/gtc/quaternion.hpp>

#include "runtime/assets/builtin_scenes.h"
#include "systems/ffd/lattice.h"
#include "systems/gaussian/from_splats.h"
#include "systems/gaussian/gaussian_deform.h"
#include "systems/gaussian/gaussian_math.h"
#include "systems/gaussian/reference_render.h"
#include "systems/gaussian/sh.h"

namespace {

using namespace sffd;
using namespace sffd::gaussian;

GaussianCloud one(glm::vec3 p, glm::vec3 scale, glm::quat q, glm::vec3 color, float opacity) {
    GaussianCloud g;
    g.positions = {p}, g.scales = {scale}, g.rotations = {q}, g.opacities = {opacity};
    for (int c = 0; c < 3; ++c) g.sh.push_back(float((double(color[c]) - 0.5) / kShC0));
    return g;
}

void append(GaussianCloud& a, const GaussianCloud& b) {
    a.positions.insert(a.positions.end(), b.positions.begin(), b.positions.end());
    a.scales.insert(a.scales.end(), b.scales.begin(), b.scales.end());
    a.rotations.insert(a.rotations.end(), b.rotations.begin(), b.rotations.end());
    a.opacities.insert(a.opacities.end(), b.opacities.begin(), b.opacities.end());
    a.sh.insert(a.sh.end(), b.sh.begin(), b.sh.end());
}

Camera camera_at(glm::dvec3 eye, glm::dvec3 target = glm::dvec3(0.0), glm::dvec3 up = {0, 1, 0},
                 float fov = 45.0f) {
    Camera c;
    c.eye = eye, c.target = target, c.up = up, c.fov_y_degrees = fov;
    return c;
}

TEST(GaussianReferenceRender, AnisotropicFootprintMatchesAnalyticEwa) {
    // A rotated anisotropic Gaussian at the image centre, camera on +z: the projection Jacobian there is
    // diag(f/d, −f/d), so Σ₂ = (f/d)² [[Σxx, −Σxy], [−Σxy, Σyy]] + 0.3 I (computed here from the
    // covariance, not by the renderer's code path).
    const glm::quat q = glm::quat(glm::angleAxis(0.6, glm::normalize(glm::dvec3(0.3, 0.2, 1.0))));
    const GaussianCloud g = one({0, 0, 0}, {0.08f, 0.03f, 0.05f}, q, {1, 1, 1}, 0.7f);
    ReferenceOptions o;
    o.width = o.height = 96;
    const double d = 3.0, f = 96 / (2.0 * std::tan(glm::radians(45.0) / 2));
    const ReferenceImage img = render_reference(g, camera_at({0, 0, d}), o);
    const glm::dmat3 s = covariance(glm::dvec3(g.scales[0]), glm::dquat(q));
    const double k = (f / d) * (f / d);
    const double a = k * s[0][0] + 0.3, b = -k * s[1][0], c = k * s[1][1] + 0.3, det = a * c - b * b;
    int checked = 0;
    for (int y = 0; y < o.height; ++y)
        for (int x = 0; x < o.width; ++x) {
            const double dx = x + 0.5 - 48, dy = y + 0.5 - 48;
            const double alpha = 0.7 * std::exp(-0.5 * (c * dx * dx - 2 * b * dx * dy + a * dy * dy) / det);
            const double got = 1.0 - double(img.transmittance[img.index(x, y)]);
            if (alpha >= 1.5 / 255.0 && alpha < 0.99) {
                EXPECT_NEAR(got, alpha, 2e-5) << x << "," << y;
                ++checked;
            } else if (alpha < 0.5 / 255.0) {
                EXPECT_EQ(got, 0.0) << x << "," << y;
            }
        }
    EXPECT_GT(checked, 100);
}

TEST(GaussianReferenceRender, FrontToBackBlendingFollowsDepthNotArrayOrder) {
    GaussianCloud g =
        one({0, 0, 0}, glm::vec3(0.3f), glm::quat(1, 0, 0, 0), {0, 1, 0}, 0.6f);            // green, behind
    append(g, one({0, 0, 0.5f}, glm::vec3(0.3f), glm::quat(1, 0, 0, 0), {1, 0, 0}, 0.5f));  // red, in front
    ReferenceOptions o;
    o.width = o.height = 32;
    o.background = {0, 0, 1};
    const ReferenceImage img = render_reference(g, camera_at({0, 0, 3}), o);
    // Centre pixel: each Gaussian's alpha is its opacity times exp(−½ r²/σ²), r = half a pixel.
    const glm::vec3 col = img.color[img.index(16, 16)];
    const double f = 32 / (2.0 * std::tan(glm::radians(45.0) / 2));
    auto alpha = [&](double opacity, double depth) {
        const double s2 = (f * 0.3 / depth) * (f * 0.3 / depth) + 0.3;
        return opacity * std::exp(-0.5 * 0.5 / s2);  // dx = dy = 0.5
    };
    const double ar = alpha(0.5, 2.5), ag = alpha(0.6, 3.0);
    EXPECT_NEAR(col.x, ar, 1e-5);
    EXPECT_NEAR(col.y, ag * (1 - ar), 1e-5);
    EXPECT_NEAR(col.z, (1 - ar) * (1 - ag), 1e-5);
}

TEST(GaussianReferenceRender, ColourDependsOnTheViewDirectionThroughSh) {
    GaussianCloud g = one({0, 0, 0}, glm::vec3(0.2f), glm::quat(1, 0, 0, 0), {0.5f, 0.5f, 0.5f}, 0.9f);
    g.sh_degree = 1;
    g.sh.resize(12, 0.0f);
    g.sh[3 * 3 + 0] = 0.4f;  // red varies with −x: brighter when looking towards −x (camera on +x)
    ReferenceOptions o;
    o.width = o.height = 16;
    for (glm::dvec3 eye : {glm::dvec3(3, 0, 0), glm::dvec3(-3, 0, 0), glm::dvec3(0, 0, 3)}) {
        const ReferenceImage img = render_reference(g, camera_at(eye), o);
        const glm::vec3 expect = sh_color(1, g.sh.data(), glm::vec3(glm::normalize(-eye)));
        const float t = img.transmittance[img.index(8, 8)];
        EXPECT_LT(glm::length(img.color[img.index(8, 8)] - expect * (1 - t)), 1e-5f) << eye.x;
    }
}

GaussianCloud sphere_with_sh() {
    GaussianCloud g = gaussians_from_splats(assets::make_sphere_cloud(20000));
    // View-dependent colour so the rigid test also checks the SH rotation end to end.
    const std::vector<float> dc = g.sh;
    g.sh_degree = 2;
    g.sh.assign(g.size() * 27, 0.0f);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-0.3f, 0.3f);
    for (std::size_t i = 0; i < g.size(); ++i) {
        for (std::size_t c = 0; c < 3; ++c) g.sh[i * 27 + c] = dc[i * 3 + c];
        for (std::size_t k = 3; k < 27; ++k) g.sh[i * 27 + k] = u(rng);
    }
    return g;
}

TEST(GaussianReferenceRender, RigidLatticeMotionRendersTheSameImageFromTheMovedCamera) {
    const GaussianCloud g = sphere_with_sh();
    Lattice l = ffd::make_lattice(
        {-1.2, -1.2, -1.2}, {glm::dvec3(2.4, 0, 0), glm::dvec3(0, 2.4, 0), glm::dvec3(0, 0, 2.4)}, {3, 3, 3});
    const glm::dmat3 q = glm::mat3_cast(glm::angleAxis(1.1, glm::normalize(glm::dvec3(0.2, 1, -0.4))));
    const glm::dvec3 t(0.5, 0.1, -0.3);
    for (std::size_t c = 0; c < l.size(); ++c) l.current[c] = q * l.rest[c] + t;
    GaussianCloud moved;
    ASSERT_TRUE(deform(l, g, moved));
    ReferenceOptions o;
    o.width = o.height = 128;
    const Camera cam = camera_at({0.4, 0.8, 3.2}, {0, 0, 0}, {0, 1, 0});
    const Camera cam_moved = camera_at(q * cam.eye + t, q * cam.target + t, q * cam.up);
    const ReferenceImage a = render_reference(g, cam, o), b = render_reference(moved, cam_moved, o);
    const double p = psnr(a, b);
    EXPECT_GT(p, 50.0) << "PSNR " << p << " dB";
    // Without the SH rotation the colours would be wrong: the same positions and covariances with the
    // unrotated SH give a clearly different image.
    GaussianCloud unrotated = moved;
    unrotated.sh = g.sh;
    const double wrong = psnr(a, render_reference(unrotated, cam_moved, o));
    std::printf("rigid motion: PSNR %.1f dB (with SH rotation), %.1f dB (SH left unrotated)\n", p, wrong);
    EXPECT_LT(wrong, p - 10.0);
}

double coverage(const ReferenceImage& img, glm::dvec2 center, glm::dvec2 semi_axes) {
    // Fraction of the pixels well inside the ellipse whose transmittance is below 10%.
    int inside = 0, covered = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            const glm::dvec2 d = (glm::dvec2(x + 0.5, y + 0.5) - center) / semi_axes;
            if (glm::dot(d, d) > 0.9 * 0.9) continue;
            ++inside;
            covered += img.transmittance[img.index(x, y)] < 0.1f;
        }
    return inside ? double(covered) / inside : 0.0;
}

TEST(GaussianReferenceRender, StretchedSphereStaysClosedWithDeformedCovariances) {
    // Stretch a converted sphere (5,000 Gaussians: ~4 px apart in this view) 2.5x along x with a lattice.
    // With Σ' = J Σ Jᵀ the surface stays closed; moving only the centres (old covariances) opens gaps.
    const GaussianCloud g = gaussians_from_splats(assets::make_sphere_cloud(5000));
    Lattice l = ffd::make_lattice(
        {-1.1, -1.1, -1.1}, {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)}, {2, 2, 2});
    for (std::size_t c = 0; c < l.size(); ++c) l.current[c].x = 2.5 * l.rest[c].x;
    GaussianCloud stretched;
    ASSERT_TRUE(deform(l, g, stretched));
    ReferenceOptions o;
    o.width = 512, o.height = 256;
    const Camera cam = camera_at({0, 0, 6}, {0, 0, 0}, {0, 1, 0}, 30.0f);
    const double f = 256 / (2.0 * std::tan(glm::radians(15.0)));
    // Silhouette: an ellipse of semi-axes about f·(2.5, 1)/6 px (the limb is slightly smaller than the
    // perspective outline; the 0.9 shrink in coverage() absorbs it).
    const glm::dvec2 centre(256, 128), axes(f * 2.5 / 6, f / 6);
    const double rest = coverage(render_reference(g, cam, o), centre, glm::dvec2(f / 6));
    const double good = coverage(render_reference(stretched, cam, o), centre, axes);
    GaussianCloud centres_only = g;
    centres_only.positions = stretched.positions;
    const double naive = coverage(render_reference(centres_only, cam, o), centre, axes);
    std::printf("coverage: rest %.4f, stretched %.4f, centres only %.4f\n", rest, good, naive);
    EXPECT_GT(rest, 0.999);
    EXPECT_GT(good, 0.999);
    EXPECT_LT(naive, 0.8);
}

}  // namespace
