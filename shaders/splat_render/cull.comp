#version 450
// Culling and compaction: drops back-facing splats and splats outside the view frustum. Survivors a point
// sprite can draw get a view-space SplatRecord (the vertex shaders then only copy it); the others (larger
// than the point-size limit, crossing the near plane, or centred off-screen: sprites are clipped by their
// centre) go to the quad list as indices. A sprite is the square around the exact screen bounding box of
// the splat's projected ellipse (ellipse_sprite), so foreshortened splats near a silhouette cost far fewer
// fragments than a square around their bounding ball. Two DrawArraysIndirectCommands follow: {sprites, 1, 0, 0} and
// {6, quads, 0, 0} (a third, the CPU cull's flat-coloured sprites of a textured cloud, stays empty here:
// this pass textures every sprite of a textured cloud per pixel). With culling off (frame.params.z == 0)
// nothing is dropped: back-facing sprites are marked hidden (plane.xyz = 0, splat_record.h) and discarded
// per fragment, so the image is the same and the cost is visible. Non-finite input is recognised from its
// bits (all_finite), never by NaN comparisons.
//
// Cheap tests first (back face from centre and normal only, then the frustum), so the two thirds of a
// closed surface that face away cost little.
//
// The lists keep splat order, so a frame is the same image every time it is drawn: the draws blend and
// depth-test their sprites in list order, and an atomic append would order them by whichever invocation
// got there first, which varies from run to run on a GPU (ties in the depth test and the order of float
// sums then change pixels: a farm's shards would not match one run). Two dispatches of this program with an
// exclusive scan between them (cull_pass.cpp): the count pass (u_count_pass = 1) writes each work group's
// kept sprites and quads into groups[g] and groups[G + g] (G groups); gfx::exclusive_scan() turns that into
// each group's first slot; the write pass classifies again and writes every kept splat at its group's first
// slot plus its rank in the group (a scan in shared memory). The commands' counts are the scan's totals.
// Hidden and deleted points (their marks, point_marks.glsl, when frame.counts.z says the cloud has some)
// are dropped first, like a culled splat; the kept ones' colours show the marks' overlays (splat_color).
//
// Both passes run the same compiled program, so they classify every splat alike (two compilations could
// contract floating-point operations differently and disagree on a splat at a frustum plane).
#include "splat_render/splat_color.glsl"

layout(local_size_x = SFFD_CULL_GROUP_SIZE) in;
#include "common/dispatch.glsl"

layout(std430, binding = SFFD_SSBO_SPLATS_DRAW) readonly buffer Splats { GpuSplat splats[]; };
layout(std430, binding = SFFD_SSBO_VISIBLE) writeonly buffer QuadList { uint quads[]; };
layout(std430, binding = SFFD_SSBO_VISIBLE_SPLATS) writeonly buffer Records { SplatRecord records[]; };
#if TEXTURED
layout(std430, binding = SFFD_SSBO_UV_AXES) readonly buffer UvAxes { vec4 uv_axes[]; };
#endif
layout(std430, binding = SFFD_SSBO_DRAW_INDIRECT) buffer Commands {
    uint point_count, point_instances, point_first, point_base;
    uint quad_vertices, quad_count, quad_first, quad_base;
};
// Count pass: per group kept sprites [0, G) and quads [G, 2G). Write pass: their exclusive scan, the total
// at [2G].
layout(std430, binding = SFFD_SSBO_CULL_GROUPS) buffer Groups { uint groups[]; };

layout(location = SFFD_LOC_CULL_PASS) uniform uint u_count_pass;

#define SFFD_GROUP_SCAN_SIZE SFFD_CULL_GROUP_SIZE
#include "common/group_scan.glsl"

const uint KEEP_NONE = 0u, KEEP_SPRITE = 1u, KEEP_QUAD = 2u;

