// Covariance, symmetric eigen-decomposition, covariance -> scale + rotation, polar decomposition.
#include <gtest/gtest.h>

#include <random>

#include <glm/gtc/quaternion.hpp>

#include "systems/gaussian/gaussian_math.h"

namespace {

using namespace sffd::gaussian;

double max_abs_diff(const glm::dmat3& a, const glm::dmat3& b) {
    double m = 0.0;
    for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r) m = std::max(m, std::abs(a[c][r] - b[c][r]));
    return m;
}

glm::dquat random_quat(std::mt19937& rng) {
    std::normal_distribution<double> n;
    return glm::normalize(glm::dquat(n(rng), n(rng), n(rng), n(rng)));
}

glm::dmat3 random_matrix(std::mt19937& rng, double spread = 1.0) {
    std::uniform_real_distribution<double> u(-spread, spread);
    glm::dmat3 m;
    for (int c = 0; c < 3; ++c) m[c] = glm::dvec3(u(rng), u(rng), u(rng));
    return m;
}

TEST(GaussianMath, CovarianceMatchesSumOfRotatedAxes) {
    // Independent of mat3_cast: rotate the basis vectors with the quaternion product q v q*.
    std::mt19937 rng(1);
    for (int t = 0; t < 100; ++t) {
        const glm::dquat q = random_quat(rng);
        const glm::dvec3 s(0.1 + t * 0.01, 0.5, 2.0 - t * 0.01);
        glm::dmat3 expect(0.0);
        for (int i = 0; i < 3; ++i) {
            glm::dvec3 e(0.0);
            e[i] = 1.0;
            const glm::dvec3 a = q * e;  // glm: q * v = q v q⁻¹
            expect += s[i] * s[i] * glm::outerProduct(a, a);
        }
        EXPECT_LT(max_abs_diff(covariance(s, q), expect), 1e-12);
        // The quaternion need not be normalised.
        EXPECT_LT(max_abs_diff(covariance(s, 3.0 * q), expect), 1e-12);
    }
}

void check_eigen(const glm::dmat3& a, double tol) {
    const SymEigen e = sym_eigen(a);
    EXPECT_GE(e.values[0], e.values[1]);
    EXPECT_GE(e.values[1], e.values[2]);
    EXPECT_NEAR(glm::determinant(e.vectors), 1.0, 1e-12);
    EXPECT_LT(max_abs_diff(glm::transpose(e.vectors) * e.vectors, glm::dmat3(1.0)), 1e-12);
    const glm::dmat3 d(e.values[0], 0, 0, 0, e.values[1], 0, 0, 0, e.values[2]);
    EXPECT_LT(max_abs_diff(e.vectors * d * glm::transpose(e.vectors), a), tol);
    for (int i = 0; i < 3; ++i) {
        const glm::dvec3 v = e.vectors[i];
        EXPECT_LT(glm::length(a * v - e.values[i] * v), tol);
    }
}

TEST(GaussianMath, SymEigenRandomAndRepeatedEigenvalues) {
    std::mt19937 rng(2);
    for (int t = 0; t < 200; ++t) {
        const glm::dmat3 m = random_matrix(rng);
        check_eigen(m * glm::transpose(m), 1e-12);  // SPD
        check_eigen(m + glm::transpose(m), 1e-12);  // indefinite
    }
    // Repeated eigenvalues: exact multiples of the identity, double and triple, zero eigenvalues.
    check_eigen(glm::dmat3(3.0), 1e-15);
    check_eigen(glm::dmat3(0.0), 1e-15);
    for (int t = 0; t < 50; ++t) {
        const glm::dmat3 q = glm::mat3_cast(random_quat(rng));
        for (glm::dvec3 ev : {glm::dvec3(2, 2, 5), glm::dvec3(5, 2, 2), glm::dvec3(1, 0, 0),
                              glm::dvec3(1e-8, 1e-8, 1), glm::dvec3(4, 4, 4)}) {
            const glm::dmat3 a = q * glm::dmat3(ev.x, 0, 0, 0, ev.y, 0, 0, 0, ev.z) * glm::transpose(q);
            check_eigen(a, 1e-12);
            const SymEigen e = sym_eigen(a);
            glm::dvec3 sorted = ev;
            if (sorted.x < sorted.y) std::swap(sorted.x, sorted.y);
            if (sorted.y < sorted.z) std::swap(sorted.y, sorted.z);
            if (sorted.x < sorted.y) std::swap(sorted.x, sorted.y);
            for (int i = 0; i < 3; ++i) EXPECT_NEAR(e.values[i], sorted[i], 1e-12);
        }
    }
}

