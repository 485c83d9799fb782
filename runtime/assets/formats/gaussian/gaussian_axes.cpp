#include "runtime/assets/formats/gaussian/gaussian_axes.h"

#include <cstddef>

namespace sffd::gaussian {

AxisTurnParts axis_turn_parts(AxisTurn turn) {
    AxisTurnParts t;
    const glm::dvec3 s = turn == AxisTurn::x180 ? glm::dvec3(1, -1, -1) : glm::dvec3(-1, -1, 1);
    t.scale = glm::vec3(s);
    t.rotation = turn == AxisTurn::x180 ? glm::quat(0, 1, 0, 0) : glm::quat(0, 0, 0, 1);
    // Sign of each basis function under the turn: Y_k(R d) = ±Y_k(d). Every 3DGS basis function of degree
    // <= 3 (systems/gaussian/sh.h) is even or odd in each coordinate; kOdd[k] holds its parity in x, y, z
    // (bits 0, 1, 2), so a coordinate's sign flip flips Y_k when Y_k is odd in it.
    //   k: 0 C0 | 1 y, 2 z, 3 x | 4 xy, 5 yz, 6 2z²-x²-y², 7 xz, 8 x²-y² |
    //      9 y(3x²-y²), 10 xyz, 11 y(4z²-x²-y²), 12 z(2z²-3x²-3y²), 13 x(4z²-x²-y²), 14 z(x²-y²), 15
    //      x(x²-3y²)
    constexpr unsigned kOdd[16] = {0, 2, 4, 1, 3, 6, 0, 5, 0, 2, 7, 2, 4, 1, 4, 1};
    for (std::size_t k = 0; k < 16; ++k) {
        double sign = 1.0;
        for (int axis = 0; axis < 3; ++axis)
            if ((kOdd[k] >> axis) & 1u) sign *= s[axis];
        t.sh_sign[k] = float(sign);
    }
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
