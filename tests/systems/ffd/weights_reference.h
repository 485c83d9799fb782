// An independent double-precision reference for weighted FFD (tests only): Sederberg–Parry's Bernstein sum
// X' = Σ P[i][j][k] B(l,i,s) B(m,j,t) B(n,k,u) over the current control points of a lattice with a uniform
// rest grid, its analytic Jacobian J = [F_s F_t F_u] M⁻¹ (../shared/notes/ffd-math.md), and the weighted
// blend every deformer must give: X_w = X + w (X' − X), J_w = I + w (J − I); normals by the cofactor of J_w,
// splat axes J_w a, Gaussian covariances J_w Σ J_wᵀ, SH by the polar rotation of J_w. Nothing here calls
// the library's evaluators (local coordinates, bases and sums are written out again).
#pragma once

#include <cmath>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/scene/lattice.h"

namespace sffd::ffd::test {

struct WeightedRef {
    glm::dvec3 position{0.0};
    glm::dmat3 jacobian{1.0};
    bool inside = false;
};

inline double ref_binomial(int n, int k) {
    double r = 1.0;
    for (int i = 1; i <= k; ++i) r = r * double(n - k + i) / double(i);
    return r;
}
inline double ref_bernstein(int n, int i, double s) {
    if (i < 0 || i > n) return 0.0;
    return ref_binomial(n, i) * std::pow(1.0 - s, n - i) * std::pow(s, i);
}
inline double ref_bernstein_d(int n, int i, double s) {
    return n * (ref_bernstein(n - 1, i - 1, s) - ref_bernstein(n - 1, i, s));
}

// Rows of M⁻¹ from the cross products: (T×U)/((T×U)·S), (S×U)/((S×U)·T), (S×T)/((S×T)·U).
inline glm::dmat3 ref_inverse_axes(const Lattice& l) {
    const glm::dvec3 S = l.axes[0], T = l.axes[1], U = l.axes[2];
    const glm::dvec3 r0 = glm::cross(T, U) / glm::dot(glm::cross(T, U), S);
    const glm::dvec3 r1 = glm::cross(S, U) / glm::dot(glm::cross(S, U), T);
    const glm::dvec3 r2 = glm::cross(S, T) / glm::dot(glm::cross(S, T), U);
    return glm::transpose(glm::dmat3(r0, r1, r2));  // glm is column-major: rows r0, r1, r2
}

// The weighted Bernstein FFD of one world point (a lattice whose rest is the uniform grid).
inline WeightedRef weighted_bernstein(const Lattice& l, const glm::dvec3& x, double w) {
    WeightedRef r;
    r.position = x;
    const glm::dmat3 minv = ref_inverse_axes(l);
    const glm::dvec3 stu = minv * (x - l.origin);
    const double slack = 1e-6;
    for (int a = 0; a < 3; ++a)
        if (!(stu[a] >= -slack && stu[a] <= 1.0 + slack)) return r;
    r.inside = true;
    const glm::dvec3 c = glm::clamp(stu, glm::dvec3(0.0), glm::dvec3(1.0));
    const int L = l.divisions.x, M = l.divisions.y, N = l.divisions.z;
    glm::dvec3 X(0.0), Fs(0.0), Ft(0.0), Fu(0.0);
    for (int i = 0; i <= L; ++i)
        for (int j = 0; j <= M; ++j)
            for (int k = 0; k <= N; ++k) {
                const glm::dvec3 P = l.current[std::size_t((i * (M + 1) + j) * (N + 1) + k)];
                const double bs = ref_bernstein(L, i, c.x), bt = ref_bernstein(M, j, c.y),
                             bu = ref_bernstein(N, k, c.z);
                X += P * (bs * bt * bu);
                Fs += P * (ref_bernstein_d(L, i, c.x) * bt * bu);
                Ft += P * (bs * ref_bernstein_d(M, j, c.y) * bu);
                Fu += P * (bs * bt * ref_bernstein_d(N, k, c.z));
            }
    const glm::dmat3 J = glm::dmat3(Fs, Ft, Fu) * minv;
    r.position = x + w * (X - x);
    r.jacobian = glm::dmat3(1.0) + w * (J - glm::dmat3(1.0));
    return r;
}

// cof(J) n normalised: (b×c) n.x + (c×a) n.y + (a×b) n.z with a, b, c the columns of J.
inline glm::dvec3 ref_cofactor_normal(const glm::dmat3& J, const glm::dvec3& n) {
    const glm::dvec3 v =
        glm::cross(J[1], J[2]) * n.x + glm::cross(J[2], J[0]) * n.y + glm::cross(J[0], J[1]) * n.z;
    return v / glm::length(v);
}

// The orthogonal polar factor R of J = R U, by Newton's iteration R <- (R + R⁻ᵀ) / 2 in double.
inline glm::dmat3 ref_polar_rotation(const glm::dmat3& J) {
    glm::dmat3 R = J;
    for (int it = 0; it < 100; ++it) {
        const glm::dmat3 next = 0.5 * (R + glm::transpose(glm::inverse(R)));
        double d = 0.0;
        for (int c = 0; c < 3; ++c) d = std::max(d, glm::length(next[c] - R[c]));
        R = next;
        if (d < 1e-15) break;
    }
    return R;
}

// A Bernstein lattice around [lo, lo + size]³ (slightly skewed) with every control point moved by a smooth
// field: a bend, a twist and a stretch, so J is far from I and anisotropic.
inline Lattice weighted_test_lattice(glm::ivec3 div, double lo = -1.2, double size = 2.4) {
    Lattice l = make_lattice(
        glm::dvec3(lo, lo - 0.05, lo + 0.03),
        {glm::dvec3(size, 0.1, -0.05), glm::dvec3(0.08, size, 0.1), glm::dvec3(-0.1, 0.05, size)}, div);
    for (glm::dvec3& p : l.current) {
        const double a = 0.35 * p.y;
        const glm::dvec3 q(std::cos(a) * p.x + std::sin(a) * p.z, p.y,
                           -std::sin(a) * p.x + std::cos(a) * p.z);
        p = q + glm::dvec3(0.15 * q.y * q.y, 0.2 * q.x, 0.1 * std::sin(2.0 * q.x)) +
            glm::dvec3(0.1 * q.x, 0, 0);
    }
    return l;
}

}  // namespace sffd::ffd::test
