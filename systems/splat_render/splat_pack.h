// Packs an authored SplatCloud into the 64-byte GpuSplat layout of shaders/common/bindings.h (CPU side of
// the upload into GpuSplatStore.rest). Colour: per-splat RGBA8 when present, else the material's base
// colour (sRGB-encoded); uv in axis_u.w / axis_v.w; normal.w = 1.
#pragma once

#include <cstdint>
#include <vector>

#include "runtime/scene/components.h"
#include "shaders/common/bindings.h"

namespace sffd::render {

std::vector<gpu::GpuSplat> pack_splats(const SplatCloud& cloud);

// Bounding sphere (cloud space, relative to origin) of the splat centres: centre of the box, largest
// distance to it plus the largest splat radius.
struct BoundingSphere {
    glm::dvec3 center{0.0};
    double radius = 0.0;
    double max_splat_radius = 0.0;  // largest |axis_u|, |axis_v| (included in radius)
};
BoundingSphere bounding_sphere(const SplatCloud& cloud);

}  // namespace sffd::render
