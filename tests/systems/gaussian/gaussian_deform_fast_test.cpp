// The vectorised shape/colour kernel of gaussian::deform against the double-precision per-Gaussian path
// (DeformOptions::reference_shapes), both from the same Jacobians: covariances, SH colours, view-mode
// frames and statistics, on clouds whose sizes are not a multiple of the vector width, partly outside the
// lattice, in place and chained, and on a lattice that flattens its cells. Every case runs once per SIMD
// target this CPU runs (names end in /avx3, /avx2, /sse4, /scalar), with the same tolerances on each.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "systems/ffd/lattice.h"
#include "systems/ffd/operations.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/gaussian_deform.h"
#include "systems/gaussian/gaussian_deform_fast.h"
#include "systems/gaussian/gaussian_math.h"
#include "systems/gaussian/sh.h"
#include "tests/systems/gaussian/test_math.h"
#include "tests/test_util/simd_targets.h"

namespace {

using namespace sffd;
using namespace sffd::gaussian;
using sffd::test::max_abs;

Lattice twisted(LatticeBasis basis, int div) {
    Lattice l =
        ffd::make_lattice({-1, -1, -1}, {glm::dvec3(2, 0, 0), glm::dvec3(0, 2, 0), glm::dvec3(0, 0, 2)},
                          {div, div, div}, basis);
    ffd::twist_graded(l, ffd::all_control_points(l), {0, 1, 0}, 0.8, glm::dvec3(0.0));
    for (glm::dvec3& p : l.current) p.x += 0.2 * p.y * p.y, p.z *= 1.0 + 0.3 * p.x;
    return l;
}

GaussianCloud cloud(std::size_t n, int degree, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1, 1);
    std::normal_distribution<float> nd;
    GaussianCloud g;
    g.sh_degree = degree;
    for (std::size_t i = 0; i < n; ++i) {
        g.positions.emplace_back(1.2f * u(rng), 1.2f * u(rng), 1.2f * u(rng));  // some outside [-1,1]³
        // Anisotropic, some needle-thin (axis ratio down to 1e-3).
        const float thin = i % 7 == 0 ? 1e-3f : 0.3f + 0.2f * u(rng);
        g.scales.emplace_back(0.03f * (1.2f + u(rng)), 0.02f * (1.1f + u(rng)), 0.03f * thin);
        g.rotations.push_back(glm::normalize(glm::quat(nd(rng), nd(rng), nd(rng), nd(rng))));
        g.opacities.push_back(0.5f);
        for (int k = 0; k < sh_coeffs(degree) * 3; ++k) g.sh.push_back(0.5f * u(rng));
    }
    return g;
}

glm::dmat3 sigma(const GaussianCloud& g, std::size_t i) {
    return covariance(glm::dvec3(g.scales[i]), glm::dquat(g.rotations[i]));
}

// Largest colour difference over a few directions (coefficients |c| <= 0.5, as the GPU comparison).
float colour_error(const GaussianCloud& a, const GaussianCloud& b, std::size_t i) {
    const int K = sh_coeffs(a.sh_degree);
    float e = 0.0f;
    for (const glm::vec3 d :
         {glm::vec3(0.3f, -0.5f, 0.8f), glm::vec3(-0.9f, 0.1f, 0.4f), glm::vec3(0.2f, 0.9f, -0.3f)}) {
        const glm::vec3 n = glm::normalize(d);
        const glm::vec3 da = a.sh_frames.empty() ? n : glm::transpose(a.sh_frames[i]) * n;
        const glm::vec3 db = b.sh_frames.empty() ? n : glm::transpose(b.sh_frames[i]) * n;
        e = std::max(e, glm::length(sh_color(a.sh_degree, &a.sh[i * std::size_t(K) * 3], da) -
                                    sh_color(b.sh_degree, &b.sh[i * std::size_t(K) * 3], db)));
    }
    return e;
}

