// Deforming Gaussians through a lattice: the ffd Jacobian output, Σ' = J Σ Jᵀ against finite differences
// and a Monte Carlo fit of the pushed-forward density, rigid lattice motions, the ECS system. The cases of
// the CPU deformation itself (GaussianDeformCpu) run once per SIMD target this CPU runs.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>

#include <glm/gtc/quaternion.hpp>

#include "runtime/ecs/registry.h"
#include "systems/animation/animation_system.h"
#include "systems/animation/components.h"
#include "systems/ffd/components.h"
#include "systems/ffd/deform.h"
#include "systems/ffd/lattice.h"
#include "systems/ffd/operations.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/gaussian_deform.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "systems/gaussian/reference_render.h"
#include "systems/gaussian/gaussian_math.h"
#include "systems/gaussian/gaussian_system.h"
#include "systems/gaussian/sh.h"
#include "tests/systems/gaussian/test_math.h"
#include "tests/test_util/simd_targets.h"

namespace {

using namespace sffd;
using namespace sffd::gaussian;

using sffd::test::max_abs;

// A 4³ Bernstein (or B-spline) lattice around [-1,1]³ with a graded twist about y and a bend.
Lattice twisted_lattice(LatticeBasis basis = LatticeBasis::bernstein, int div = 4) {
    Lattice l =
        ffd::make_lattice({-1, -1, -1}, {glm::dvec3(2, 0, 0), glm::dvec3(0, 2, 0), glm::dvec3(0, 0, 2)},
                          {div, div, div}, basis);
    ffd::twist_graded(l, ffd::all_control_points(l), {0, 1, 0}, 0.6, glm::dvec3(0.0));
    for (glm::dvec3& p : l.current) p.x += 0.15 * p.y * p.y;
    return l;
}

GaussianCloud random_cloud(std::size_t n, int degree, double extent, double scale, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1, 1);
    std::normal_distribution<float> nd;
    GaussianCloud g;
    g.origin = glm::dvec3(0.0);
    g.sh_degree = degree;
    for (std::size_t i = 0; i < n; ++i) {
        g.positions.emplace_back(float(extent) * u(rng), float(extent) * u(rng), float(extent) * u(rng));
        g.scales.emplace_back(float(scale) * (1.2f + u(rng)), float(scale) * (1.2f + u(rng)),
                              float(scale) * (0.2f + 0.1f * u(rng)));
        g.rotations.push_back(glm::normalize(glm::quat(nd(rng), nd(rng), nd(rng), nd(rng))));
        g.opacities.push_back(0.5f + 0.4f * u(rng));
        for (int k = 0; k < sh_coeffs(degree) * 3; ++k) g.sh.push_back(0.5f * u(rng));
    }
    return g;
}

TEST(GaussianDeform, FfdJacobianOutputMatchesReferenceOnEveryBackend) {
    for (LatticeBasis basis : {LatticeBasis::bernstein, LatticeBasis::bspline}) {
        Lattice l = twisted_lattice(basis);
        const GaussianCloud g = random_cloud(3000, 0, 1.3, 0.01, 1);  // some points outside the box
        for (ffd::Backend b : {ffd::Backend::fast, ffd::Backend::sparse, ffd::Backend::reference}) {
            if (basis == LatticeBasis::bspline && b == ffd::Backend::sparse) continue;
            std::vector<glm::vec3> pos(g.size());
            std::vector<glm::mat3> jac(g.size(), glm::mat3(0.0f));
            ffd::PointsOut out{pos.data(), nullptr, nullptr, nullptr};
            out.jacobians = jac.data();
            auto stats =
                ffd::deform(l, {g.positions.data(), nullptr, nullptr, nullptr, g.size(), g.origin}, out, b);
            ASSERT_TRUE(stats) << stats.message();
            std::size_t outside = 0;
            for (std::size_t i = 0; i < g.size(); ++i) {
                const ffd::ReferencePoint rp = ffd::reference_point(l, glm::dvec3(g.positions[i]));
                if (!rp.inside) {
                    ++outside;
                    EXPECT_EQ(jac[i], glm::mat3(1.0f));
                    continue;
                }
                EXPECT_LT(max_abs(glm::dmat3(jac[i]) - rp.jacobian), 2e-5 * max_abs(rp.jacobian))
                    << ffd::backend_name(b);
            }
            EXPECT_GT(outside, 100u);
        }
    }
}

class GaussianDeformCpu : public sffd::test::EverySimdTarget {};

