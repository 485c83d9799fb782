#version 450 core
// Tile path, step 2: the p-th Gaussian in depth order writes one (tile id, depth-order position) entry per
// tile it touches, from its scanned offset. Entries are laid out in depth order, so the stable radix sort
// by tile id that follows leaves every tile's entries front to back (the (tile, depth) order of 3DGS's
// 64-bit keys, from two 32-bit sorts).
// It writes exactly the slots tile_count.comp gave it, offsets[p] .. offsets[p + 1]: the two programs
// compute the box from the same source, but GLSL does not promise two programs the same float results
// (no `precise`: a driver may contract one and not the other). A larger box would write into the next
// Gaussian's slots; a smaller one leaves slots unwritten (undefined contents after the buffers grow, a
// tile id past the ranges). Slots its box does not fill get the tile id u_tiles.x * u_tiles.y, past every
// tile: sorted last and skipped by the ranges pass.
// Run per range of the depth order like tile_count.comp (the offsets bound from position u_base, one past
// the range's end included); the entries are written at random, so their arrays are bound whole, and each
// entry's value is the Gaussian's depth-order position u_base + p (the tile blend reads the depth-ordered
// projection range by range).
#include "gaussian/gaussian_layout.h"

layout(local_size_x = 64) in;
#include "common/dispatch.glsl"

layout(std430, binding = SFFD_GAUSS_SSBO_PROJ_CENTER) readonly buffer ProjCenter { vec4 proj_center[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_TILE_CONIC) readonly buffer ProjConic { vec4 proj_conic[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_DRAW) readonly buffer Draw { uint vertex_count, instance_count, first, base_instance; };
layout(std430, binding = SFFD_GAUSS_SSBO_TOUCHED) readonly buffer Offsets { uint offsets[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_TILE_KEYS) writeonly buffer TileKeys { uint tile_keys[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_TILE_VALUES) writeonly buffer TileValues { uint tile_values[]; };

uniform uint u_count;
uniform uint u_base;      // depth-order position of the range's first Gaussian
uniform uint u_capacity;  // entries the entry buffers hold: never written past (a wrapped 32-bit total)
uniform vec2 u_size;
uniform uvec2 u_tiles;

#include "splat_render/gaussian/tile_common.glsl"

void main() {
    const uint p = sffd_dispatch_index();
    if (p >= u_count || u_base + p >= instance_count) return;
    const uint i = u_base + p;
    uint o = offsets[p];
    const uint end = min(offsets[p + 1u], u_capacity);
    if (o >= end) return;
    const ivec4 box = pixel_box(proj_center[p], proj_conic[p]);
    if (box.x <= box.z && box.y <= box.w) {
        const uvec4 t = tile_rect(box);
        for (uint ty = t.y; ty <= t.w && o < end; ++ty)
            for (uint tx = t.x; tx <= t.z && o < end; ++tx, ++o) {
                tile_keys[o] = ty * u_tiles.x + tx;
                tile_values[o] = i;
            }
    }
    for (; o < end; ++o) {
        tile_keys[o] = u_tiles.x * u_tiles.y;
        tile_values[o] = i;
    }
}
