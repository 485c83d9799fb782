// CPU deformation of 3D Gaussians through an FFD lattice:
//   centre  μ' = FFD(μ)                      (the ffd system's own evaluator, systems/ffd/deform.h)
//   shape   Σ' = J Σ Jᵀ, J the world Jacobian at μ (first-order push-forward of the density), stored
//           back as scale + rotation (symmetric eigen-decomposition)
//   colour  SH rotated by R, the rotation of the polar decomposition J = R U (a reflection when the
//           cell inverts: the SH are transformed by the orthogonal R either way)
// Gaussians outside the lattice (J = I) are copied unchanged; opacities are never changed, except that a
// Gaussian whose result is not finite is made transparent (DeformStats::not_finite), as on the GPU.
#pragma once

#include <cstddef>
#include <cstdint>

#include "runtime/core/result.h"
#include "systems/ffd/components.h"
#include "systems/ffd/deform.h"
#include "systems/gaussian/components.h"

namespace sffd::gaussian {

struct DeformStats {
    std::size_t inside = 0;      // Gaussians inside the lattice
    std::size_t inverted = 0;    // det J < 0
    std::size_t degenerate = 0;  // J (near) singular: the covariance collapses, SH left unrotated
    std::size_t not_finite = 0;  // results that were not finite: written as the GPU pass writes them
                                 // (input centre, scale 0, identity rotation, SH 0, opacity 0 when
                                 // `out` carries opacities), never left as NaN or inf
};

// How view-dependent colour follows the deformation (the issue asks for both, measured):
//   rotate_coefficients: the SH coefficients are rotated by R (per-band matrices, once per deformation);
//   rotate_view: the coefficients are kept and R is stored in GaussianCloud::sh_frames; renderers evaluate
//                the SH at Rᵀ d (one 3x3 product per splat per frame, no coefficient work when deforming).
enum class ShMode : std::uint8_t { rotate_coefficients, rotate_view };

struct DeformOptions {
    ffd::Backend backend = ffd::Backend::automatic;  // the lattice evaluator
    bool copy_opacities = true;
    ShMode sh = ShMode::rotate_coefficients;
    // Shape and colour from J: the vectorised float kernel (gaussian_deform_fast.h, the GPU pass's
    // arithmetic) unless this is set: then the double-precision per-Gaussian maths, the exact reference
    // (tests, benchmarks).
    bool reference_shapes = false;
    // Optional per-Gaussian weight in [0, 1], one per Gaussian of `in` (PointWeights,
    // runtime/scene/point_columns.h): the centre moves by w times its displacement and the shape and SH
    // follow J_w = I + w (J - I) (Σ' = J_w Σ J_wᵀ, SH by the polar rotation of J_w). Null: weight 1.
    const float* weights = nullptr;
};

// Writes `out` (positions, scales, rotations, sh or sh_frames; opacities copied when `copy_opacities`)
// from `in`. `out` may be `in` (chained lattices deform in place; frames compose). Lattice errors read
// "lattice: problem".
Result<DeformStats> deform(const Lattice& lattice, const GaussianCloud& in, GaussianCloud& out,
                           const DeformOptions& options);
Result<DeformStats> deform(const Lattice& lattice, const GaussianCloud& in, GaussianCloud& out,
                           ffd::Backend backend = ffd::Backend::automatic, bool copy_opacities = true);

// Gaussians [first, first + count) only, written exactly as deform() writes them (first on a page boundary,
// runtime/scene/point_pages.h): `out` already holds a whole output of `in`'s size (a previous deform() of
// the same cloud, or `in` itself); the rest of it is left alone. The deformation system redoes the pages a
// control-point edit reaches with it.
Result<DeformStats> deform_range(const Lattice& lattice, const GaussianCloud& in, GaussianCloud& out,
                                 const DeformOptions& options, std::size_t first, std::size_t count);

// Rotates each splat's coefficients by its sh_frames entry and clears the frames (before writing a file).
void bake_sh_frames(GaussianCloud& cloud);

}  // namespace sffd::gaussian
