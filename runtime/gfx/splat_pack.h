// Packs an authored SplatCloud into the 64-byte GpuSplat layout of shaders/common/bindings.h (CPU side of
// the uploads into GpuSplatStore, splat_store.h). Colour: per-splat RGBA8 when present, else white, which
// the render passes multiply by the material's base colour (a uniform: a material edit re-uploads nothing);
// uv in axis_u.w / axis_v.w; normal.w = 1.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "runtime/scene/components.h"
#include "shaders/common/bindings.h"

namespace sffd::gfx {

std::vector<gpu::GpuSplat> pack_splats(const SplatCloud& cloud);

// The per-splat columns pack_splats reads, each either empty (its default) or positions.size() long: a
// deformation's output packs straight from its arrays and the authored colours, without a SplatCloud copy.
struct SplatColumns {
    std::span<const glm::vec3> positions, normals, axis_u, axis_v;
    std::span<const std::uint32_t> colors;
    std::span<const glm::vec2> uvs;
};
// Into `out` (resized; its memory is reused: every frame of an interactive CPU deformation packs the whole
// cloud again), across the cores.
void pack_splats(const SplatColumns& columns, std::vector<gpu::GpuSplat>& out);
// Into `out` (columns.positions.size() elements: a mapped GL buffer, say), across the cores.
void pack_splats(const SplatColumns& columns, std::span<gpu::GpuSplat> out);

// Linear [0, 1] -> 8-bit sRGB (the image writers use the same encoding).
std::uint8_t encode_srgb8(float linear);

// The packed colour of a splat without colours (white: the base colour is applied when drawing).
inline constexpr std::uint32_t uncoloured_splat = 0xffffffffu;

}  // namespace sffd::gfx
