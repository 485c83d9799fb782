#version 450 core
// Tile path, step 2: the p-th Gaussian in depth order writes one (tile id, Gaussian index) entry per
// tile it touches, from its scanned offset. Entries are laid out in depth order, so the stable radix sort
// by tile id that follows leaves every tile's entries front to back (the (tile, depth) order of 3DGS's
// 64-bit keys, from two 32-bit sorts).
#include "gaussian/gaussian_layout.h"

layout(local_size_x = 64) in;
#include "common/dispatch.glsl"

layout(std430, binding = SFFD_GAUSS_SSBO_PROJ_CENTER) readonly buffer ProjCenter { vec4 proj_center[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_TILE_CONIC) readonly buffer ProjConic { vec4 proj_conic[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_ORDER) readonly buffer Order { uint order[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_DRAW) readonly buffer Draw { uint vertex_count, instance_count, first, base_instance; };
layout(std430, binding = SFFD_GAUSS_SSBO_TOUCHED) readonly buffer Offsets { uint offsets[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_TILE_KEYS) writeonly buffer TileKeys { uint tile_keys[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_TILE_VALUES) writeonly buffer TileValues { uint tile_values[]; };

uniform uint u_count;
uniform uint u_capacity;  // entries the entry buffers hold: never written past (a wrapped 32-bit total)
uniform vec2 u_size;
uniform uvec2 u_tiles;

#include "gaussian/tile_common.glsl"

void main() {
    const uint p = sffd_dispatch_index();
    if (p >= u_count || p >= instance_count) return;
    const uint i = order[p];
    const ivec4 box = pixel_box(proj_center[i], proj_conic[i]);
    if (box.x > box.z || box.y > box.w) return;
    const uvec4 t = tile_rect(box);
    uint o = offsets[p];
    for (uint ty = t.y; ty <= t.w; ++ty)
        for (uint tx = t.x; tx <= t.z; ++tx, ++o) {
            if (o >= u_capacity) return;
            tile_keys[o] = ty * u_tiles.x + tx;
            tile_values[o] = i;
        }
}
