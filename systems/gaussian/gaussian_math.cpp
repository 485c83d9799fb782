#include "systems/gaussian/gaussian_math.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "runtime/scene/sym_eigen.h"

namespace sffd::gaussian {

glm::dmat3 covariance(const glm::dvec3& scale, const glm::dquat& q) {
    const glm::dmat3 r = glm::mat3_cast(glm::normalize(q));
    const glm::dmat3 m = r * glm::dmat3(scale.x, 0, 0, 0, scale.y, 0, 0, 0, scale.z);
    return m * glm::transpose(m);
}

SymEigen sym_eigen(const glm::dmat3& in) { return sym_eigen(in, glm::dmat3(1.0)); }

SymEigen sym_eigen(const glm::dmat3& in, const glm::dmat3& guess) {
    // Jacobi on Gᵀ A G (runtime/scene/sym_eigen.h): a good guess G leaves little to rotate (one sweep instead
    // of four to six). Stops at 1e-32 of the squared Frobenius norm or below 1e-300 absolute.
    const glm::dmat3 sym = 0.5 * (in + glm::transpose(in));
    const glm::dmat3 rotated = glm::transpose(guess) * sym * guess;
    const Eigen3 j =
        jacobi_eigen(0.5 * (rotated + glm::transpose(rotated)), guess, JacobiRule{}, EigenOrder::descending);
    SymEigen e;
    e.values = j.values;
    e.vectors = j.vectors;
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

ScaleRotation decompose_covariance(const glm::dmat3& sigma) {
    return decompose_covariance(sigma, glm::dmat3(1.0));
}

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
