#include "systems/gaussian/gaussian_axes.h"

#include <cstddef>

#include "systems/gaussian/sh.h"

namespace sffd::gaussian {

AxisTurnParts axis_turn_parts(AxisTurn turn) {
    AxisTurnParts t;
    const glm::dvec3 s = turn == AxisTurn::x180 ? glm::dvec3(1, -1, -1) : glm::dvec3(-1, -1, 1);
    t.scale = glm::vec3(s);
    t.rotation = turn == AxisTurn::x180 ? glm::quat(0, 1, 0, 0) : glm::quat(0, 0, 0, 1);
    // Sign of each basis function under the turn: Y_k(R d) = ±Y_k(d); read off at a direction where no
    // basis function of degree <= 3 vanishes, so the ratio is exactly ±1.
    const glm::dvec3 d = glm::normalize(glm::dvec3(0.31, 0.52, 0.79));
    double y[16], yr[16];
    sh_basis(3, d, y);
    sh_basis(3, s * d, yr);
    for (int k = 0; k < 16; ++k) t.sh_sign[std::size_t(k)] = y[k] * yr[k] < 0 ? -1.0f : 1.0f;
    return t;
}

void turn_axes(GaussianCloud& g, AxisTurn turn) {
    const AxisTurnParts t = axis_turn_parts(turn);
    g.origin *= glm::dvec3(t.scale);
    for (glm::vec3& p : g.positions) p *= t.scale;
    for (glm::quat& q : g.rotations) q = t.rotation * q;
    const std::size_t K = std::size_t(sh_coeffs(g.sh_degree));
    for (std::size_t i = 0, n = g.sh.size() / (3 * K); i < n; ++i)
        for (std::size_t k = 1; k < K; ++k)
            for (std::size_t c = 0; c < 3; ++c) g.sh[(i * K + k) * 3 + c] *= t.sh_sign[k];
    // Derived clouds' SH frames (view-direction mode) are expressed in the old axes: turn them too.
    const glm::vec3 sf = t.scale;
    const glm::mat3 r(glm::vec3(sf.x, 0, 0), glm::vec3(0, sf.y, 0), glm::vec3(0, 0, sf.z));
    for (glm::mat3& f : g.sh_frames) f = r * f * r;
}

}  // namespace sffd::gaussian