void expect_match(const GaussianCloud& fast, const GaussianCloud& ref, const char* what) {
    ASSERT_EQ(fast.size(), ref.size());
    double worst_sigma = 0.0;
    float worst_colour = 0.0f;
    for (std::size_t i = 0; i < ref.size(); ++i) {
        EXPECT_LT(glm::length(fast.positions[i] - ref.positions[i]), 1e-5f) << what << " " << i;
        const glm::dmat3 s = sigma(ref, i);
        worst_sigma = std::max(worst_sigma, max_abs(sigma(fast, i) - s) / max_abs(s));
        worst_colour = std::max(worst_colour, colour_error(fast, ref, i));
        EXPECT_EQ(fast.opacities[i], ref.opacities[i]);
    }
    EXPECT_LT(worst_sigma, 3e-5) << what;  // the GPU pass's tolerance against the same reference
    EXPECT_LT(worst_colour, 5e-5f) << what;
}

class GaussianDeformFast : public sffd::test::EverySimdTarget {};

TEST_P(GaussianDeformFast, MatchesTheDoublePrecisionReference) {
    for (LatticeBasis basis : {LatticeBasis::bernstein, LatticeBasis::bspline})
        for (int degree : {0, 1, 3}) {
            const Lattice l = twisted(basis, 5);
            const GaussianCloud g =
                cloud(1003, degree, unsigned(7 + degree));  // not a multiple of any lane width
            GaussianCloud fast, ref;
            DeformOptions ro;
            ro.reference_shapes = true;
            auto fs = deform(l, g, fast);
            auto rs = deform(l, g, ref, ro);
            ASSERT_TRUE(fs && rs);
            EXPECT_EQ(fs->inside, rs->inside);
            EXPECT_EQ(fs->inverted, rs->inverted);
            EXPECT_EQ(fs->degenerate, rs->degenerate);
            EXPECT_GT(rs->inside, 300u);
            EXPECT_LT(rs->inside, g.size());
            expect_match(fast, ref, degree == 3 ? "degree 3" : "degree < 3");
            // Outside Gaussians are copied bit for bit (their SH rows too: whole vector groups of degree 3
            // write every row, the input's where nothing was rotated).
            const std::size_t row = std::size_t(sh_coeffs(degree)) * 3;
            for (std::size_t i = 0; i < g.size(); ++i)
                if (glm::any(glm::greaterThan(glm::abs(g.positions[i]), glm::vec3(1.0f)))) {
                    EXPECT_EQ(fast.scales[i], g.scales[i]);
                    EXPECT_EQ(fast.rotations[i], g.rotations[i]);
                    EXPECT_TRUE(std::equal(&g.sh[i * row], &g.sh[i * row] + row, &fast.sh[i * row])) << i;
                }
        }
}

TEST_P(GaussianDeformFast, PolarRotationsAreWithinFloatRoundingOfTheReference) {
    // The vectorised Newton iteration (polar_rotation) must give the double-precision reference's rotations
    // to float rounding, under a strong shear where it needs most steps (the other tests allow 1e-5).
    Lattice l = twisted(LatticeBasis::bernstein, 4);
    for (glm::dvec3& p : l.current) p.y += 0.6 * p.x * p.z, p.x *= 1.0 + 0.5 * p.y * p.y;
    const GaussianCloud g = cloud(2000, 1, 5);
    DeformOptions view, view_ref;
    view.sh = view_ref.sh = ShMode::rotate_view;
    view_ref.reference_shapes = true;
    GaussianCloud fv = g, rv = g;
    ASSERT_TRUE(deform(l, fv, fv, view));
    ASSERT_TRUE(deform(l, rv, rv, view_ref));
    ASSERT_EQ(fv.sh_frames.size(), g.size());
    double worst = 0.0, worst_orthogonality = 0.0;
    std::size_t rotated = 0;
    for (std::size_t i = 0; i < g.size(); ++i) {
        const glm::dmat3 f(fv.sh_frames[i]);
        if (f == glm::dmat3(1.0)) continue;  // outside, or not moved
        ++rotated;
        worst = std::max(worst, max_abs(f - glm::dmat3(rv.sh_frames[i])));
        worst_orthogonality = std::max(worst_orthogonality, max_abs(glm::transpose(f) * f - glm::dmat3(1.0)));
    }
    std::printf("polar rotations: %zu, worst entry error %.2e, worst |RᵀR - I| %.2e\n", rotated, worst,
                worst_orthogonality);
    EXPECT_GT(rotated, 1000u);
    EXPECT_LT(worst, 1e-6);
    EXPECT_LT(worst_orthogonality, 1e-6);
}

