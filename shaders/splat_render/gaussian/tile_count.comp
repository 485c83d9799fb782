#version 450 core
// Tile path, step 1: for the p-th Gaussian in depth order (p < the drawn count of the indirect draw),
// the number of 16x16 tiles its pixel box touches; 0 past the drawn count. Scanned next to give each
// Gaussian its first (tile, Gaussian) entry. Run per range of the depth order: the depth-ordered
// projection and the counts are bound from position u_base.
#include "gaussian/gaussian_layout.h"

layout(local_size_x = 64) in;
#include "common/dispatch.glsl"

layout(std430, binding = SFFD_GAUSS_SSBO_PROJ_CENTER) readonly buffer ProjCenter { vec4 proj_center[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_TILE_CONIC) readonly buffer ProjConic { vec4 proj_conic[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_DRAW) readonly buffer Draw { uint vertex_count, instance_count, first, base_instance; };
layout(std430, binding = SFFD_GAUSS_SSBO_TOUCHED) writeonly buffer Touched { uint touched[]; };

uniform uint u_count;
uniform uint u_base;  // depth-order position of the range's first Gaussian
uniform vec2 u_size;
uniform uvec2 u_tiles;

#include "splat_render/gaussian/tile_common.glsl"

void main() {
    const uint p = sffd_dispatch_index();
    if (p >= u_count) return;
    uint n = 0u;
    if (u_base + p < instance_count) {
        const ivec4 box = pixel_box(proj_center[p], proj_conic[p]);
        if (box.x <= box.z && box.y <= box.w) {
            const uvec4 t = tile_rect(box);
            n = (t.z - t.x + 1u) * (t.w - t.y + 1u);
        }
    }
    touched[p] = n;
}
