// Cloud-space bounds of an authored SplatCloud. pack_splats() (the GpuSplat packing) lives with the
// uploads in runtime/gfx/splat_pack.h and is visible here under its old name.
#pragma once

#include <cstdint>
#include <vector>

#include "runtime/scene/components.h"
#include "runtime/scene/point_columns.h"
#include "runtime/gfx/splat_pack.h"
#include "shaders/common/bindings.h"

namespace sffd::render {

using gfx::pack_splats;

// Bounding sphere (cloud space, relative to origin) of the splat centres: centre of the box, largest
// distance to it plus the largest splat radius.
struct BoundingSphere {
    glm::dvec3 center{0.0};
    double radius = 0.0;
    double max_splat_radius = 0.0;  // largest |axis_u|, |axis_v| (included in radius)
};
// With `flags`, of the points that are neither hidden nor deleted only (none left: radius 0).
BoundingSphere bounding_sphere(const SplatCloud& cloud, const PointFlags* flags = nullptr);

}  // namespace sffd::render
