// Small dense maths for 3D Gaussians, in double precision: covariance from scale + rotation,
// symmetric 3x3 eigen-decomposition (cyclic Jacobi: robust for repeated eigenvalues), the covariance's
// decomposition back into scale + rotation, and the polar decomposition J = R U.
// glm matrices are column-major: m[c][r].
#pragma once

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

namespace sffd::gaussian {

// Σ = R S Sᵀ Rᵀ, R = mat3_cast(q) (q need not be normalised: it is), S = diag(scale).
glm::dmat3 covariance(const glm::dvec3& scale, const glm::dquat& q);

// A = V diag(values) Vᵀ for a symmetric A (only its symmetric part is read). Values in descending order,
// V orthonormal with det V = +1 (a proper rotation). Exact for diagonal input; repeated eigenvalues give
// some orthonormal basis of their eigenspace.
struct SymEigen {
    glm::dvec3 values{0.0};
    glm::dmat3 vectors{1.0};  // columns are the eigenvectors
};
SymEigen sym_eigen(const glm::dmat3& a);
// The same, starting from an orthogonal guess of the eigenvectors (columns), e.g. the deformed axes
// of a Gaussian: fewer Jacobi sweeps. Any orthogonal guess gives the same decomposition.
SymEigen sym_eigen(const glm::dmat3& a, const glm::dmat3& guess);

// Scale (standard deviations, sqrt of the eigenvalues; negative rounding noise clamps to 0) and unit
// rotation with Σ = R S Sᵀ Rᵀ. The axis order is the eigenvalue order (largest first).
struct ScaleRotation {
    glm::dvec3 scale{1.0};
    glm::dquat rotation{1.0, 0.0, 0.0, 0.0};
};
ScaleRotation decompose_covariance(const glm::dmat3& sigma);
ScaleRotation decompose_covariance(const glm::dmat3& sigma, const glm::dmat3& guess);

// Gram–Schmidt orthonormalisation of the columns of m (a guess for sym_eigen); identity columns where
// m is degenerate.
glm::dmat3 orthonormalize(const glm::dmat3& m);

// J = R U with R orthogonal (det R = sign det J: a reflection when the map inverts) and U symmetric
// positive definite. `ok` is false when J is singular or nearly (|det J| <= 1e-12 ‖J‖³); then R = I.
struct Polar {
    glm::dmat3 rotation{1.0};
    glm::dmat3 stretch{1.0};
    bool ok = true;
};
Polar polar_decomposition(const glm::dmat3& j);

// Unit quaternion of a proper rotation matrix (sign chosen with w >= 0).
glm::dquat quat_from_rotation(const glm::dmat3& r);

}  // namespace sffd::gaussian
