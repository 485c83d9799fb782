#version 450
// Compute rasteriser, pass 1 (visibility; Schuetz, Kerbl and Wimmer 2021's compute version of Botsch et
// al. 2005 with 32-bit atomics): one invocation per sprite record of the cull pass. A sprite whose side is
// at most SFFD_RASTER_MAX_SPRITE pixels is ray-cast at every pixel centre of its square like
// visibility.frag, and its eps-pushed window depth goes into the per-pixel depth words with atomicMin; a
// larger one is appended to the list the raster path draws (hybrid: large splats stay on the fixed-function
// rasteriser, whose cost follows their pixels). u_list selects the record list: x = its first record
// (0: the sprites; capacity: the CPU cull's flat-coloured sprites of a textured cloud), y = the word of the
// cull's draw commands holding its length, z = the list (0, 1: which DrawElementsIndirectCommand of
// RASTER_BIG_COMMANDS it appends to; its indices start at x).
#include "splat_render/compute_raster.glsl"

layout(local_size_x = SFFD_RASTER_GROUP_SIZE) in;
#include "common/dispatch.glsl"

layout(std430, binding = SFFD_SSBO_VISIBLE_SPLATS) readonly buffer Records { SplatRecord records[]; };
layout(std430, binding = SFFD_SSBO_DRAW_INDIRECT) readonly buffer Commands { uint commands[]; };
layout(std430, binding = SFFD_SSBO_RASTER_BIG) writeonly buffer Big { uint big[]; };
layout(std430, binding = SFFD_SSBO_RASTER_BIG_COMMANDS) buffer BigCommands { uint big_commands[]; };
layout(location = 0) uniform uvec4 u_list;

void main() {
    uint i = sffd_dispatch_index();
    if (i >= commands[u_list.y]) return;
    uint r = u_list.x + i;
    SplatRecord rec = records[r];
    if (rec.center.w > SFFD_RASTER_MAX_SPRITE) {
        big[u_list.x + atomicAdd(big_commands[5u * u_list.z], 1u)] = r;
        return;
    }
    ivec4 box = raster_sprite_pixels(rec.center);
    float eps = rec.plane.w;
    for (int y = box.y; y <= box.w; ++y)
        for (int x = box.x; x <= box.z; ++x) {
            vec3 ray;
            float inv_t, t;
            vec2 st;
            if (!raster_raycast(rec, ivec2(x, y), ray, inv_t, t, st)) continue;
            // visibility.frag: pushed back by eps along the ray (the view-axis depth grows by eps / |ray|).
            float depth = raster_window_depth_inv(1.0 / (t + eps * inversesqrt(dot(ray, ray))));
            if (depth < 1.0) atomicMin(raster_depth[raster_pixel(ivec2(x, y))], floatBitsToUint(max(depth, 0.0)));
        }
}
