#version 450
// Compute rasteriser, pass 1 (visibility; Schuetz, Kerbl and Wimmer 2021's compute version of Botsch et
// al. 2005 with 32-bit atomics): one invocation per sprite record of the cull pass. A sprite whose side is
// at most SFFD_RASTER_MAX_SPRITE pixels is ray-cast at every pixel centre of its square like
// visibility.frag, and its eps-pushed window depth goes into the per-pixel depth words with atomicMin; a
// larger one is appended to the list the raster path draws (hybrid: large splats stay on the fixed-function
// rasteriser, whose cost follows their pixels). u_list selects the record list: x = its first record
// (0: the sprites; capacity: the CPU cull's flat-coloured sprites of a textured cloud), y = the word of the
// cull's draw commands holding its length, z = the list (0, 1: which DrawElementsIndirectCommand of
// RASTER_BIG_COMMANDS it appends to; its indices start at x), w = the invocations dispatched.
//
// The large sprites' list keeps record order, as the cull's lists do (cull.comp: the rasteriser blends
// them in list order, so an order that changes from run to run changes the float sums): this pass counts
// them per work group into `groups`, gfx::exclusive_scan() gives each group its first slot, and a second
// dispatch of this program (u_write_pass = 1) writes each at its group's slot plus its rank in the group.
#include "splat_render/compute_raster.glsl"

layout(local_size_x = SFFD_RASTER_GROUP_SIZE) in;
#include "common/dispatch.glsl"

layout(std430, binding = SFFD_SSBO_VISIBLE_SPLATS) readonly buffer Records { SplatRecord records[]; };
layout(std430, binding = SFFD_SSBO_DRAW_INDIRECT) readonly buffer Commands { uint commands[]; };
layout(std430, binding = SFFD_SSBO_RASTER_BIG) writeonly buffer Big { uint big[]; };
layout(std430, binding = SFFD_SSBO_RASTER_BIG_COMMANDS) buffer BigCommands { uint big_commands[]; };
layout(location = 0) uniform uvec4 u_list;
layout(std430, binding = SFFD_SSBO_RASTER_GROUPS) buffer Groups { uint groups[]; };
layout(location = 1) uniform uint u_write_pass;

#define SFFD_GROUP_SCAN_SIZE SFFD_RASTER_GROUP_SIZE
#include "common/group_scan.glsl"

void main() {
    const uint i = sffd_dispatch_index();
    const uint r = u_list.x + i;
    const bool listed = i < commands[u_list.y];
    SplatRecord rec;
    bool big_sprite = false;
    if (listed) {
        rec = records[r];
        big_sprite = rec.center.w > SFFD_RASTER_MAX_SPRITE;
    }
    // Inclusive scan of the large-sprite flags over the work group (every invocation reaches it).
    const uint lid = gl_LocalInvocationID.x;
    const uint flag = big_sprite ? 1u : 0u;
    const uint scanned = sffd_inclusive_group_scan(flag);
    const uint group = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    const uint group_count = (u_list.w + SFFD_RASTER_GROUP_SIZE - 1u) / SFFD_RASTER_GROUP_SIZE;
    if (u_write_pass != 0u) {
        if (group == 0u && lid == 0u) big_commands[5u * u_list.z] = groups[group_count];
        if (big_sprite) big[u_list.x + groups[group] + scanned - flag] = r;
        return;
    }
    if (lid == SFFD_RASTER_GROUP_SIZE - 1u && group < group_count) groups[group] = scanned;
    if (!listed || big_sprite) return;
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
