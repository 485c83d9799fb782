// Cyclic Jacobi eigen-decomposition of a symmetric 3x3 matrix: the one solver behind the PCA normals of
// splat estimation (runtime/assets/splat_estimation.cpp) and the covariance decomposition of Gaussians
// (systems/gaussian/gaussian_math.cpp). It lives in the runtime so that both layers can reach it. The
// callers differ only in the stopping rule, the starting basis and the output order, which are parameters:
// each keeps its own rule so that its results stay bit-identical.
#pragma once

#include <glm/glm.hpp>

namespace sffd {

// When the sweeps stop: after max_sweeps, or once off ≤ relative·scale or off < floor, where off is the sum
// of the squared off-diagonal entries (upper triangle) and scale is either the sum of the squared diagonal
// entries (recomputed every sweep) or the squared Frobenius norm of the input (taken once). A rotation is
// skipped where |a_pq| < skip_below.
struct JacobiRule {
    int max_sweeps = 64;
    double relative = 1e-32;
    bool relative_to_diagonal = false;
    double floor = 1e-300;
    double skip_below = 1e-300;
};

enum class EigenOrder { ascending, descending };

struct Eigen3 {
    glm::dvec3 values{0.0};
    glm::dmat3 vectors{1.0};  // columns are the eigenvectors, in the order of values
};

// Decomposes a (read as given: pass a symmetric matrix) starting from the orthonormal basis v0 (columns;
// identity when there is no guess): each rotation zeroes one off-diagonal entry and is accumulated into v0.
// Converges quadratically and never needs distinct eigenvalues (no characteristic polynomial, no deflation);
// a good guess leaves little to rotate. The eigenvector signs are whatever the rotations give.
Eigen3 jacobi_eigen(const glm::dmat3& a, const glm::dmat3& v0, const JacobiRule& rule, EigenOrder order);

}  // namespace sffd
