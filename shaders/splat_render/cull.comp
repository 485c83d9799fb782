#version 450
// Culling and compaction: drops back-facing splats and splats outside the view frustum. Survivors a point
// sprite can draw get a view-space SplatRecord (the vertex shaders then only copy it); the others (larger
// than the point-size limit, crossing the near plane, or centred off-screen: sprites are clipped by their
// centre) go to the quad list as indices. Two DrawArraysIndirectCommands follow: {sprites, 1, 0, 0} and
// {6, quads, 0, 0}. With culling off (frame.params.z == 0) nothing is dropped: back-facing sprites are
// marked (plane.xyz = NaN) and discarded per fragment, so the image is the same and the cost is visible.
layout(local_size_x = 128) in;

#include "splat_render/splat_color.glsl"

layout(std430, binding = SFFD_SSBO_SPLATS_DRAW) readonly buffer Splats { GpuSplat splats[]; };
layout(std430, binding = SFFD_SSBO_VISIBLE) writeonly buffer QuadList { uint quads[]; };
layout(std430, binding = SFFD_SSBO_VISIBLE_SPLATS) writeonly buffer Records { SplatRecord records[]; };
layout(std430, binding = SFFD_SSBO_DRAW_INDIRECT) buffer Commands {
    uint point_count, point_instances, point_first, point_base;
    uint quad_vertices, quad_count, quad_first, quad_base;
};

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= frame.counts.x) return;
    GpuSplat s = splats[i];
    SplatView o = splat_view(s);
    vec3 n = cross(o.u, o.v);
    if (!(o.r > 0.0) || dot(n, n) <= 1e-12 * o.r * o.r * o.r * o.r) return;  // degenerate (or NaN)

    // Back-facing (a splat flipped by an inverted lattice cell, normal.w == 0, is drawn two-sided).
    bool back = s.normal.w != 0.0 && dot(o.shading_n, o.c) > 0.0;
    if (frame.params.z != 0.0) {
        if (back) return;
        // Frustum, as a bounding ball against the view-space planes of a symmetric perspective.
        float p00 = frame.projection[0][0], p11 = frame.projection[1][1];
        float near_plane = frame.projection[3][2] / (frame.projection[2][2] - 1.0);
        float far_plane = frame.projection[3][2] / (frame.projection[2][2] + 1.0);
        float depth = -o.c.z;
        if (depth + o.r < near_plane || depth - o.r > far_plane) return;
        if ((depth - p00 * abs(o.c.x)) * inversesqrt(p00 * p00 + 1.0) < -o.r) return;
        if ((depth - p11 * abs(o.c.y)) * inversesqrt(p11 * p11 + 1.0) < -o.r) return;
    }

    float size = sprite_size(o.c, o.r);
    vec2 ndc = vec2(frame.projection[0][0] * o.c.x, frame.projection[1][1] * o.c.y) / -o.c.z;
    if (size < 0.0 || size > frame.params.y || any(greaterThan(abs(ndc), vec2(1.0)))) {
        quads[atomicAdd(quad_count, 1u)] = i;
        return;
    }
    SplatRecord rec;
    splat_raycast_setup(o, rec.plane, rec.dual_u, rec.dual_v);
    if (back) rec.plane.xyz = vec3(uintBitsToFloat(0x7fc00000u));  // NaN: every fragment discards
    rec.center = vec4(o.c, size);
    vec3 world_n = normalize(mat3(frame.view_to_world) * o.shading_n);
    rec.normal = vec4(world_n, pack_color(splat_color(s, o, world_n).rgb));
    records[atomicAdd(point_count, 1u)] = rec;
}
