#include "systems/gaussian/gaussian_axes.h"

#include <cstddef>

#include "systems/gaussian/sh.h"

namespace sffd::gaussian {

void turn_axes(GaussianCloud& g, AxisTurn turn) {
    const glm::dvec3 s = turn == AxisTurn::x180 ? glm::dvec3(1, -1, -1) : glm::dvec3(-1, -1, 1);
    const glm::quat qr = turn == AxisTurn::x180 ? glm::quat(0, 1, 0, 0) : glm::quat(0, 0, 0, 1);
    // Sign of each basis function under the turn: Y_k(R d) = ±Y_k(d); read off at a direction where no
    // basis function of degree <= 3 vanishes, so the ratio is exactly ±1.
    const glm::dvec3 d = glm::normalize(glm::dvec3(0.31, 0.52, 0.79));
    double y[16], yr[16];
    sh_basis(3, d, y);
    sh_basis(3, s * d, yr);
    float sign[16];
    for (int k = 0; k < 16; ++k) sign[k] = y[k] * yr[k] < 0 ? -1.0f : 1.0f;
    const glm::vec3 sf(s);
    g.origin *= s;
    for (glm::vec3& p : g.positions) p *= sf;
    for (glm::quat& q : g.rotations) q = qr * q;
    const std::size_t K = std::size_t(sh_coeffs(g.sh_degree));
    for (std::size_t i = 0, n = g.sh.size() / (3 * K); i < n; ++i)
        for (std::size_t k = 1; k < K; ++k)
            for (std::size_t c = 0; c < 3; ++c) g.sh[(i * K + k) * 3 + c] *= sign[k];
    // Derived clouds' SH frames (view-direction mode) are expressed in the old axes: turn them too.
    const glm::mat3 r(glm::vec3(sf.x, 0, 0), glm::vec3(0, sf.y, 0), glm::vec3(0, 0, sf.z));
    for (glm::mat3& f : g.sh_frames) f = r * f * r;
}

}  // namespace sffd::gaussian
