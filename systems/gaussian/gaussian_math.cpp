#include "systems/gaussian/gaussian_math.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace sffd::gaussian {

glm::dmat3 covariance(const glm::dvec3& scale, const glm::dquat& q) {
    const glm::dmat3 r = glm::mat3_cast(glm::normalize(q));
    const glm::dmat3 m = r * glm::dmat3(scale.x, 0, 0, 0, scale.y, 0, 0, 0, scale.z);
    return m * glm::transpose(m);
}

SymEigen sym_eigen(const glm::dmat3& in) { return sym_eigen(in, glm::dmat3(1.0)); }

SymEigen sym_eigen(const glm::dmat3& in, const glm::dmat3& guess) {
    // Cyclic Jacobi on Gᵀ A G: each rotation zeroes one off-diagonal entry; converges quadratically and
    // never needs the eigenvalues to be distinct (no characteristic polynomial, no deflation). A good
    // guess G leaves little to rotate (one sweep instead of four to six).
    const glm::dmat3 sym = 0.5 * (in + glm::transpose(in));
    const glm::dmat3 rotated = glm::transpose(guess) * sym * guess;
    double a[3][3], v[3][3];
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) a[r][c] = 0.5 * (rotated[c][r] + rotated[r][c]), v[r][c] = guess[c][r];
    double norm = 0.0;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) norm += a[r][c] * a[r][c];
    const double tiny = 1e-300;
    for (int sweep = 0; sweep < 64; ++sweep) {
        const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        if (off <= 1e-32 * norm || off < tiny) break;
        for (int p = 0; p < 2; ++p)
            for (int q = p + 1; q < 3; ++q) {
                const double apq = a[p][q];
                if (std::abs(apq) < tiny) continue;
                const double theta = (a[q][q] - a[p][p]) / (2.0 * apq);
                const double t = (theta >= 0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1.0));
                const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
                // A ← Gᵀ A G with G the rotation in the (p, q) plane.
                for (int k = 0; k < 3; ++k) {
                    const double akp = a[k][p], akq = a[k][q];
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < 3; ++k) {
                    const double apk = a[p][k], aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                for (int k = 0; k < 3; ++k) {
                    const double vkp = v[k][p], vkq = v[k][q];
                    v[k][p] = c * vkp - s * vkq;
                    v[k][q] = s * vkp + c * vkq;
                }
            }
    }
    int order[3] = {0, 1, 2};
    std::sort(order, order + 3, [&](int x, int y) { return a[x][x] > a[y][y]; });
    SymEigen e;
    for (int i = 0; i < 3; ++i) {
        e.values[i] = a[order[i]][order[i]];
        e.vectors[i] = glm::dvec3(v[0][order[i]], v[1][order[i]], v[2][order[i]]);
    }
    if (glm::determinant(e.vectors) < 0.0) e.vectors[2] = -e.vectors[2];
    return e;
}

glm::dmat3 orthonormalize(const glm::dmat3& m) {
    glm::dvec3 a = m[0], b = m[1];
    const double la = glm::length(a);
    if (!(la > 1e-300)) return glm::dmat3(1.0);
    a /= la;
    b -= glm::dot(a, b) * a;
    const double lb = glm::length(b);
    if (!(lb > 1e-12 * glm::length(m[1]))) return glm::dmat3(1.0);
    b /= lb;
    return glm::dmat3(a, b, glm::cross(a, b));
}

glm::dquat quat_from_rotation(const glm::dmat3& r) {
    glm::dquat q = glm::normalize(glm::quat_cast(r));
    if (q.w < 0.0) q = -q;
    return q;
}

ScaleRotation decompose_covariance(const glm::dmat3& sigma) { return decompose_covariance(sigma, glm::dmat3(1.0)); }

ScaleRotation decompose_covariance(const glm::dmat3& sigma, const glm::dmat3& guess) {
    const SymEigen e = sym_eigen(sigma, guess);
    ScaleRotation out;
    for (int i = 0; i < 3; ++i) out.scale[i] = std::sqrt(std::max(0.0, e.values[i]));
    out.rotation = quat_from_rotation(e.vectors);
    return out;
}

Polar polar_decomposition(const glm::dmat3& j) {
    Polar p;
    double n2 = 0.0;
    for (int c = 0; c < 3; ++c) n2 += glm::dot(j[c], j[c]);
    const double det = glm::determinant(j);
    if (!(std::abs(det) > 1e-12 * n2 * std::sqrt(n2))) {
        p.ok = false;
        return p;
    }
    // Newton iteration X ← (ζX + ζ⁻¹X⁻ᵀ)/2 with Frobenius-norm scaling ζ = (‖X⁻¹‖/‖X‖)^½ (Higham): the
    // orthogonal factor of the polar decomposition in a handful of steps, keeping the sign of det J.
    glm::dmat3 x = j;
    for (int it = 0; it < 40; ++it) {
        const glm::dmat3 inv_t = glm::transpose(glm::inverse(x));
        double nx = 0.0, ni = 0.0;
        for (int c = 0; c < 3; ++c) nx += glm::dot(x[c], x[c]), ni += glm::dot(inv_t[c], inv_t[c]);
        const double zeta = std::sqrt(std::sqrt(ni / nx));
        const glm::dmat3 next = 0.5 * (zeta * x + (1.0 / zeta) * inv_t);
        double change = 0.0, size = 0.0;
        for (int c = 0; c < 3; ++c) {
            const glm::dvec3 dc = next[c] - x[c];
            change += glm::dot(dc, dc);
            size += glm::dot(next[c], next[c]);
        }
        x = next;
        if (change <= 1e-30 * size) break;
    }
    p.rotation = x;
    const glm::dmat3 u = glm::transpose(x) * j;
    p.stretch = 0.5 * (u + glm::transpose(u));
    return p;
}

}  // namespace sffd::gaussian
