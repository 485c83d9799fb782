// Spherical harmonics in the 3DGS basis (graphdeco-inria/gaussian-splatting, utils/sh_utils.py, and its
// CUDA rasterizer's computeColorFromSH), degrees 0..3.
//
// Basis, for a unit direction d = (x, y, z) from the camera to the splat, coefficient index k:
//   k 0: C0
//   k 1..3 (band 1, order y, z, x, with signs): −C1 y, +C1 z, −C1 x
//   k 4..8: C2[0] xy, C2[1] yz, C2[2] (2z² − x² − y²), C2[3] xz, C2[4] (x² − y²)
//   k 9..15: C3[0] y(3x² − y²), C3[1] xyz, C3[2] y(4z² − x² − y²), C3[3] z(2z² − 3x² − 3y²),
//            C3[4] x(4z² − x² − y²), C3[5] z(x² − y²), C3[6] x(x² − 3y²)
// These are the real orthonormal SH with the Condon–Shortley phase (so band 1 is −y, z, −x, not x, y, z:
// the trap in andrewwillmott/sh-lib #1 and nerfstudio #3010). Colour = max(0, 0.5 + Σ_k c_k Y_k(d)).
//
// Rotation: for an orthogonal R (a reflection is allowed), sh_rotation(R) gives per-band matrices D_l with
// Σ_k (D c)_k Y_k(d) = Σ_k c_k Y_k(Rᵀ d) for every d: the coefficients of the function rotated by R.
// Built by evaluating the basis at 2l+1 fixed directions, rotated, and solving against the precomputed
// inverse of the unrotated evaluation matrix (exact: each band is closed under rotation).
#pragma once

#include <glm/glm.hpp>

namespace sffd::gaussian {

inline constexpr double kShC0 = 0.28209479177387814;
inline constexpr double kShC1 = 0.4886025119029199;
inline constexpr double kShC2[5] = {1.0925484305920792, -1.0925484305920792, 0.31539156525252005,
                                    -1.0925484305920792, 0.5462742152960396};
inline constexpr double kShC3[7] = {-0.5900435899266435, 2.890611442640554,   -0.4570457994644658,
                                    0.3731763325901154,  -0.4570457994644658, 1.445305721320277,
                                    -0.5900435899266435};

// out[k] = Y_k(d) for k < (degree+1)²; d should be unit length.
void sh_basis(int degree, const glm::dvec3& d, double* out);
void sh_basis(int degree, const glm::vec3& d, float* out);

// Colour of one splat along d: coeffs = (degree+1)² RGB triples (GaussianCloud::sh layout for one splat).
glm::vec3 sh_color(int degree, const float* coeffs, const glm::vec3& d);

struct ShRotation {
    int degree = 0;
    float band1[3][3] = {};  // D_1[row][col]
    float band2[5][5] = {};
    float band3[7][7] = {};
};
ShRotation sh_rotation(const glm::dmat3& r, int degree);

// Rotates one splat's coefficients (K RGB triples): out may equal in. The DC term is unchanged.
void sh_rotate(const ShRotation& rot, const float* in, float* out);

// The tables behind sh_rotation(), for the GPU deformation (shaders/gaussian/deform.comp rotates the
// coefficients the same way): band l's 2l+1 sample directions (dirs[j]) and A_l⁻¹ row-major (inverse[r*n+k]).
void sh_sample_tables(int band, glm::dvec3* dirs, double* inverse);

// Condition number (2-norm estimate, for the test) of the fixed evaluation matrix of band l (1..3).
double sh_sample_condition(int band);

}  // namespace sffd::gaussian