TEST_P(GaussianDeformFast, ViewModeAndChainedInPlaceDeformationsMatchTheReference) {
    const Lattice a = twisted(LatticeBasis::bernstein, 4), b = twisted(LatticeBasis::bspline, 6);
    const GaussianCloud g = cloud(777, 3, 21);
    DeformOptions view, view_ref, ref;
    view.sh = view_ref.sh = ShMode::rotate_view;
    view_ref.reference_shapes = ref.reference_shapes = true;
    GaussianCloud fv = g, rv = g, fc = g, rc = g;
    for (const Lattice* l : {&a, &b}) {
        ASSERT_TRUE(deform(*l, fv, fv, view));
        ASSERT_TRUE(deform(*l, rv, rv, view_ref));
        ASSERT_TRUE(deform(*l, fc, fc));
        ASSERT_TRUE(deform(*l, rc, rc, ref));
    }
    ASSERT_EQ(fv.sh_frames.size(), g.size());
    for (std::size_t i = 0; i < g.size(); ++i)
        EXPECT_LT(max_abs(glm::dmat3(fv.sh_frames[i]) - glm::dmat3(rv.sh_frames[i])), 1e-5) << i;
    EXPECT_EQ(fv.sh, g.sh);
    expect_match(fv, rv, "view mode");
    expect_match(fc, rc, "coefficients, chained");
    expect_match(fv, rc, "view mode against rotated coefficients");
}

TEST_P(GaussianDeformFast, FlattenedCellsCountAsDegenerateWithoutNaN) {
    // Every control point's y set to 0: J has a zero row, Σ' is flat, the SH stay unrotated. The reference
    // lattice evaluator for both (the fast one leaves rounding-size entries in that row). Degree 3 moves
    // its whole groups' rows as vectors, degree 2 one Gaussian at a time.
    Lattice l = ffd::make_lattice({-1, -1, -1},
                                  {glm::dvec3(2, 0, 0), glm::dvec3(0, 2, 0), glm::dvec3(0, 0, 2)}, {3, 3, 3});
    for (glm::dvec3& p : l.current) p.y = 0.0;
    for (int degree : {2, 3}) {
        const GaussianCloud g = cloud(133, degree, 5);
        GaussianCloud fast, ref;
        DeformOptions fo, ro;
        fo.backend = ro.backend = ffd::Backend::reference;
        ro.reference_shapes = true;
        auto fs = deform(l, g, fast, fo);
        auto rs = deform(l, g, ref, ro);
        ASSERT_TRUE(fs && rs);
        EXPECT_EQ(fs->degenerate, rs->degenerate) << degree;
        EXPECT_EQ(fs->degenerate, rs->inside) << degree;
        EXPECT_GT(rs->inside, 50u) << degree;
        for (std::size_t i = 0; i < g.size(); ++i) {
            for (int c = 0; c < 3; ++c) EXPECT_TRUE(std::isfinite(fast.scales[i][c])) << i;
            EXPECT_TRUE(std::isfinite(glm::dot(fast.rotations[i], fast.rotations[i]))) << i;
            if (glm::all(glm::lessThanEqual(glm::abs(g.positions[i]), glm::vec3(1.0f)))) {
                EXPECT_LT(fast.scales[i].z, 1e-6f * fast.scales[i].x) << i;  // the collapsed axis, last
                const glm::dmat3 s = sigma(ref, i);
                EXPECT_LT(max_abs(sigma(fast, i) - s), 1e-4 * max_abs(s)) << i;
            }
        }
        EXPECT_EQ(fast.sh, g.sh) << degree;
    }
}

