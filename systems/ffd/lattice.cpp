#include "systems/ffd/lattice.h"

#include <algorithm>
#include <cmath>

namespace sffd::ffd {

glm::dmat3 inverse_axes(const Lattice& l) {
    const glm::dvec3 &S = l.axes[0], &T = l.axes[1], &U = l.axes[2];
    const glm::dvec3 r0 = glm::cross(T, U) / glm::dot(glm::cross(T, U), S);
    const glm::dvec3 r1 = glm::cross(S, U) / glm::dot(glm::cross(S, U), T);
    const glm::dvec3 r2 = glm::cross(S, T) / glm::dot(glm::cross(S, T), U);
    return glm::transpose(glm::dmat3(r0, r1, r2));  // rows r0, r1, r2
}

glm::dvec3 local_coords(const Lattice& l, const glm::dvec3& world) {
    return inverse_axes(l) * (world - l.origin);
}

bool rest_is_uniform(const Lattice& l) {
    const glm::ivec3 d = l.divisions;
    if (d.x < 1 || d.y < 1 || d.z < 1 || l.rest.size() != l.size()) return false;
    const double scale = glm::length(l.axes[0]) + glm::length(l.axes[1]) + glm::length(l.axes[2]);
    const double tolerance = 1e-12 * scale;
    // Each grid point computed in place (rest_grid_point) and squared distances (no square roots): this
    // runs every frame a lattice moves (deformed_bounds), where building the grid first and a square root
    // per point took 7.7 µs (11³, hot cache, the 2-core machine).
    double worst = 0.0;
    std::size_t c = 0;
    for (int i = 0; i <= d.x; ++i)
        for (int j = 0; j <= d.y; ++j)
            for (int k = 0; k <= d.z; ++k, ++c) {
                const glm::dvec3 e = rest_grid_point(l.origin, l.axes, d, i, j, k) - l.rest[c];
                worst = std::max(worst, glm::dot(e, e));
            }
    return worst <= tolerance * tolerance;
}

Box deformed_bounds(const Lattice& l, const Box& in) {
    if (in.empty) return in;
    glm::dvec3 dlo(0.0), dhi(0.0);
    Box hull;
    if (!l.current.empty()) hull = Box{l.current[0], l.current[0], false};
    for (std::size_t c = 0; c < l.current.size(); ++c) {
        const glm::dvec3 d = l.current[c] - l.rest[c];
        dlo = glm::min(dlo, d);
        dhi = glm::max(dhi, d);
        hull.lo = glm::min(hull.lo, l.current[c]);
        hull.hi = glm::max(hull.hi, l.current[c]);
    }
    Box out{in.lo + dlo, in.hi + dhi, false};
    if (!hull.empty && l.basis == LatticeBasis::bernstein && rest_is_uniform(l)) {
        // Inside points land in the control points' convex hull; outside points stay in `in`.
        // Pad by the inside slack: a point up to kInsideSlack outside is deformed as if on the face.
        const glm::dvec3 pad(kInsideSlack *
                             (glm::length(l.axes[0]) + glm::length(l.axes[1]) + glm::length(l.axes[2])));
        const glm::dvec3 lo = glm::min(hull.lo - pad, in.lo), hi = glm::max(hull.hi + pad, in.hi);
        out.lo = glm::max(out.lo, lo);
        out.hi = glm::min(out.hi, hi);
    }
    return out;
}

}  // namespace sffd::ffd
