// Picking 3D Gaussians: each Gaussian is an Embree user-geometry ellipsoid at the 3DGS alpha
// cut, k(α) = sqrt(2 ln(255 α)) standard deviations. Expected distances are worked out independently
// from the covariance Σ = R S² Rᵀ: the ray point p(t) is on the boundary when
// (p − c)ᵀ Σ⁻¹ (p − c) = k², a quadratic in t solved here in closed form.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include <glm/gtc/quaternion.hpp>

#include "runtime/app/frame_loop.h"
#include "runtime/ecs/registry.h"
#include "runtime/scene/components.h"
#include "systems/ffd/components.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/gaussian_system.h"
#include "systems/picking/gaussian_source.h"
#include "systems/picking/picking_system.h"
#include "systems/picking/selection.h"
#include "test_scenes.h"

namespace sffd::picking {
namespace {

const double k1 = std::sqrt(2.0 * std::log(255.0));  // opacity 1: 3.3290 σ

struct G {
    glm::dvec3 centre;
    glm::vec3 scale;
    glm::quat rotation{1, 0, 0, 0};
    float opacity = 1.0f;
};

GaussianCloud cloud_of(const std::vector<G>& gs, int sh_degree = 0) {
    GaussianCloud c;
    c.sh_degree = sh_degree;
    for (const G& g : gs) {
        c.positions.emplace_back(g.centre);
        c.scales.push_back(g.scale);
        c.rotations.push_back(g.rotation);
        c.opacities.push_back(g.opacity);
        for (int k = 0; k < sh_coeffs(sh_degree) * 3; ++k) c.sh.push_back(0.1f);
    }
    return c;
}

// Independent reference: entry parameter of the ray into {x : (x − c)ᵀ Σ⁻¹ (x − c) ≤ k²}, −1 on a miss.
double analytic_entry(const G& g, double k, glm::dvec3 o, glm::dvec3 d) {
    const glm::dmat3 R = glm::mat3_cast(glm::dquat(g.rotation));
    const glm::dvec3 s(g.scale);
    const glm::dmat3 S2(s.x * s.x, 0, 0, 0, s.y * s.y, 0, 0, 0, s.z * s.z);
    const glm::dmat3 inv = glm::inverse(R * S2 * glm::transpose(R));
    const glm::dvec3 w = o - g.centre;
    const double a = glm::dot(d, inv * d), b = glm::dot(w, inv * d), c = glm::dot(w, inv * w) - k * k;
    const double disc = b * b - a * c;
    if (disc < 0) return -1;
    return (-b - std::sqrt(disc)) / a;
}

PickQuery ray_query(glm::dvec3 o, glm::dvec3 d) {
    PickQuery q = query_from_ray({o, d});
    return q;
}

TEST(PickingGaussians, AlphaCutSigmas) {
    EXPECT_NEAR(gaussian_pick_sigmas(1.0), 3.3290, 1e-4);
    EXPECT_NEAR(gaussian_pick_sigmas(0.5), std::sqrt(2.0 * std::log(127.5)), 1e-12);
    EXPECT_EQ(gaussian_pick_sigmas(1.0 / 255.0), 0.0);  // exactly at the cut: never drawn
    EXPECT_EQ(gaussian_pick_sigmas(0.001), 0.0);
    EXPECT_EQ(gaussian_pick_sigmas(std::nan("")), 0.0);
}

TEST(PickingGaussians, AxisAlignedGaussianHitsAtTheEllipsoid) {
    ecs::Registry reg;
    const G g{{1.0, 2.0, 3.0}, {0.5f, 1.0f, 2.0f}};
    const ecs::Entity e = reg.create();
    reg.emplace<GaussianCloud>(e, cloud_of({g}));
    PickingState state;
    // Along −x, −y, −z through the centre: entry at the centre + k σ_axis.
    const glm::dvec3 dirs[3] = {{-1, 0, 0}, {0, -1, 0}, {0, 0, -1}};
    for (int a = 0; a < 3; ++a) {
        const glm::dvec3 o = g.centre - 10.0 * dirs[a];
        const PickHit hit = pick(reg, state, ray_query(o, dirs[a]));
        ASSERT_EQ(hit.kind, PickKind::gaussian) << a;
        EXPECT_EQ(hit.entity, e);
        EXPECT_EQ(hit.index, 0u);
        const double sigma = double(g.scale[a]);
        EXPECT_NEAR(hit.distance, 10.0 - k1 * sigma, 1e-5) << a;
        EXPECT_NEAR(glm::length(hit.position - (g.centre - k1 * sigma * dirs[a])), 0.0, 1e-5);
    }
    EXPECT_STREQ(pick_kind_name(PickKind::gaussian), "gaussian");
    EXPECT_EQ(state.gaussian_geometry_count(), 1u);
}

TEST(PickingGaussians, RotatedGaussiansMatchTheCovarianceQuadratic) {
    std::mt19937 rng(17);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    int hits = 0;
    for (int trial = 0; trial < 50; ++trial) {
        ecs::Registry reg;
        G g{{u(rng), u(rng), u(rng)},
            {float(0.1 + 0.4 * (u(rng) + 1)), float(0.1 + 0.4 * (u(rng) + 1)),
             float(0.02 + 0.2 * (u(rng) + 1))},
            glm::normalize(glm::quat(float(u(rng)), float(u(rng)), float(u(rng)), float(u(rng)))),
            float(0.05 + 0.475 * (u(rng) + 1))};
        reg.emplace<GaussianCloud>(reg.create(), cloud_of({g}));
        PickingState state;
        const double k = std::sqrt(2.0 * std::log(255.0 * double(g.opacity)));
        // Rays from a random far point towards a point near the centre: some hit, some miss.
        const glm::dvec3 o = g.centre + 6.0 * glm::normalize(glm::dvec3(u(rng), u(rng), u(rng)));
        const glm::dvec3 aim = g.centre + 1.5 * glm::dvec3(u(rng), u(rng), u(rng));
        const glm::dvec3 d = glm::normalize(aim - o);
        const double expect = analytic_entry(g, k, o, d);
        const PickHit hit = pick(reg, state, ray_query(o, d));
        if (expect < 0) {
            EXPECT_EQ(hit.kind, PickKind::none) << trial;
        } else {
            ASSERT_EQ(hit.kind, PickKind::gaussian) << trial;
            EXPECT_NEAR(hit.distance, expect, 2e-5) << trial;
            ++hits;
        }
    }
    // Both outcomes are exercised (aims spread ±1.5 around the centre; the ellipsoids reach 0.2 to 3.3).
    EXPECT_GT(hits, 10);
    EXPECT_LT(hits, 45);
    std::printf("rotated Gaussians: %d of 50 rays hit\n", hits);
}

TEST(PickingGaussians, RotationTurnsTheLongAxis) {
    // Long axis σ = 2 along local x, turned 90° about z onto world y.
    ecs::Registry reg;
    const G g{{0, 0, 0}, {2.0f, 0.25f, 0.25f}, glm::angleAxis(glm::radians(90.0f), glm::vec3(0, 0, 1))};
    reg.emplace<GaussianCloud>(reg.create(), cloud_of({g}));
    PickingState state;
    EXPECT_NEAR(pick(reg, state, ray_query({0, 10, 0}, {0, -1, 0})).distance, 10.0 - 2.0 * k1, 1e-5);
    EXPECT_NEAR(pick(reg, state, ray_query({10, 0, 0}, {-1, 0, 0})).distance, 10.0 - 0.25 * k1, 1e-5);
    // 1.0 along y from the centre, going down z: half a σ off the long axis → inside; 1.0 along x: 4 σ off.
    EXPECT_EQ(pick(reg, state, ray_query({0, 1.0, 10}, {0, 0, -1})).kind, PickKind::gaussian);
    EXPECT_EQ(pick(reg, state, ray_query({1.0, 0, 10}, {0, 0, -1})).kind, PickKind::none);
}

TEST(PickingGaussians, MissJustOutsideHitJustInside) {
    ecs::Registry reg;
    const G g{{0, 0, 0}, {0.3f, 0.3f, 0.3f}, {1, 0, 0, 0}, 0.5f};
    reg.emplace<GaussianCloud>(reg.create(), cloud_of({g}));
    PickingState state;
    const double r = 0.3 * std::sqrt(2.0 * std::log(127.5));  // opacity 0.5: 2.972 σ
    EXPECT_EQ(pick(reg, state, ray_query({r * 0.999, 0, 5}, {0, 0, -1})).kind, PickKind::gaussian);
    EXPECT_EQ(pick(reg, state, ray_query({r * 1.001, 0, 5}, {0, 0, -1})).kind, PickKind::none);
    EXPECT_EQ(pick(reg, state, ray_query({0, 0, 5}, {0, 0, 1})).kind, PickKind::none);  // pointing away
}

TEST(PickingGaussians, NearestOfSeveralAndTransparentOnesSkipped) {
    ecs::Registry reg;
    const std::vector<G> gs = {
        {{0, 0, 0}, {0.2f, 0.2f, 0.2f}},
        {{0, 0, 3}, {0.2f, 0.2f, 0.1f}},
        {{0, 0, 6}, {0.2f, 0.2f, 0.3f}, {1, 0, 0, 0}, 0.003f},  // below 1/255: not drawn
        {{5, 0, 6}, {0.2f, 0.2f, 0.2f}}};
    const ecs::Entity e = reg.create();
    reg.emplace<GaussianCloud>(e, cloud_of(gs));
    PickingState state;
    const PickHit hit = pick(reg, state, ray_query({0, 0, 10}, {0, 0, -1}));
    ASSERT_EQ(hit.kind, PickKind::gaussian);
    EXPECT_EQ(hit.index, 1u);
    EXPECT_NEAR(hit.distance, 7.0 - 0.1 * k1, 1e-5);
    // From below: the one at the origin.
    const PickHit below = pick(reg, state, ray_query({0, 0, -10}, {0, 0, 1}));
    ASSERT_EQ(below.kind, PickKind::gaussian);
    EXPECT_EQ(below.index, 0u);
    EXPECT_NEAR(below.distance, 10.0 - 0.2 * k1, 1e-5);
    // Make the transparent one opaque: it is now the nearest (refresh follows the component change).
    reg.patch<GaussianCloud>(e).opacities[2] = 1.0f;
    const PickHit again = pick(reg, state, ray_query({0, 0, 10}, {0, 0, -1}));
    EXPECT_EQ(again.index, 2u);
    EXPECT_NEAR(again.distance, 4.0 - 0.3 * k1, 1e-5);
}

TEST(PickingGaussians, NearerOfASplatSurfaceAndAGaussianAndOcclusion) {
    ecs::Registry reg;
    const ecs::Entity splats = reg.create();
    reg.emplace<SplatCloud>(splats, test::disc_grid(3, 1.0, 0.6, 1.0, {-1.0, -1.0}));  // sheet at z = 1
    const ecs::Entity gauss = reg.create();
    reg.emplace<GaussianCloud>(gauss,
                               cloud_of({{{0, 0, 2}, {0.1f, 0.1f, 0.1f}}, {{0, 0, 0}, {0.1f, 0.1f, 0.1f}}}));
    PickingState state;
    const PickHit from_top = pick(reg, state, ray_query({0, 0, 10}, {0, 0, -1}));
    ASSERT_EQ(from_top.kind, PickKind::gaussian);
    EXPECT_EQ(from_top.entity, gauss);
    EXPECT_EQ(from_top.index, 0u);
    const PickHit from_below = pick(reg, state, ray_query({0, 0, -10}, {0, 0, 1}));
    ASSERT_EQ(from_below.kind, PickKind::gaussian);
    EXPECT_EQ(from_below.index, 1u);
    // Between the two, going up: the sheet at z = 1 is nearer than the Gaussian at z = 2.
    const PickHit mid = pick(reg, state, ray_query({0, 0, 0.5}, {0, 0, 1}));
    EXPECT_EQ(mid.kind, PickKind::surface);
    EXPECT_EQ(mid.entity, splats);
    // A Gaussian hides what is behind it (occlusion ray), not what is beside it.
    EXPECT_TRUE(state.surface_between({0, 0, 10}, {0, 0, 1.5}));
    EXPECT_FALSE(state.surface_between({3, 3, 10}, {3, 3, 1.5}));
}

TEST(PickingGaussians, EntityTransformAppliesToTheEllipsoid) {
    ecs::Registry reg;
    const ecs::Entity e = reg.create();
    reg.emplace<GaussianCloud>(e, cloud_of({{{1, 0, 0}, {0.1f, 0.2f, 0.3f}}}));
    // Scale x by 3, then turn 90° about z, then move by (0, 0, 5): the centre lands at (0, 3, 5) and the
    // local x axis (σ 0.1 · 3 = 0.3) points along world y.
    reg.emplace<Transform>(
        e, Transform{{0, 0, 5}, glm::angleAxis(glm::radians(90.0), glm::dvec3(0, 0, 1)), {3, 1, 1}});
    PickingState state;
    const PickHit hit = pick(reg, state, ray_query({0, 10, 5}, {0, -1, 0}));
    ASSERT_EQ(hit.kind, PickKind::gaussian);
    EXPECT_NEAR(hit.distance, 7.0 - 0.3 * k1, 1e-5);
    const PickHit side = pick(reg, state, ray_query({10, 3, 5}, {-1, 0, 0}));
    ASSERT_EQ(side.kind, PickKind::gaussian);
    EXPECT_NEAR(side.distance, 10.0 - 0.2 * k1, 1e-5);
}

TEST(PickingGaussians, HostileDataIsNotPickable) {
    ecs::Registry reg;
    const float nan = std::nanf("");
    const ecs::Entity e = reg.create();
    reg.emplace<GaussianCloud>(e, cloud_of({{{0, 0, 0}, {nan, 0.1f, 0.1f}},
                                            {{0, 0, 1}, {0.0f, 0.0f, 0.0f}},
                                            {{0, 0, 2}, {0.1f, 0.1f, 0.1f}, {0, 0, 0, 0}},
                                            {{0, 0, 3}, {0.1f, 0.1f, 0.1f}, {1, 0, 0, 0}, nan},
                                            {{0, 0, 4}, {0.1f, 0.1f, 0.0f}}}));  // flat: pickable, 1e-6 thick
    PickingState state;
    const PickHit hit = pick(reg, state, ray_query({0, 0, 10}, {0, 0, -1}));
    ASSERT_EQ(hit.kind, PickKind::gaussian);
    EXPECT_EQ(hit.index, 4u);
    EXPECT_NEAR(hit.distance, 6.0, 1e-5);
    // Under the flat one, along the ray only the hostile ones remain: nothing is hit.
    EXPECT_EQ(pick(reg, state, ray_query({0, 0, 3.5}, {0, 0, -1})).kind, PickKind::none);
    // A component with mismatched array sizes is skipped, not read out of range.
    reg.patch<GaussianCloud>(e).opacities.pop_back();
    EXPECT_EQ(pick(reg, state, ray_query({0, 0, 10}, {0, 0, -1})).kind, PickKind::none);
    EXPECT_EQ(state.gaussian_geometry_count(), 0u);
}

// Deformed Gaussians: a 2x2x2 Bernstein lattice on the unit cube whose control points are scaled by 2
// along x (a linear map, so the FFD is exactly x' = 2x, J = diag(2, 1, 1)): the Gaussian at
// (0.5, 0.5, 0.5) with σ = 0.05 moves to (1, 0.5, 0.5) with σ_x = 0.1.
TEST(PickingGaussians, PicksFollowTheDeformation) {
    ecs::Registry reg;
    const ecs::Entity lattice = reg.create();
    reg.emplace<Lattice>(lattice, test::box_lattice({0, 0, 0}, {1, 1, 1}, {2, 2, 2}));
    const ecs::Entity e = reg.create();
    reg.emplace<GaussianCloud>(e, cloud_of({{{0.5, 0.5, 0.5}, {0.05f, 0.05f, 0.05f}}}, 1));
    reg.emplace<Deformers>(e, Deformers{{lattice}});
    gaussian_deform_system(reg, FrameContext{});
    PickingState state;
    PickQuery along_x = ray_query({5, 0.5, 0.5}, {-1, 0, 0});
    along_x.control_points = false;
    const PickHit rest = pick(reg, state, along_x);
    ASSERT_EQ(rest.kind, PickKind::gaussian);
    EXPECT_NEAR(rest.distance, 4.5 - 0.05 * k1, 1e-5);

    for (glm::dvec3& p : reg.patch<Lattice>(lattice).current) p.x *= 2.0;
    gaussian_deform_system(reg, FrameContext{});  // the deformation phase, as the engine runs it
    const auto commits = state.stats().surface_commits;
    const PickHit moved = pick(reg, state, along_x);
    ASSERT_EQ(moved.kind, PickKind::gaussian);
    EXPECT_EQ(moved.entity, e);
    EXPECT_NEAR(moved.distance, 4.0 - 0.1 * k1, 1e-5);
    EXPECT_EQ(state.stats().surface_commits, commits + 1);
    // The old place (x = 0.5, off the deformed ellipsoid by 5 σ_x) is empty now; the new one is hit.
    PickQuery down = ray_query({0.5, 0.5, 5}, {0, 0, -1});
    down.control_points = false;
    EXPECT_EQ(pick(reg, state, down).kind, PickKind::none);
    down.ray.origin.x = 1.0;
    EXPECT_EQ(pick(reg, state, down).kind, PickKind::gaussian);
    // Nothing changed: no new commit.
    EXPECT_EQ(state.stats().surface_commits, commits + 1);
    // The brush maps a Gaussian hit back to its authored centre, in the lattice's space.
    const auto rest_point = surface_hit_in_lattice_space(reg, lattice, pick(reg, state, down));
    ASSERT_TRUE(rest_point.has_value());
    EXPECT_NEAR(glm::length(*rest_point - glm::dvec3(0.5)), 0.0, 1e-6);

    EXPECT_EQ(state.stats().gaussian_cpu_deformations, 0u);  // the deformation phase output was current

    // Without Deformers, the authored cloud is picked again.
    reg.remove<Deformers>(e);
    const PickHit authored = pick(reg, state, along_x);
    EXPECT_NEAR(authored.distance, 4.5 - 0.05 * k1, 1e-5);
}

// The default rule picks the Gaussian with the largest 3DGS blending weight α T along the ray (α: the
// Gaussian's alpha at its closest approach, here the centre: α = opacity; T: the transmittance of those
// in front), worked out by hand below; PickSettings::gaussians = first_ellipsoid picks the nearest entry.
TEST(PickingGaussians, MostVisiblePassesOverFaintFloaters) {
    ecs::Registry reg;
    const ecs::Entity e = reg.create();
    reg.emplace<GaussianCloud>(e, cloud_of({{{0, 0, 0}, {0.2f, 0.2f, 0.2f}, {1, 0, 0, 0}, 1.0f},
                                            {{0, 0, 1}, {0.3f, 0.3f, 0.3f}, {1, 0, 0, 0}, 0.1f}}));
    PickingState state;
    const PickQuery down = ray_query({0, 0, 10}, {0, 0, -1});
    // Weights: floater 0.1, opaque one 0.9 · 0.99.
    const PickHit visible = pick(reg, state, down);
    ASSERT_EQ(visible.kind, PickKind::gaussian);
    EXPECT_EQ(visible.index, 0u);
    EXPECT_NEAR(visible.distance, 10.0 - 0.2 * k1, 1e-5);
    reg.set_resource<PickSettings>(PickSettings{0.08, GaussianPick::first_ellipsoid});
    const PickHit first = pick(reg, state, down);
    ASSERT_EQ(first.kind, PickKind::gaussian);
    EXPECT_EQ(first.index, 1u);
    EXPECT_NEAR(first.distance, 9.0 - 0.3 * std::sqrt(2.0 * std::log(25.5)), 1e-5);
    reg.erase_resource<PickSettings>();
    // A faint Gaussian alone is still picked (it is all the pixel shows).
    reg.patch<GaussianCloud>(e).opacities[0] = 0.02f;
    EXPECT_EQ(pick(reg, state, down).index, 1u);  // weights: 0.1, then 0.9 · 0.02
}

TEST(PickingGaussians, BlendingWeightsDecideBetweenTwo) {
    // Front 0.6, back 0.6: weights 0.6 and 0.24 -> front. Front 0.3, back 0.9: 0.3 and 0.63 -> back.
    const std::pair<float, float> cases[] = {{0.6f, 0.6f}, {0.3f, 0.9f}};
    const std::uint32_t expect[] = {1u, 0u};
    for (int c = 0; c < 2; ++c) {
        ecs::Registry reg;
        reg.emplace<GaussianCloud>(reg.create(),
                                   cloud_of({{{0, 0, 0}, {0.2f, 0.2f, 0.2f}, {1, 0, 0, 0}, cases[c].second},
                                             {{0, 0, 2}, {0.2f, 0.2f, 0.2f}, {1, 0, 0, 0}, cases[c].first}}));
        PickingState state;
        EXPECT_EQ(pick(reg, state, ray_query({0, 0, 10}, {0, 0, -1})).index, expect[c]) << c;
    }
}

TEST(PickingGaussians, SplatDiscsAreOpaqueInTheWeighting) {
    ecs::Registry reg;
    const ecs::Entity sheet = reg.create();
    reg.emplace<SplatCloud>(sheet, test::disc_grid(3, 1.0, 0.6, 0.0, {-1.0, -1.0}));  // z = 0
    const ecs::Entity g = reg.create();
    reg.emplace<GaussianCloud>(
        g, cloud_of({{{0, 0, 1}, {0.2f, 0.2f, 0.2f}, {1, 0, 0, 0}, 0.2f},      // in front, faint
                     {{0, 0, -1}, {0.2f, 0.2f, 0.2f}, {1, 0, 0, 0}, 1.0f}}));  // behind the sheet
    PickingState state;
    PickQuery down = ray_query({0, 0, 10}, {0, 0, -1});
    down.control_points = false;
    // Faint Gaussian 0.2, the sheet 0.8 (the Gaussian behind it never counts).
    const PickHit hit = pick(reg, state, down);
    EXPECT_EQ(hit.kind, PickKind::surface);
    EXPECT_EQ(hit.entity, sheet);
    EXPECT_NEAR(hit.distance, 10.0, 1e-5);
    // An opaque Gaussian in front wins over the sheet (0.99 against 0.01).
    reg.patch<GaussianCloud>(g).opacities[0] = 1.0f;
    const PickHit front = pick(reg, state, down);
    EXPECT_EQ(front.kind, PickKind::gaussian);
    EXPECT_EQ(front.index, 0u);
    // From below, the opaque Gaussian under the sheet.
    PickQuery up = ray_query({0, 0, -10}, {0, 0, 1});
    up.control_points = false;
    EXPECT_EQ(pick(reg, state, up).index, 1u);
}

TEST(PickingGaussians, OnlyGaussiansCoveringHalfThePixelHideControlPoints) {
    ecs::Registry reg;
    const ecs::Entity e = reg.create();
    reg.emplace<GaussianCloud>(e, cloud_of({{{0, 0, 1}, {0.3f, 0.3f, 0.3f}, {1, 0, 0, 0}, 0.3f}}));
    PickingState state;
    state.refresh(reg);
    EXPECT_FALSE(state.surface_between({0, 0, 10}, {0, 0, 0}));  // alpha 0.3 on this line
    reg.patch<GaussianCloud>(e).opacities[0] = 0.6f;
    state.refresh(reg);
    EXPECT_TRUE(state.surface_between({0, 0, 10}, {0, 0, 0}));  // alpha 0.6
    // Off-centre by 0.3 = 1 σ: alpha 0.6 e^-0.5 = 0.36 < 0.5.
    EXPECT_FALSE(state.surface_between({0.3, 0, 10}, {0.3, 0, 0}));
}

// Without a current DeformedGaussians (the phase did not run, ran before the last edit, or its output is
// GPU-only), picking deforms centres and Jacobians itself, once per change of its inputs.
TEST(PickingGaussians, PicksFollowTheLatticeWithoutTheDeformationPhase) {
    ecs::Registry reg;
    const ecs::Entity lattice = reg.create();
    reg.emplace<Lattice>(lattice, test::box_lattice({0, 0, 0}, {1, 1, 1}, {2, 2, 2}));
    const ecs::Entity e = reg.create();
    reg.emplace<GaussianCloud>(e, cloud_of({{{0.5, 0.5, 0.5}, {0.05f, 0.05f, 0.05f}}}));
    reg.emplace<Deformers>(e, Deformers{{lattice}});
    for (glm::dvec3& p : reg.patch<Lattice>(lattice).current) p.x *= 2.0;  // x' = 2x
    PickingState state;
    PickQuery along_x = ray_query({5, 0.5, 0.5}, {-1, 0, 0});
    along_x.control_points = false;
    EXPECT_NEAR(pick(reg, state, along_x).distance, 4.0 - 0.1 * k1, 1e-5);
    EXPECT_EQ(state.stats().gaussian_cpu_deformations, 1u);
    pick(reg, state, along_x);
    EXPECT_EQ(state.stats().gaussian_cpu_deformations, 1u);  // nothing moved: no new deformation
    // The phase runs: its output is used (no picking deformation); then a later edit makes it stale.
    gaussian_deform_system(reg, FrameContext{});
    EXPECT_NEAR(pick(reg, state, along_x).distance, 4.0 - 0.1 * k1, 1e-5);
    EXPECT_EQ(state.stats().gaussian_cpu_deformations, 1u);
    for (glm::dvec3& p : reg.patch<Lattice>(lattice).current) p.x *= 1.5;  // x' = 3x, DeformedGaussians stale
    EXPECT_NEAR(pick(reg, state, along_x).distance, 3.5 - 0.15 * k1, 1e-5);
    EXPECT_EQ(state.stats().gaussian_cpu_deformations, 2u);
}

// Two independent routes to the deformed ellipsoid under a non-linear (twisted, stretched) lattice:
// picking's J R S axes versus the deformation phase's Σ' = J Σ Jᵀ re-factored as scale + rotation.
// Random rays must meet both at the same distances.
TEST(PickingGaussians, OwnJacobianEllipsoidsMatchTheDeformationPhase) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<G> gs;
    for (int i = 0; i < 40; ++i)
        gs.push_back(
            {{0.2 + 0.6 * u(rng), 0.2 + 0.6 * u(rng), 0.2 + 0.6 * u(rng)},
             {float(0.01 + 0.03 * u(rng)), float(0.01 + 0.03 * u(rng)), float(0.005 + 0.01 * u(rng))},
             glm::normalize(glm::quat(float(u(rng) - 0.5), float(u(rng) - 0.5), float(u(rng) - 0.5),
                                      float(u(rng) - 0.5))),
             float(0.3 + 0.7 * u(rng))});
    auto scene = [&](ecs::Registry& reg) {
        const ecs::Entity lattice = reg.create();
        Lattice l = test::box_lattice({0, 0, 0}, {1, 1, 1}, {3, 3, 3});
        for (glm::dvec3& p : l.current) {
            const double a = 0.8 * (p.y - 0.5);  // twist about the vertical axis through (0.5, ·, 0.5)
            const glm::dvec3 d = p - glm::dvec3(0.5, p.y, 0.5);
            p = glm::dvec3(0.5 + 1.4 * (std::cos(a) * d.x + std::sin(a) * d.z), p.y,
                           0.5 - std::sin(a) * d.x + std::cos(a) * d.z);
        }
        reg.emplace<Lattice>(lattice, l);
        const ecs::Entity e = reg.create();
        reg.emplace<GaussianCloud>(e, cloud_of(gs));
        reg.emplace<Deformers>(e, Deformers{{lattice}});
    };
    ecs::Registry own, phase;
    scene(own);
    scene(phase);
    gaussian_deform_system(phase, FrameContext{});
    PickingState s_own, s_phase;
    own.set_resource<PickSettings>(PickSettings{0.08, GaussianPick::first_ellipsoid});
    phase.set_resource<PickSettings>(PickSettings{0.08, GaussianPick::first_ellipsoid});
    int hits = 0;
    for (int r = 0; r < 400; ++r) {
        const glm::dvec3 o(-1.0, u(rng), u(rng));
        const glm::dvec3 d = glm::normalize(glm::dvec3(0.0 + 1.5, u(rng), u(rng)) - o);
        PickQuery q = ray_query(o, d);
        q.control_points = false;
        const PickHit a = pick(own, s_own, q), b = pick(phase, s_phase, q);
        ASSERT_EQ(a.kind, b.kind) << r;
        if (a.kind != PickKind::gaussian) continue;
        ++hits;
        EXPECT_EQ(a.index, b.index) << r;
        EXPECT_NEAR(a.distance, b.distance, 2e-5) << r;
    }
    EXPECT_EQ(s_own.stats().gaussian_cpu_deformations, 1u);
    EXPECT_EQ(s_phase.stats().gaussian_cpu_deformations, 0u);
    std::printf("own Jacobians vs deformation phase: %d of 400 rays hit\n", hits);
    EXPECT_GT(hits, 20);
}

}  // namespace
}  // namespace sffd::picking