TEST_P(GaussianDeformFast, NeedlesWithTwoTinyAxesKeepThemFiniteAndSmall) {
    // Two axes 1e-10 of the third: their columns' dot products are under float's normal range (the
    // rotation's angle is then taken from them scaled up). Every Gaussian keeps a finite shape, is not
    // dropped, and its two small axes stay of their size (|J| is within [0.5, 2] on this lattice).
    const Lattice l = twisted(LatticeBasis::bernstein, 4);
    GaussianCloud g = cloud(2003, 3, 17);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(1.0f, 1.5f);
    for (glm::vec3& s : g.scales) s = glm::vec3(0.05f, 0.05e-10f * u(rng), 0.05e-10f * u(rng));
    GaussianCloud fast;
    auto fs = deform(l, g, fast);
    ASSERT_TRUE(fs);
    EXPECT_EQ(fs->not_finite, 0u);
    EXPECT_GT(fs->inside, 1000u);
    for (std::size_t i = 0; i < g.size(); ++i) {
        glm::vec3 s = fast.scales[i];
        for (int c = 0; c < 3; ++c) ASSERT_TRUE(std::isfinite(s[c])) << i;
        ASSERT_EQ(fast.opacities[i], g.opacities[i]) << i;
        std::sort(&s[0], &s[0] + 3);
        EXPECT_GT(s.x, 0.05e-10f * 0.2f) << i;
        EXPECT_LT(s.y, 0.05e-10f * 1.5f * 3.0f) << i;
        EXPECT_GT(s.z, 0.05f * 0.3f) << i;
    }
}

// Coefficients or a centre that are not finite (a cloud made in memory: readers refuse them), or a rotation
// that is not a unit quaternion, are dropped by both kernels, into another cloud (whole vector groups of
// degree 3 are checked before their rows are streamed out) and in place, whether the lattice moves the
// Gaussian or not: the same ones, transparent, no colour left, counted.
TEST_P(GaussianDeformFast, NonFiniteCoefficientsAreDroppedIntoAnotherCloudAndInPlace) {
    const Lattice l = twisted(LatticeBasis::bernstein, 4);
    GaussianCloud g = cloud(16 * 4 + 5, 3, 5);  // whole groups at every lane width, and a partial one
    const std::size_t row = 48;
    // Gaussian, coefficient: bands 1-3, and the band 0 colour (never rotated) of one inside and one outside.
    const std::vector<std::pair<std::size_t, std::size_t>> bad_at = {{3, 3},  {17, 10}, {40, 17}, {41, 24},
                                                                     {50, 1}, {51, 2},  {63, 31}, {66, 38}};
    std::vector<std::size_t> bad;
    for (std::size_t b = 0; b < bad_at.size(); ++b) {
        const auto [i, k] = bad_at[b];
        bad.push_back(i);
        // Half inside the lattice (rotated), half outside (copied).
        g.positions[i] = b % 2 ? glm::vec3(0.1f, -0.2f, 0.3f) : glm::vec3(1.5f, 0.0f, 0.0f);
        g.sh[i * row + k] =
            b % 3 ? std::numeric_limits<float>::quiet_NaN() : std::numeric_limits<float>::infinity();
    }
    // A zero rotation outside the lattice is copied as it is, not a unit quaternion: dropped too.
    g.positions[25] = glm::vec3(0.0f, 1.5f, 0.0f);
    g.rotations[25] = glm::quat(0.0f, 0.0f, 0.0f, 0.0f);
    bad.push_back(25);
    // A centre that is not finite: dropped at the origin, as the GPU pass does, instead of at its centre.
    g.positions[30] = glm::vec3(std::numeric_limits<float>::quiet_NaN(), 0.0f, 0.0f);
    bad.push_back(30);
    for (bool in_place : {false, true})
        for (bool reference : {false, true}) {
            const std::string what = std::string(in_place ? "in place" : "into another cloud") +
                                     (reference ? ", reference kernel" : ", vectorised kernel");
            DeformOptions options;
            options.reference_shapes = reference;
            options.copy_opacities = true;
            GaussianCloud out = in_place ? g : GaussianCloud{};
            auto st = in_place ? deform(l, out, out, options) : deform(l, g, out, options);
            ASSERT_TRUE(st) << st.message();
            EXPECT_EQ(st->not_finite, bad.size()) << what;
            for (std::size_t i = 0; i < g.size(); ++i) {
                const bool dropped = std::find(bad.begin(), bad.end(), i) != bad.end();
                EXPECT_EQ(out.opacities[i], dropped ? 0.0f : 0.5f) << what << " " << i;
                const glm::vec3 p = out.positions[i];
                EXPECT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))
                    << what << " " << i;
                if (i == 30) {
                    EXPECT_EQ(p, glm::vec3(0.0f)) << what;
                }
                for (std::size_t k = 0; k < row; ++k) {
                    const float c = out.sh[i * row + k];
                    if (dropped) EXPECT_EQ(c, 0.0f) << what << " " << i << " " << k;
                    else EXPECT_TRUE(std::isfinite(c)) << what << " " << i << " " << k;
                }
            }
        }
}