// Σ' of Gaussian i from the output's scale + rotation.
glm::dmat3 out_sigma(const GaussianCloud& g, std::size_t i) {
    return covariance(glm::dvec3(g.scales[i]), glm::dquat(g.rotations[i]));
}

TEST_P(GaussianDeformCpu, CovarianceMatchesCentralDifferencesOfTheLatticeMap) {
    // Σ' = Σ_a (J a)(J a)ᵀ over the scaled principal axes a of Σ; J a from central differences of the
    // double-precision lattice map along a (independent of the float kernels' Jacobian).
    const Lattice l = twisted_lattice();
    const GaussianCloud g = random_cloud(400, 0, 0.9, 0.05, 2);
    GaussianCloud out;
    auto stats = deform(l, g, out);
    ASSERT_TRUE(stats) << stats.message();
    EXPECT_EQ(stats->inside, g.size());
    const double h = 1e-4;
    for (std::size_t i = 0; i < g.size(); ++i) {
        const glm::dvec3 mu(g.positions[i]);
        const glm::dmat3 a = glm::mat3_cast(glm::dquat(g.rotations[i])) *
                             glm::dmat3(g.scales[i].x, 0, 0, 0, g.scales[i].y, 0, 0, 0, g.scales[i].z);
        glm::dmat3 expect(0.0);
        for (int c = 0; c < 3; ++c) {
            const glm::dvec3 d = (ffd::reference_point(l, mu + h * a[c] / glm::length(a[c])).position -
                                  ffd::reference_point(l, mu - h * a[c] / glm::length(a[c])).position) /
                                 (2 * h) * glm::length(a[c]);
            expect += glm::outerProduct(d, d);
        }
        const glm::dmat3 got = out_sigma(out, i);
        EXPECT_LT(max_abs(got - expect), 1e-4 * max_abs(expect)) << i;
        EXPECT_LT(glm::length(glm::dvec3(out.positions[i]) - ffd::reference_point(l, mu).position), 1e-5);
    }
}

TEST_P(GaussianDeformCpu, CovarianceMatchesMonteCarloFitOfTheDeformedDensity) {
    // Sample a small Gaussian, push the samples through the actual lattice (fast float path), fit their
    // covariance: it must match J Σ Jᵀ up to sampling noise (~sqrt(2/N) = 0.3%) and curvature (~scale).
    const Lattice l = twisted_lattice();
    const GaussianCloud g = random_cloud(5, 0, 0.6, 0.02, 3);
    GaussianCloud out;
    ASSERT_TRUE(deform(l, g, out));
    std::mt19937 rng(9);
    std::normal_distribution<double> nd;
    const std::size_t N = 200000;
    for (std::size_t i = 0; i < g.size(); ++i) {
        const glm::dmat3 a = glm::mat3_cast(glm::dquat(g.rotations[i])) *
                             glm::dmat3(g.scales[i].x, 0, 0, 0, g.scales[i].y, 0, 0, 0, g.scales[i].z);
        std::vector<glm::vec3> samples(N), moved(N);
        for (glm::vec3& s : samples)
            s = glm::vec3(glm::dvec3(g.positions[i]) + a * glm::dvec3(nd(rng), nd(rng), nd(rng)));
        ASSERT_TRUE(ffd::deform(l, {samples.data(), nullptr, nullptr, nullptr, N, {}},
                                {moved.data(), nullptr, nullptr, nullptr}));
        glm::dvec3 mean(0.0);
        for (const glm::vec3& m : moved) mean += glm::dvec3(m);
        mean /= double(N);
        glm::dmat3 cov(0.0);
        for (const glm::vec3& m : moved) cov += glm::outerProduct(glm::dvec3(m) - mean, glm::dvec3(m) - mean);
        cov /= double(N - 1);
        const glm::dmat3 expect = out_sigma(out, i);
        EXPECT_LT(max_abs(cov - expect), 0.02 * max_abs(expect)) << i;
        EXPECT_LT(glm::length(mean - glm::dvec3(out.positions[i])), 0.01 * glm::length(a[0]) + 1e-4);
    }
}

