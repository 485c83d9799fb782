#version 450
// Culling and compaction: drops back-facing splats and splats outside the view frustum, and sorts the
// survivors into two lists of the visible-index buffer: point sprites (slots from 0) and world-space quads
// (slots from frame.counts.z) for splats a sprite cannot draw correctly (larger than the point-size limit,
// crossing the near plane, or centred off-screen: sprites are clipped by their centre). Two
// DrawArraysIndirectCommands follow: {points, 1, 0, 0} and {6, quads, 0, 0}.
// With culling off (frame.params.z == 0) it only classifies.
layout(local_size_x = 128) in;

#include "splat_render/splat_common.glsl"

layout(std430, binding = SFFD_SSBO_SPLATS_DRAW) readonly buffer Splats { GpuSplat splats[]; };
layout(std430, binding = SFFD_SSBO_VISIBLE) writeonly buffer Visible { uint visible[]; };
layout(std430, binding = SFFD_SSBO_DRAW_INDIRECT) buffer Commands {
    uint point_count, point_instances, point_first, point_base;
    uint quad_vertices, quad_count, quad_first, quad_base;
};

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= frame.counts.x) return;
    GpuSplat s = splats[i];
    vec3 c = (frame.model_view * vec4(s.center.xyz, 1.0)).xyz;
    vec3 u = mat3(frame.model_view) * s.axis_u.xyz;
    vec3 v = mat3(frame.model_view) * s.axis_v.xyz;
    float r = ellipse_max_radius(u, v);
    if (!(r > 0.0) || dot(cross(u, v), cross(u, v)) <= 1e-20 * r * r * r * r) return;  // degenerate

    if (frame.params.z != 0.0) {
        // Back-facing (a splat flipped by an inverted lattice cell, normal.w == 0, is drawn two-sided).
        vec3 n = mat3(frame.normal_view) * s.normal.xyz;
        if (s.normal.w != 0.0 && dot(n, c) > 0.0) return;
        // Frustum, as a bounding ball against the view-space planes of a symmetric perspective.
        float p00 = frame.projection[0][0], p11 = frame.projection[1][1];
        float near_plane = frame.projection[3][2] / (frame.projection[2][2] - 1.0);
        float far_plane = frame.projection[3][2] / (frame.projection[2][2] + 1.0);
        float depth = -c.z;
        if (depth + r < near_plane || depth - r > far_plane) return;
        if ((depth - p00 * abs(c.x)) * inversesqrt(p00 * p00 + 1.0) < -r) return;
        if ((depth - p11 * abs(c.y)) * inversesqrt(p11 * p11 + 1.0) < -r) return;
    }

    float size = sprite_size(c, r);
    vec2 ndc = vec2(frame.projection[0][0] * c.x, frame.projection[1][1] * c.y) / -c.z;
    bool quad = size < 0.0 || size > frame.params.y || any(greaterThan(abs(ndc), vec2(1.0)));
    if (quad) {
        uint slot = atomicAdd(quad_count, 1u);
        visible[frame.counts.z + slot] = i;
    } else {
        uint slot = atomicAdd(point_count, 1u);
        visible[slot] = i;
    }
}
