// How many multiply-adds the compute-bound CPU kernels do, so their benchmarks can state speed as a
// fraction of the host's FMA floor (bench_util.h, fma_floor). A model of the loops as written, counting
// every multiply, add or fused multiply-add of float lanes as one:
// - dense Bernstein FFD (systems/ffd/deform_fast.cpp), per point: the bases (degree L and M with their
//   derivatives, degree N and the one below it), the factorised sums over the rows that move, for the
//   coordinates that move, and the finish (J = I + G M⁻¹, cofactor normals, two axes);
// - a Gaussian adds J Σ Jᵀ from its scale and rotation and the SH rotation's matrix products. The shape's
//   Jacobi sweeps, the colour's Newton steps and the building of the SH rotation matrices are not counted,
//   so the Gaussian fraction is a lower bound.
#pragma once

#include <cstddef>

#include "systems/ffd/deform_kernels.h"

namespace sffd::bench {

// Per point, the dense Bernstein kernel with derivatives (normals and both axes when `surface`, the
// Jacobian only otherwise).
inline double bernstein_multiply_adds(const Lattice& l, bool surface) {
    const ffd::detail::Prepared p = ffd::detail::prepare(l, glm::dvec3(0.0));
    const double L = p.L, M = p.M, K = p.N + 1, nc = p.coords;
    double rows = 0;
    for (std::uint8_t r : p.row_nonzero) rows += r != 0;
    const double bases = (L * L + 2 * L + 1) + (M * M + 2 * M + 1) + (K - 1) * K;
    const double sums = rows * ((K - 1) * nc * 2 + nc + 3 * nc) + (L + 1) * 4 * nc;
    const double jacobian = 27 + 6 + 3;                  // J, one cross product, the determinant
    const double finish = surface ? 12 + 9 + 6 + 18 + 3  // two cross products, n' and its length, axes, X'
                                  : 3;                   // X'
    return bases + sums + jacobian + finish;
}

// Per Gaussian of SH degree `degree` on top of the FFD's Jacobian: Σ = R S² Rᵀ (the quaternion's matrix and
// six entries), J Σ Jᵀ (two 3x3 products, six entries kept), and the bands' rotations of three channels.
inline double gaussian_extra_multiply_adds(int degree) {
    double sh = 0;
    for (int band = 1; band <= degree; ++band) sh += double((2 * band + 1) * (2 * band + 1));
    return 18 + 18 + 27 + 18 + 3 * sh;
}

}  // namespace sffd::bench
