#version 450 core
// Tile path, step 3: each tile's range [begin, end) in the entries sorted by tile id (ranges cleared to
// 0 by the CPU first, so tiles without entries stay empty). Entries past the last tile (tile_emit.comp's
// unfilled slots, sorted last) belong to no range.
#include "gaussian/gaussian_layout.h"

layout(local_size_x = 64) in;
#include "common/dispatch.glsl"

layout(std430, binding = SFFD_GAUSS_SSBO_TILE_KEYS) readonly buffer TileKeys { uint tile_keys[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_RANGES) writeonly buffer Ranges { uvec2 ranges[]; };

uniform uint u_entries;
uniform uint u_tile_count;  // tile ids from here on are tile_emit.comp's unfilled slots: no tile's

void main() {
    const uint k = sffd_dispatch_index();
    if (k >= u_entries) return;
    const uint t = tile_keys[k];
    if (t >= u_tile_count) return;
    if (k == 0u || tile_keys[k - 1u] != t) ranges[t].x = k;
    if (k + 1u == u_entries || tile_keys[k + 1u] != t) ranges[t].y = k + 1u;
}
