// Parents of a Gaussian hierarchy: several Gaussians merged into one, as hierarchical 3DGS builds its
// interior nodes (Kerbl et al. 2024, "A Hierarchical 3D Gaussian Representation for Real-Time Rendering
// of Very Large Datasets", sec. 4.1), in double precision:
//   weight  w_i = o_i · S_i, S_i = s_a·s_b the product of the two largest scales (the footprint the
//           Gaussian shows from its broad side, up to π)
//   mean    μ = Σ w_i μ_i / Σ w_i
//   cov     Σ = Σ w_i (Σ_i + d_i d_iᵀ) / Σ w_i,  d_i = μ_i − μ,  Σ_i = R_i diag(s_i²) R_iᵀ
//           (the moment-matched Gaussian of the weighted mixture), written back as scales and a rotation
//           by its eigen decomposition (Jacobi; scales ascending along x y z, a right-handed frame)
//   SH      every coefficient Σ w_i c_i / Σ w_i (DC and higher bands alike)
//   opacity o = min(1, Σ o_i S_i / S), S of the merged scales: the children's covered area spread over
//           the parent's footprint. A weighted mean of the opacities instead would make a parent of
//           sparse, opaque children fully opaque over the gaps between them; this keeps the coverage a
//           view at the parent's distance sees (children that overlap saturate at 1).
// When every weight is 0 (transparent or flat children) the weights are 1 instead; when the merged
// footprint S is 0 (coincident points) the opacity is the largest child's.
#pragma once

#include <cstdint>
#include <span>

#include "runtime/scene/components.h"

namespace sffd::lod {

// The hierarchy weight of one Gaussian (linear scales, opacity in [0, 1]).
double merge_weight(const glm::vec3& scale, float opacity);

// Appends to `out` the merge of Gaussians `members` of `in` (not empty; out.sh_degree == in.sh_degree).
// The merged centre is stored relative to out.origin.
void merge_gaussians(const GaussianCloud& in, std::span<const std::uint32_t> members, GaussianCloud& out);

// The symmetric eigen decomposition the merge uses: `cov` (row-major 3×3, symmetric) = V diag(values) Vᵀ
// with values ascending and V's columns a right-handed orthonormal frame (cyclic Jacobi, double).
void symmetric_eigen(const double cov[9], double values[3], double vectors[9]);

}  // namespace sffd::lod
