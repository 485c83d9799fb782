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
// closed surface that face away cost little. One global atomic per kept splat: per-workgroup slot
// reservation needs barrier(), which llvmpipe runs as coroutines (measured: the pass became ~1.5x slower).
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

const uint KEEP_NONE = 0u, KEEP_SPRITE = 1u, KEEP_QUAD = 2u;

void main() {
    uint i = sffd_dispatch_index();
    uint keep = KEEP_NONE;
    GpuSplat s;
    vec3 c = vec3(0.0);
    bool back = false;
    vec3 u = vec3(0.0), v = vec3(0.0);
    vec3 box = vec3(0.0);  // sprite: NDC centre (xy) and side in pixels (z), ellipse_sprite()
    if (i < frame.counts.x) {
        // Centre and normal first: the back-face test needs only them (llvmpipe loads SSBOs per lane).
        s.center = splats[i].center;
        s.normal = splats[i].normal;
        c = (frame.model_view * vec4(s.center.xyz, 1.0)).xyz;
        // Back-facing (a splat flipped by an inverted lattice cell, normal.w == 0, is drawn two-sided).
        back = s.normal.w != 0.0 && dot(mat3(frame.normal_view) * s.normal.xyz, c) > 0.0;
        keep = back && frame.params.z != 0.0 ? KEEP_NONE : KEEP_SPRITE;
        if (!all_finite(s.center.xyz) || !all_finite(s.normal.xyz) || !all_finite(c))
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

    if (keep == KEEP_QUAD) {
        quads[atomicAdd(quad_count, 1u)] = i;
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
        rec.normal = vec4(world_n, pack_color(splat_color(s, o, world_n).rgb));
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
        records[atomicAdd(point_count, 1u)] = rec;
    }
}