// A Jacobian past the float range (a 1e-12 box with a control point moved by 1e29: J ~1e41) is not finite:
// those Gaussians are dropped and counted by both kernels alike, in whole vector groups and in the partial
// one, at every degree's row layout; the others keep finite shapes and colours.
TEST_P(GaussianDeformFast, JacobiansPastTheFloatRangeAreDroppedAndCountedAsByTheReference) {
    Lattice l = ffd::make_lattice(
        {0, 0, 0}, {glm::dvec3(1e-12, 0, 0), glm::dvec3(0, 1e-12, 0), glm::dvec3(0, 0, 1e-12)}, {1, 1, 1});
    l.current[l.index(1, 1, 1)] += glm::dvec3(1e29, -1e29, 1e29);
    for (int degree : {1, 3}) {
        GaussianCloud g;
        g.sh_degree = degree;
        const std::size_t row = std::size_t(sh_coeffs(degree)) * 3;
        const std::size_t n = 16 * 2 + 5;  // whole groups at every lane width, and a partial one
        for (std::size_t i = 0; i < n; ++i) {
            // Every other one in the box's interior (J overflows), the others near its origin corner, where
            // the moved point's weight barely changes (J ~1e35: finite, near-singular by the 1e-12 rule).
            const float t = float(i) / float(n);
            g.positions.push_back(i % 2
                                      ? glm::vec3(1e-12f * t, 1e-12f * (1.0f - t), 1e-12f * (0.5f + 0.4f * t))
                                      : glm::vec3(1e-15f * (1.0f + t), 1e-15f * (2.0f - t), 1.5e-15f));
            g.scales.emplace_back(1e-13f);
            g.rotations.emplace_back(1.0f, 0.0f, 0.0f, 0.0f);
            g.opacities.push_back(0.8f);
            for (std::size_t k = 0; k < row; ++k) g.sh.push_back(0.1f);
        }
        std::vector<std::uint8_t> dropped[2];
        std::size_t counted[2] = {}, degenerate[2] = {};
        for (bool reference : {false, true}) {
            GaussianCloud out;
            DeformOptions options;
            options.backend = ffd::Backend::reference, options.copy_opacities = true;
            options.reference_shapes = reference;
            auto st = deform(l, g, out, options);
            ASSERT_TRUE(st) << st.message();
            counted[reference] = st->not_finite, degenerate[reference] = st->degenerate;
            for (std::size_t i = 0; i < out.size(); ++i) {
                const glm::quat q = out.rotations[i];
                EXPECT_TRUE(std::isfinite(q.w + q.x + q.y + q.z)) << i;
                EXPECT_TRUE(std::isfinite(out.scales[i].x + out.scales[i].y + out.scales[i].z)) << i;
                EXPECT_TRUE(std::isfinite(out.positions[i].x + out.positions[i].y + out.positions[i].z)) << i;
                for (std::size_t k = 0; k < row; ++k) EXPECT_TRUE(std::isfinite(out.sh[i * row + k])) << i;
                dropped[reference].push_back(out.opacities[i] == 0.0f);
            }
        }
        EXPECT_EQ(counted[1], n / 2) << degree;
        EXPECT_EQ(counted[0], counted[1]) << degree;
        EXPECT_EQ(degenerate[0], degenerate[1]) << degree;
        EXPECT_EQ(dropped[0], dropped[1]) << degree;
        EXPECT_EQ(std::size_t(std::count(dropped[0].begin(), dropped[0].end(), 1)), counted[0]) << degree;
    }
}

// The kernel that runs is the pinned target's (so the cases above test each target's code).
TEST_P(GaussianDeformFast, KernelRunsThePinnedTargetsLaneWidth) {
    const std::string t = GetParam().name;
    const int expected = t == "avx3" || t == "avx3_dl" ? 16
                         : t == "avx2"                 ? 8
                         : t == "sse4" || t == "neon"  ? 4
                                                       : 1;
    EXPECT_EQ(simd::chosen(), t);
    EXPECT_EQ(detail::shape_lane_width(), expected) << t;
}

SFFD_INSTANTIATE_EVERY_SIMD_TARGET(GaussianDeformFast);

}  // namespace
