// The paper's benchmark case, shared by the FFD benches (bench_ffd_deform on the CPU, bench_ffd_gpu):
// splats on a unit Fibonacci sphere inside an 11x11x11 lattice (divisions 10) with a global twist (every
// control point rotated about the vertical axis by an angle proportional to its height, as
// ../shared/peers/blender_lattice.py does). Both benches measure the same deformation this way.
#pragma once

#include <cmath>
#include <cstddef>

#include <glm/glm.hpp>

#include "systems/ffd/lattice.h"
#include "systems/ffd/operations.h"

namespace sffd::bench {

// Point i of n on the unit sphere (golden-angle spiral, even density); also its outward normal.
inline glm::dvec3 fibonacci_sphere(std::size_t i, std::size_t n) {
    const double golden = M_PI * (3.0 - std::sqrt(5.0));
    const double y = 1.0 - 2.0 * (double(i) + 0.5) / double(n), r = std::sqrt(1.0 - y * y),
                 th = golden * double(i);
    return {r * std::cos(th), y, r * std::sin(th)};
}

// The twisted lattice around the unit sphere (box [-1.1, 1.1]³, divisions 10).
inline Lattice twisted_lattice(LatticeBasis basis) {
    Lattice l = ffd::make_lattice({-1.1, -1.1, -1.1},
                                  {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)},
                                  {10, 10, 10}, basis);
    ffd::twist_graded(l, ffd::all_control_points(l), glm::dvec3(0, 1, 0), 0.6, glm::dvec3(0.0));
    return l;
}

}  // namespace sffd::bench