void main() {
    uint i = sffd_dispatch_index();
    uint keep = KEEP_NONE;
    GpuSplat s;
    vec3 c = vec3(0.0);
    bool back = false;
    vec3 u = vec3(0.0), v = vec3(0.0);
    vec3 box = vec3(0.0);  // sprite: NDC centre (xy) and side in pixels (z), ellipse_sprite()
    uint mark = SFFD_MARK_DEFAULT;
    if (i < frame.counts.x) mark = point_mark(i, frame.counts.z);
    if (i < frame.counts.x && !mark_gone(mark)) {
        // Centre and normal first: the back-face test needs only them (llvmpipe loads SSBOs per lane).
        s.center = splats[i].center;
        s.color = splats[i].color;
        s.normal = splats[i].normal;
        c = (frame.model_view * vec4(s.center, 1.0)).xyz;
        // Back-facing (a splat flipped by an inverted lattice cell, normal.w == 0, is drawn two-sided).
        back = s.normal.w != 0.0 && dot(mat3(frame.normal_view) * s.normal.xyz, c) > 0.0;
        keep = back && frame.params.z != 0.0 ? KEEP_NONE : KEEP_SPRITE;
        if (!all_finite(s.center) || !all_finite(s.normal.xyz) || !all_finite(c))
            keep = KEEP_NONE;  // nothing to draw (the CPU cull agrees)
    }
    float r = 0.0;
    if (keep != KEEP_NONE) {
        s.axis_u = splats[i].axis_u;
        s.axis_v = splats[i].axis_v;
        u = mat3(frame.model_view) * s.axis_u.xyz;
        v = mat3(frame.model_view) * s.axis_v.xyz;
        vec3 n = cross(u, v);
        if (!all_finite(s.axis_u.xyz) || !all_finite(s.axis_v.xyz) || !all_finite(u) || !all_finite(v)) {
            keep = KEEP_NONE;
        } else {
            r = ellipse_max_radius(u, v);
            if (r <= 0.0 || dot(n, n) <= 1e-12 * r * r * r * r) keep = KEEP_NONE;  // degenerate
        }
    }
    if (keep != KEEP_NONE && frame.params.z != 0.0) {
        // Frustum, as a bounding ball against the view-space planes of a symmetric perspective.
        float p00 = frame.projection[0][0], p11 = frame.projection[1][1];
        float near_plane = frame.projection[3][2] / (frame.projection[2][2] - 1.0);
        float far_plane = frame.projection[3][2] / (frame.projection[2][2] + 1.0);
        float depth = -c.z;
        if (depth + r < near_plane || depth - r > far_plane ||
            (depth - p00 * abs(c.x)) * inversesqrt(p00 * p00 + 1.0) < -r ||
            (depth - p11 * abs(c.y)) * inversesqrt(p11 * p11 + 1.0) < -r)
            keep = KEEP_NONE;
    }
    if (keep != KEEP_NONE) {
        box = ellipse_sprite(c, u, v);
        if (box.z < 0.0 || box.z > frame.params.y || any(greaterThan(abs(box.xy), vec2(1.0)))) keep = KEEP_QUAD;
    }

    // Inclusive scan of the kept flags over the work group (every invocation reaches it: no early return
    // above), sprites in the low 16 bits, quads in the high 16: a group holds at most
    // SFFD_CULL_GROUP_SIZE < 2^16 of either kind.
    const uint lid = gl_LocalInvocationID.x;
    const uint flag = keep == KEEP_SPRITE ? 1u : keep == KEEP_QUAD ? 0x10000u : 0u;
    const uint scanned = sffd_inclusive_group_scan(flag);
    const uint group = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    const uint group_count = (frame.counts.x + SFFD_CULL_GROUP_SIZE - 1u) / SFFD_CULL_GROUP_SIZE;
    if (u_count_pass != 0u) {
        if (lid == SFFD_CULL_GROUP_SIZE - 1u && group < group_count) {
            groups[group] = scanned & 0xffffu;
            groups[group_count + group] = scanned >> 16u;
        }
        return;
    }
    const uint rank = scanned - flag;  // kept splats of this group before this one
    const uint sprites = groups[group_count];  // the sprites' total: the quads' scan starts from it
    if (group == 0u && lid == 0u) {
        point_count = sprites;
        quad_count = groups[2u * group_count] - sprites;
    }
    if (keep == KEEP_QUAD) {
        quads[groups[group_count + group] - sprites + (rank >> 16u)] = i;
    } else if (keep == KEEP_SPRITE) {
        SplatView o = splat_view(s);
        SplatRecord rec;
        splat_raycast_setup(o, rec.plane, rec.dual_u, rec.dual_v);
        if (back) rec.plane.xyz = vec3(0.0);  // hidden (culling off): every fragment discards
        rec.center = vec4(box.xy, o.c.z, box.z);
        vec3 world_n = normalize(mat3(frame.view_to_world) * o.shading_n);
#if TEXTURED && LIT
        // Preview: lighting factors; the texture is sampled per pixel (SplatRecord).
        vec3 diffuse, specular;
        splat_light_factors(o, world_n, diffuse, specular);
        rec.normal = vec4(world_n, pack_light(diffuse));
        rec.plane.w = pack_light(specular);
#elif TEXTURED
        rec.normal = vec4(world_n, 0.0);  // HQ samples the texture per pixel: the mip level goes here below
#else
        rec.normal = vec4(world_n, pack_color(splat_color(s, o, world_n, mark).rgb));
#endif
#if TEXTURED
        vec4 uv_axes_i = uv_axes[i];
        rec.uv = splat_uv_frame(s, uv_axes_i);
        float lod = splat_texture_lod(o.c, rec.plane, rec.dual_u, rec.dual_v, uv_axes_i, vec2(textureSize(material_texture, 0)));
#if LIT
        rec.center.z = lod;   // preview
#else
        rec.normal.w = lod;   // HQ: the colour slot carries the mip level
#endif
#else
        rec.uv = vec4(0.0);
#endif
        records[groups[group] + (rank & 0xffffu)] = rec;
    }
}
