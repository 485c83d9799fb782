// The vectorised shape-and-colour kernel of gaussian::deform (gaussian_deform_fast.cpp): W Gaussians in the
// W float lanes of one vector, the same arithmetic as the GPU pass (shaders/gaussian/deform.comp): one-sided
// Jacobi on A = J R S for Σ' = A Aᵀ, scaled Newton for the polar rotation, SH rotated per band through the
// sample-direction tables. Internal to the gaussian system; gaussian_deform.cpp calls it per range.
#pragma once

#include <cstddef>

#include <glm/glm.hpp>

#include "systems/gaussian/components.h"

namespace sffd::gaussian::detail {

struct FastShapeArgs {
    const GaussianCloud* in = nullptr;
    GaussianCloud* out = nullptr;          // may be `in`
    const glm::mat3* jacobians = nullptr;  // jacobians[b] is Gaussian first + b's
    std::size_t first = 0;
    bool view_mode = false;  // store the polar rotation in out->sh_frames instead of rotating coefficients
    bool frames_in = false;  // in->sh_frames holds a frame per Gaussian (composed onto)
};

// Writes scales, rotations and sh (or sh_frames) of Gaussians first + [begin, end) (begin a multiple of the
// lane width, or the whole range). Gaussians with J = I are copied. Returns how many had a near-singular J.
std::size_t deform_shapes_fast(const FastShapeArgs& a, std::size_t begin, std::size_t end);

// Lanes per vector of the kernel (16 with AVX-512, 8 with AVX, else 4): ranges are split on multiples of it.
int shape_lane_width();

}  // namespace sffd::gaussian::detail