TEST_P(GaussianDeformCpu, RigidLatticeMotionMovesGaussiansRigidly) {
    // Every control point moved by x -> Q x + t: linear precision makes the FFD exactly that map, so
    // centres, covariances and the colours seen from rotated view directions must follow it.
    Lattice l = ffd::make_lattice({-1, -1, -1},
                                  {glm::dvec3(2, 0, 0), glm::dvec3(0, 2, 0), glm::dvec3(0, 0, 2)}, {3, 4, 2});
    const glm::dmat3 q = glm::mat3_cast(glm::angleAxis(0.9, glm::normalize(glm::dvec3(1, -2, 0.5))));
    const glm::dvec3 t(0.3, -0.2, 0.7);
    for (std::size_t c = 0; c < l.size(); ++c) l.current[c] = q * l.rest[c] + t;
    const GaussianCloud g = random_cloud(500, 3, 0.95, 0.05, 4);
    GaussianCloud out;
    auto stats = deform(l, g, out);
    ASSERT_TRUE(stats) << stats.message();
    EXPECT_EQ(stats->inverted, 0u);
    EXPECT_EQ(out.opacities, g.opacities);
    std::mt19937 rng(11);
    std::normal_distribution<double> nd;
    for (std::size_t i = 0; i < g.size(); ++i) {
        EXPECT_LT(glm::length(glm::dvec3(out.positions[i]) - (q * glm::dvec3(g.positions[i]) + t)), 2e-6);
        const glm::dmat3 expect = q * out_sigma(g, i) * glm::transpose(q);
        EXPECT_LT(max_abs(out_sigma(out, i) - expect), 2e-6 * max_abs(expect));
        for (int s = 0; s < 20; ++s) {
            const glm::dvec3 d = glm::normalize(glm::dvec3(nd(rng), nd(rng), nd(rng)));
            const glm::vec3 before = sh_color(3, &g.sh[i * 48], glm::vec3(d));
            const glm::vec3 after = sh_color(3, &out.sh[i * 48], glm::vec3(q * d));
            EXPECT_LT(glm::length(after - before), 2e-5f);
        }
    }
}

TEST_P(GaussianDeformCpu, OutsideGaussiansAreUnchangedAndInversionIsCounted) {
    Lattice l = twisted_lattice();
    GaussianCloud g = random_cloud(200, 2, 0.5, 0.05, 5);
    for (glm::vec3& p : g.positions) p += glm::vec3(5, 0, 0);  // all outside
    GaussianCloud out;
    auto stats = deform(l, g, out);
    ASSERT_TRUE(stats);
    EXPECT_EQ(stats->inside, 0u);
    EXPECT_EQ(out.positions, g.positions);
    EXPECT_EQ(out.scales, g.scales);
    EXPECT_EQ(out.rotations, g.rotations);
    EXPECT_EQ(out.sh, g.sh);
    // A mirror lattice (x -> -x) inverts every Gaussian: det J < 0, still a valid covariance, and the SH
    // transformed by the reflection (colour seen along the mirrored direction is the original).
    Lattice m = ffd::make_lattice({-1, -1, -1},
                                  {glm::dvec3(2, 0, 0), glm::dvec3(0, 2, 0), glm::dvec3(0, 0, 2)}, {2, 2, 2});
    for (std::size_t c = 0; c < m.size(); ++c) m.current[c].x = -m.rest[c].x;
    const GaussianCloud h = random_cloud(100, 3, 0.9, 0.05, 6);
    auto ms = deform(m, h, out);
    ASSERT_TRUE(ms);
    EXPECT_EQ(ms->inverted, h.size());
    const glm::dmat3 f(-1, 0, 0, 0, 1, 0, 0, 0, 1);
    for (std::size_t i = 0; i < h.size(); ++i) {
        EXPECT_LT(max_abs(out_sigma(out, i) - f * out_sigma(h, i) * f), 1e-6);
        const glm::vec3 d = glm::normalize(glm::vec3(0.3f, -0.5f, 0.8f));
        EXPECT_LT(glm::length(sh_color(3, &out.sh[i * 48], glm::vec3(f * glm::dvec3(d))) -
                              sh_color(3, &h.sh[i * 48], d)),
                  2e-5f);
    }
}

