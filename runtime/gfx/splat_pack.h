// Packs an authored SplatCloud into the 64-byte GpuSplat layout of shaders/common/bindings.h (CPU side of
// the uploads into GpuSplatStore, splat_store.h). Colour: per-splat RGBA8 when present, else the
// material's base colour (sRGB-encoded); uv in axis_u.w / axis_v.w; normal.w = 1.
#pragma once

#include <cstdint>
#include <vector>

#include "runtime/scene/components.h"
#include "shaders/common/bindings.h"

namespace sffd::gfx {

std::vector<gpu::GpuSplat> pack_splats(const SplatCloud& cloud);

// Linear [0, 1] -> 8-bit sRGB (the image writers use the same encoding).
std::uint8_t encode_srgb8(float linear);

}  // namespace sffd::gfx