TEST(GaussianMath, SymEigenFromAnyOrthogonalGuess) {
    // The warm start only changes the work, never the result: random, reflected, exact and degenerate
    // guesses all give a correct decomposition.
    std::mt19937 rng(7);
    for (int t = 0; t < 100; ++t) {
        const glm::dmat3 m = random_matrix(rng);
        const glm::dmat3 a = m * glm::transpose(m);
        glm::dmat3 guess = glm::mat3_cast(random_quat(rng));
        if (t % 2) guess[1] = -guess[1];
        for (const glm::dmat3& g :
             {guess, sym_eigen(a).vectors, orthonormalize(m), orthonormalize(glm::dmat3(0.0))}) {
            const SymEigen e = sym_eigen(a, g);
            const glm::dmat3 d(e.values[0], 0, 0, 0, e.values[1], 0, 0, 0, e.values[2]);
            EXPECT_LT(max_abs_diff(e.vectors * d * glm::transpose(e.vectors), a), 1e-12);
            EXPECT_NEAR(glm::determinant(e.vectors), 1.0, 1e-12);
            EXPECT_GE(e.values[0], e.values[1]);
            EXPECT_GE(e.values[1], e.values[2]);
        }
    }
}

TEST(GaussianMath, DecomposeCovarianceRoundTrips) {
    std::mt19937 rng(3);
    for (int t = 0; t < 200; ++t) {
        const glm::dquat q = random_quat(rng);
        const glm::dvec3 s(std::exp(-3.0 + 0.03 * t), 0.7, std::exp(2.0 - 0.02 * t));
        const glm::dmat3 sigma = covariance(s, q);
        const ScaleRotation sr = decompose_covariance(sigma);
        EXPECT_NEAR(glm::length(sr.rotation), 1.0, 1e-12);
        EXPECT_GE(sr.rotation.w, 0.0);
        EXPECT_LT(max_abs_diff(covariance(sr.scale, sr.rotation), sigma),
                  1e-12 * (1.0 + s.x * s.x + s.z * s.z));
        // Same scales as the input, as a set.
        glm::dvec3 a = s, b = sr.scale;
        std::sort(&a[0], &a[0] + 3), std::sort(&b[0], &b[0] + 3);
        for (int i = 0; i < 3; ++i) EXPECT_NEAR(a[i], b[i], 1e-9 * (1 + a[i]));
    }
    // A flat Gaussian (one zero scale) decomposes with a zero scale, not NaN.
    const ScaleRotation flat = decompose_covariance(covariance({1.0, 0.5, 0.0}, glm::dquat(1, 0, 0, 0)));
    EXPECT_EQ(flat.scale.z, 0.0);
    EXPECT_TRUE(std::isfinite(flat.rotation.w));
}

TEST(GaussianMath, PolarDecomposition) {
    std::mt19937 rng(4);
    for (int t = 0; t < 300; ++t) {
        glm::dmat3 j = glm::dmat3(1.0) + random_matrix(rng, 0.8);
        if (t % 3 == 0) j[0] = -j[0];  // also maps that invert
        if (std::abs(glm::determinant(j)) < 1e-3) continue;
        const Polar p = polar_decomposition(j);
        ASSERT_TRUE(p.ok);
        EXPECT_LT(max_abs_diff(glm::transpose(p.rotation) * p.rotation, glm::dmat3(1.0)), 1e-12);
        EXPECT_NEAR(glm::determinant(p.rotation), glm::determinant(j) > 0 ? 1.0 : -1.0, 1e-12);
        EXPECT_LT(max_abs_diff(p.rotation * p.stretch, j), 1e-12);
        EXPECT_LT(max_abs_diff(p.stretch, glm::transpose(p.stretch)), 1e-12);
        const SymEigen e = sym_eigen(p.stretch);
        EXPECT_GT(e.values[2], 0.0);
        // Independent formula: U = sqrt(JᵀJ) from the eigen-decomposition of JᵀJ.
        const SymEigen g = sym_eigen(glm::transpose(j) * j);
        const glm::dmat3 root = g.vectors *
                                glm::dmat3(std::sqrt(g.values[0]), 0, 0, 0, std::sqrt(g.values[1]), 0, 0, 0,
                                           std::sqrt(g.values[2])) *
                                glm::transpose(g.vectors);
        EXPECT_LT(max_abs_diff(root, p.stretch), 1e-10);
    }
    // A rotation is its own polar factor; a singular map is reported.
    const glm::dmat3 rot = glm::mat3_cast(glm::angleAxis(0.7, glm::normalize(glm::dvec3(1, 2, 3))));
    EXPECT_LT(max_abs_diff(polar_decomposition(rot).rotation, rot), 1e-14);
    EXPECT_FALSE(polar_decomposition(glm::dmat3(1, 0, 0, 0, 1, 0, 0, 0, 0)).ok);
}

}  // namespace
