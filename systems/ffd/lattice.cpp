#include "systems/ffd/lattice.h"

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
    const auto grid = rest_grid(l.origin, l.axes, l.divisions);
    if (grid.size() != l.rest.size()) return false;
    const double scale = glm::length(l.axes[0]) + glm::length(l.axes[1]) + glm::length(l.axes[2]);
    for (std::size_t c = 0; c < grid.size(); ++c)
        if (glm::length(grid[c] - l.rest[c]) > 1e-12 * scale) return false;
    return true;
}

Box deformed_bounds(const Lattice& l, const Box& in) {
    if (in.empty) return in;
    glm::dvec3 dlo(0.0), dhi(0.0);
    Box hull;
    for (std::size_t c = 0; c < l.current.size(); ++c) {
        const glm::dvec3 d = l.current[c] - l.rest[c];
        dlo = glm::min(dlo, d);
        dhi = glm::max(dhi, d);
        hull.add(l.current[c]);
    }
    Box out{in.lo + dlo, in.hi + dhi, false};
    if (l.basis == LatticeBasis::bernstein && rest_is_uniform(l)) {
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
