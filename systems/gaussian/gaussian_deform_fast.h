// The vectorised shape-and-colour kernel of gaussian::deform (gaussian_deform_fast.cpp): W Gaussians in the
// W float lanes of one vector, the same arithmetic as the GPU pass (shaders/gaussian/deform.comp): one-sided
// Jacobi on A = J R S for Σ' = A Aᵀ, scaled Newton for the polar rotation, SH rotated per band through the
// sample-direction tables. Internal to the gaussian system; gaussian_deform.cpp calls it per range.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>

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
    // not_finite[b] = 1 where Gaussian first + b is to be dropped: its J, or what is written for it and a
    // renderer reads (position, and scale, rotation and SH by finite_shape(); the frame in view mode), is
    // not finite; else 0. The kernel checks what it writes while it still holds it: the rows of a large
    // cloud are streamed past the caches, and reading them back would be a second trip to memory.
    std::uint8_t* not_finite = nullptr;
};

inline bool finite3(const glm::vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// Whether a Gaussian's shape and colour are fit for a renderer: scale, rotation and the `count` SH
// coefficients finite, the quaternion unit (a zero or overflowed one is not). The coefficients are tested
// on their exponent bits without an early exit, so the loop is vector code and no fast-math rewrite of
// isfinite can remove it.
inline bool finite_shape(const glm::vec3& s, const glm::quat& q, const float* sh, std::size_t count) {
    if (!std::isfinite(s.x) || !std::isfinite(s.y) || !std::isfinite(s.z) ||
        !std::isfinite(q.w + q.x + q.y + q.z))
        return false;
    if (!(std::abs(glm::dot(q, q) - 1.0f) < 1e-3f)) return false;
    std::uint32_t all = 0;
    for (std::size_t k = 0; k < count; ++k) {
        std::uint32_t bits;
        std::memcpy(&bits, sh + k, sizeof bits);
        all |= std::uint32_t((bits & 0x7f800000u) == 0x7f800000u);
    }
    return all == 0;
}

// Writes scales, rotations and sh (or sh_frames) of Gaussians first + [begin, end) (begin a multiple of the
// lane width, or the whole range). Gaussians with J = I are copied. Returns how many had a near-singular J.
// Rows written with streaming stores are fenced before it returns.
std::size_t deform_shapes_fast(const FastShapeArgs& a, std::size_t begin, std::size_t end);

// Lanes per vector of the SIMD target the kernel dispatches to (runtime/simd/simd.h: 16 avx3, 8 avx2, 4 sse4
// and neon, 1 scalar): ranges are split on multiples of it.
int shape_lane_width();

}  // namespace sffd::gaussian::detail
