#include "runtime/scene/lattice.h"

namespace sffd {

std::vector<glm::dvec3> rest_grid(const glm::dvec3& origin, const std::array<glm::dvec3, 3>& axes,
                                  const glm::ivec3& d) {
    std::vector<glm::dvec3> grid;
    grid.reserve(std::size_t(d.x + 1) * (d.y + 1) * (d.z + 1));
    for (int i = 0; i <= d.x; ++i)
        for (int j = 0; j <= d.y; ++j)
            for (int k = 0; k <= d.z; ++k)
                grid.push_back(origin + (double(i) / d.x) * axes[0] + (double(j) / d.y) * axes[1] +
                               (double(k) / d.z) * axes[2]);
    return grid;
}

Lattice make_lattice(const glm::dvec3& origin, const std::array<glm::dvec3, 3>& axes, const glm::ivec3& divisions,
                     LatticeBasis basis) {
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
