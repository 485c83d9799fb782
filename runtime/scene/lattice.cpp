#include "runtime/scene/lattice.h"

#include <cmath>
#include <string>

namespace sffd {

std::vector<glm::dvec3> rest_grid(const glm::dvec3& origin, const std::array<glm::dvec3, 3>& axes,
                                  const glm::ivec3& d) {
    std::vector<glm::dvec3> grid;
    grid.reserve(std::size_t(d.x + 1) * (d.y + 1) * (d.z + 1));
    for (int i = 0; i <= d.x; ++i)
        for (int j = 0; j <= d.y; ++j)
            for (int k = 0; k <= d.z; ++k) grid.push_back(rest_grid_point(origin, axes, d, i, j, k));
    return grid;
}

static bool finite(const glm::dvec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

Status validate_lattice(const Lattice& l, const std::string& what) {
    for (int a = 0; a < 3; ++a)
        if (l.divisions[a] < 1 || l.divisions[a] > kMaxLatticeDivisions)
            return make_error(what + ": divisions must be between 1 and " +
                              std::to_string(kMaxLatticeDivisions) + " per axis (got " +
                              std::to_string(l.divisions[a]) + ")");
    if (!finite(l.origin)) return make_error(what + ": origin is not finite");
    for (int a = 0; a < 3; ++a)
        if (!finite(l.axes[a])) return make_error(what + ": axis " + "STU"[a] + " is not finite");
    const double scale = glm::length(l.axes[0]) * glm::length(l.axes[1]) * glm::length(l.axes[2]);
    const double det = glm::determinant(glm::dmat3(l.axes[0], l.axes[1], l.axes[2]));
    if (!(scale > 0.0) || !(std::abs(det) > 1e-9 * scale))
        return make_error(what + ": zero-volume box (axes S, T, U are degenerate or coplanar)");
    const std::size_t n = l.size();
    if (l.rest.size() != n)
        return make_error(what + ": expected " + std::to_string(n) + " rest control points, got " +
                          std::to_string(l.rest.size()));
    if (l.current.size() != n)
        return make_error(what + ": expected " + std::to_string(n) + " control points, got " +
                          std::to_string(l.current.size()));
    // Every frame validates every moving lattice: one pass with no early exit (it vectorises), then the
    // search for the culprit only when there is one.
    bool all_finite = true;
    for (std::size_t c = 0; c < n; ++c) {
        const glm::dvec3 a = l.current[c], b = l.rest[c];
        all_finite &= std::isfinite(a.x + a.y + a.z + b.x + b.y + b.z);
    }
    if (all_finite) return {};
    for (std::size_t c = 0; c < n; ++c) {
        if (!finite(l.current[c]))
            return make_error(what + ": control point " + std::to_string(c) + " is not finite");
        if (!finite(l.rest[c]))
            return make_error(what + ": rest control point " + std::to_string(c) + " is not finite");
    }
    return {};
}

Lattice make_lattice(const glm::dvec3& origin, const std::array<glm::dvec3, 3>& axes,
                     const glm::ivec3& divisions, LatticeBasis basis) {
    Lattice l;
    l.origin = origin;
    l.axes = axes;
    l.divisions = divisions;
    l.basis = basis;
    l.rest = rest_grid(origin, axes, divisions);
    l.current = l.rest;
    return l;
}

}  // namespace sffd
