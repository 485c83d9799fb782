// Synthetic splat clouds for sweeps (any point count): a unit sphere sampled on a Fibonacci spiral, with
// outward normals, tangent axes scaled to a radius that closes the surface, and a colour gradient.
#pragma once

#include <cstddef>

#include "runtime/scene/components.h"

namespace sffd::profiling {

SplatCloud synthetic_sphere(std::size_t count, double radius = 1.0);

}  // namespace sffd::profiling