TEST_P(GaussianDeformCpu, ViewDirectionModeEqualsCoefficientRotation) {
    // rotate_view keeps the coefficients and stores the polar rotation R per splat; evaluating at Rᵀd
    // must give the colours of rotate_coefficients, also after two chained (in-place) deformations.
    const Lattice l = twisted_lattice();
    const Lattice m = twisted_lattice(LatticeBasis::bspline, 5);
    const GaussianCloud g = random_cloud(300, 3, 0.8, 0.03, 12);
    GaussianCloud coef = g, view = g;
    DeformOptions vo;
    vo.sh = ShMode::rotate_view;
    for (const Lattice* lat : {&l, &m}) {
        ASSERT_TRUE(deform(*lat, coef, coef));
        ASSERT_TRUE(deform(*lat, view, view, vo));
    }
    ASSERT_EQ(view.sh_frames.size(), g.size());
    EXPECT_EQ(view.sh, g.sh);  // untouched
    EXPECT_EQ(view.positions, coef.positions);
    EXPECT_EQ(view.scales, coef.scales);
    std::mt19937 rng(13);
    std::normal_distribution<float> nd;
    for (std::size_t i = 0; i < g.size(); ++i)
        for (int s = 0; s < 10; ++s) {
            const glm::vec3 d = glm::normalize(glm::vec3(nd(rng), nd(rng), nd(rng)));
            const glm::vec3 a = sh_color(3, &coef.sh[i * 48], d);
            const glm::vec3 b = sh_color(3, &view.sh[i * 48], glm::transpose(view.sh_frames[i]) * d);
            EXPECT_LT(glm::length(a - b), 3e-5f) << i;
        }
    // Same images; writers refuse frames until they are baked into the coefficients.
    ReferenceOptions o;
    o.width = o.height = 96;
    Camera cam;
    cam.eye = {0.3, 0.4, 3.0};
    const double p = psnr(render_reference(coef, cam, o), render_reference(view, cam, o));
    EXPECT_GT(p, 70.0) << p;
    const auto path = std::filesystem::temp_directory_path() / "sffd_view_mode.ply";
    auto refused = write_ply(path, view);
    ASSERT_FALSE(refused);
    EXPECT_NE(refused.message().find("bake_sh_frames()"), std::string::npos) << refused.message();
    EXPECT_FALSE(deform(l, view, coef));  // coefficient mode on a cloud with frames is refused too
    bake_sh_frames(view);
    EXPECT_TRUE(view.sh_frames.empty());
    for (std::size_t k = 0; k < view.sh.size(); ++k) EXPECT_NEAR(view.sh[k], coef.sh[k], 3e-5) << k;
}

TEST(GaussianDeform, SystemRunsOnlyWhenSomethingChanged) {
    ecs::Registry reg;
    const ecs::Entity cloud = reg.create(), lat = reg.create();
    reg.emplace<GaussianCloud>(cloud, random_cloud(1000, 1, 0.9, 0.03, 7));
    reg.emplace<Lattice>(lat, twisted_lattice());
    reg.emplace<Deformers>(cloud, Deformers{{lat}});
    gaussian_deform_system(reg, {});
    const DeformedGaussians& d = reg.get<DeformedGaussians>(cloud);
    const std::uint64_t v = d.version;
    GaussianCloud direct;
    ASSERT_TRUE(deform(reg.get<Lattice>(lat), reg.get<GaussianCloud>(cloud), direct));
    EXPECT_EQ(d.cloud.positions, direct.positions);
    EXPECT_EQ(d.cloud.sh, direct.sh);
    EXPECT_TRUE(d.cloud.opacities.empty());
    gaussian_deform_system(reg, {});
    EXPECT_EQ(reg.get<DeformedGaussians>(cloud).version, v);  // nothing moved
    ffd::reset(reg.patch<Lattice>(lat));
    gaussian_deform_system(reg, {});
    EXPECT_GT(reg.get<DeformedGaussians>(cloud).version, v);
    EXPECT_EQ(reg.get<DeformedGaussians>(cloud).cloud.positions,
              reg.get<GaussianCloud>(cloud).positions);  // rest lattice
}

// Two lattices on one cloud: the first reads the authored cloud into the output, the second deforms that
// output in place; the result is the two deformations chained, and the authored cloud is left as it was.
TEST(GaussianDeform, SystemChainsItsLatticesFromTheAuthoredCloud) {
    ecs::Registry reg;
    const ecs::Entity cloud = reg.create(), a = reg.create(), b = reg.create();
    const GaussianCloud authored = random_cloud(1000, 3, 0.9, 0.03, 11);
    reg.emplace<GaussianCloud>(cloud, authored);
    reg.emplace<Lattice>(a, twisted_lattice());
    Lattice stretched = ffd::make_lattice(
        {-1.5, -1.5, -1.5}, {glm::dvec3(3, 0, 0), glm::dvec3(0, 3, 0), glm::dvec3(0, 0, 3)}, {2, 2, 2});
    for (glm::dvec3& p : stretched.current) p.x *= 1.0 + 0.2 * p.y;
    reg.emplace<Lattice>(b, stretched);
    reg.emplace<Deformers>(cloud, Deformers{{a, b}});
    gaussian_deform_system(reg, {});
    GaussianCloud direct;
    ASSERT_TRUE(deform(reg.get<Lattice>(a), authored, direct));
    ASSERT_TRUE(deform(reg.get<Lattice>(b), direct, direct));
    const DeformedGaussians& d = reg.get<DeformedGaussians>(cloud);
    EXPECT_EQ(d.cloud.positions, direct.positions);
    EXPECT_EQ(d.cloud.scales, direct.scales);
    EXPECT_EQ(d.cloud.rotations, direct.rotations);
    EXPECT_EQ(d.cloud.sh, direct.sh);
    EXPECT_NE(d.cloud.sh, authored.sh);  // the twist rotated the colours
    EXPECT_TRUE(d.cloud.opacities.empty());
    const GaussianCloud& now = reg.get<GaussianCloud>(cloud);
    EXPECT_EQ(now.positions, authored.positions);
    EXPECT_EQ(now.sh, authored.sh);
}

