// Axis conventions of Gaussian files, and the one exact conversion between them.
//
// The internal convention (GaussianCloud, every system and command) is the 3DGS PLY one, kept as the
// trainers write it: the frame of the COLMAP reconstruction, conventionally x right, y down, z forward
// ("RDF", OpenCV camera axes). PLY, compressed PLY and .splat are read and written as stored (the
// reference trainer, SuperSplat and splat-transform all treat them so: its `Transform.PLY` space).
// SPZ is specified as x right, y up, z back ("RUB", OpenGL camera axes; the Niantic README): the SPZ
// reader turns it 180 degrees about x into the internal frame. A file that was stored in RUB anyway
// (a y-up PLY; or an SPZ written by splat-transform 3.7.0, which writes SPZ in its PLY space without
// the conversion, by its own source comment) is turned by the user: `splatffd convert IN OUT
// --turn-x180`. KHR_gaussian_splatting glTF (y up, +z the front, x left) is the internal frame turned
// 180 degrees about z: read_gltf and write_glb turn it (gaussian_gltf.h); SOG is read as stored. How a
// capture in this frame is shown upright in the engine's y-up world is capture_up.h's.
//
// A turn of 180 degrees about a coordinate axis is a proper rotation R = diag(±1, ±1, ±1) with det +1,
// so it maps every part of a Gaussian exactly: centres p -> R p, rotations q -> q_R q (covariance
// R Σ Rᵀ), and each SH coefficient only changes sign (every 3DGS basis function is even or odd in each
// coordinate), no resampling and no rounding.
#pragma once

#include <array>

#include <glm/gtc/quaternion.hpp>
#include <glm/vec3.hpp>

#include "runtime/scene/components.h"

namespace sffd::gaussian {

enum class AxisTurn {
    x180,  // (x, y, z) -> (x, -y, -z): RDF <-> RUB (3DGS PLY <-> SPZ, OpenCV <-> OpenGL camera axes)
    z180,  // (x, y, z) -> (-x, -y, z): 3DGS PLY <-> glTF (splat-transform's PLY <-> engine/GLB space)
};

// Applies the turn to centres (and origin), rotations and SH coefficients in place. Its own inverse.
void turn_axes(GaussianCloud& cloud, AxisTurn turn);

// The turn as turn_axes applies it, for a writer that turns each row as it streams it (no turned copy of
// the cloud): p -> scale * p, q -> rotation * q, SH coefficient k (of 16, degree <= 3) times sh_sign[k].
struct AxisTurnParts {
    glm::vec3 scale{1.0f};
    glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};
    std::array<float, 16> sh_sign = {1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1};  // default: no turn
};
AxisTurnParts axis_turn_parts(AxisTurn turn);

}  // namespace sffd::gaussian