TEST(GaussianDeform, AnimatedLatticeMovesTheGaussiansEveryFrame) {
    // A clip twisting every control point about +y through the lattice centre (a rigid rotation, angle
    // 90° × t) drives the lattice; the Gaussian system follows frame by frame: at t the Gaussians are the
    // authored ones turned by 90° × t, colours included.
    ecs::Registry reg;
    const ecs::Entity cloud = reg.create(), lat = reg.create();
    const GaussianCloud authored = random_cloud(200, 2, 0.8, 0.03, 21);
    reg.emplace<GaussianCloud>(cloud, authored);
    Lattice l = ffd::make_lattice({-1, -1, -1},
                                  {glm::dvec3(2, 0, 0), glm::dvec3(0, 2, 0), glm::dvec3(0, 0, 2)}, {3, 3, 3});
    AnimationClip clip;
    clip.duration = 1.0;
    clip.mode = PlayMode::once;
    AnimationTrack track;
    track.kind = TrackKind::twist;
    track.axis = {0, 1, 0};
    for (std::uint32_t c = 0; c < l.size(); ++c) track.points.push_back(c);
    track.keys = {{0.0, glm::dvec3(0.0), Interpolation::linear, Easing::none},
                  {1.0, glm::dvec3(90.0, 0, 0), Interpolation::linear, Easing::none}};
    clip.tracks.push_back(track);
    reg.emplace<Lattice>(lat, l);
    reg.emplace<AnimationClip>(lat, clip);
    reg.emplace<AnimationState>(lat);
    reg.emplace<Deformers>(cloud, Deformers{{lat}});
    std::uint64_t last_version = 0;
    for (int frame = 0; frame <= 4; ++frame) {
        const FrameContext fc{std::uint64_t(frame), 0.25 * frame, frame ? 0.25 : 0.0};
        animation_system(reg, fc);
        gaussian_deform_system(reg, fc);
        const DeformedGaussians& d = reg.get<DeformedGaussians>(cloud);
        ASSERT_TRUE(reg.get<AnimationState>(lat).error.empty()) << reg.get<AnimationState>(lat).error;
        if (frame > 0) {
            EXPECT_GT(d.version, last_version) << frame;  // the lattice moved: re-deformed
        }
        last_version = d.version;
        const glm::dmat3 q =
            glm::mat3_cast(glm::angleAxis(glm::radians(90.0 * 0.25 * frame), glm::dvec3(0, 1, 0)));
        for (std::size_t i = 0; i < authored.size(); ++i) {
            EXPECT_LT(glm::length(glm::dvec3(d.cloud.positions[i]) - q * glm::dvec3(authored.positions[i])),
                      2e-6)
                << frame;
            const glm::dmat3 expect = q * out_sigma(authored, i) * glm::transpose(q);
            EXPECT_LT(max_abs(out_sigma(d.cloud, i) - expect), 2e-6 * max_abs(expect)) << frame;
            const glm::vec3 dir = glm::normalize(glm::vec3(0.3f, -0.2f, 0.9f));
            EXPECT_LT(glm::length(sh_color(2, &d.cloud.sh[i * 27], glm::vec3(q * glm::dvec3(dir))) -
                                  sh_color(2, &authored.sh[i * 27], dir)),
                      2e-5f);
        }
    }
    // Same time again: nothing moved, nothing re-deformed.
    animation_system(reg, {5, 1.0, 0.0});
    gaussian_deform_system(reg, {5, 1.0, 0.0});
    EXPECT_EQ(reg.get<DeformedGaussians>(cloud).version, last_version);
}

SFFD_INSTANTIATE_EVERY_SIMD_TARGET(GaussianDeformCpu);

}  // namespace
