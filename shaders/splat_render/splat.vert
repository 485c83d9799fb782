#version 450
// One vertex shader for every splat pass. Defines (set by the render system):
//   SHAPE_QUAD 0: a point sprite per visible splat, copied from the cull pass's SplatRecord
//   SHAPE_QUAD 1: a world-space parallelogram c +- u +- v per splat (two triangles, instanced over the quad
//                 list), for splats a sprite cannot draw; set up here from the splat itself
//   PASS 0 visibility, 1 attribute, 2 preview (the later two pass colour and normal on)
//   TEXTURED 1 (attribute and preview passes of a textured cloud): the splat's uv frame and mip level go on
//                 to the fragment shader, which samples the texture per pixel (preview: with the splat's
//                 lighting factors instead of a lit colour)
// The fragment shaders ray-cast the splat's ellipse from the flat values (see SplatRecord).

#include "splat_render/splat_common.glsl"
#ifndef TEXTURED
#define TEXTURED 0
#endif
#define UV_FRAME (PASS != 0 && TEXTURED)
#if SHAPE_QUAD
#include "splat_render/splat_color.glsl"
layout(std430, binding = SFFD_SSBO_SPLATS_DRAW) readonly buffer Splats { GpuSplat splats[]; };
layout(std430, binding = SFFD_SSBO_VISIBLE) readonly buffer QuadList { uint quads[]; };
#if UV_FRAME
layout(std430, binding = SFFD_SSBO_UV_AXES) readonly buffer UvAxes { vec4 uv_axes[]; };
#endif
// The first splat of the range the quad list's indices count from (CloudGpu::quad_batches; 0 without):
// the point marks are indexed by the whole cloud.
layout(location = SFFD_LOC_QUAD_MARK_BASE) uniform uint u_quad_mark_base;
#else
// The SplatRecord array of the cull pass, bound as a vertex buffer (stride SFFD_SPLAT_RECORD_BYTES): the vertex fetcher reads
// it far faster than per-lane SSBO loads on llvmpipe.
layout(location = 0) in vec4 a_center;
layout(location = 1) in vec4 a_plane;
layout(location = 2) in vec4 a_dual_u;
layout(location = 3) in vec4 a_dual_v;
#if PASS != 0
layout(location = 4) in vec4 a_normal;  // w: packed colour
#endif
#if UV_FRAME
layout(location = 5) in vec4 a_uv;      // splat_uv_frame
#endif
#endif

// v_plane.w: PASS 0 the visibility offset eps; PASS 1 untextured the packed albedo (pack_color); otherwise
// unused. The other values the records carry packed (pack_color, pack_light, pack_halves) are unpacked
// here, once per splat, into flat outputs: the fragment shaders, which run per covered pixel of every
// overlapping sprite, only read them (unpacking there was a quarter of the face's preview on llvmpipe).
// The HQ attribute pass of an untextured cloud still unpacks per pixel: one more output measured slower
// there (llvmpipe sets up every output per primitive).
layout(location = 0) flat out vec4 v_plane;
layout(location = 1) flat out vec4 v_dual_u;
layout(location = 2) flat out vec4 v_dual_v;
#if PASS == 1 || AUX
layout(location = 3) flat out vec3 v_normal;  // world space shading normal
#endif
#if PASS == 2
layout(location = 4) flat out vec3 v_color;  // lit colour, or TEXTURED: the diffuse factor
#endif
#if UV_FRAME
layout(location = 5) flat out vec3 v_uv;        // uv at the centre, mip level (splat_texture_lod)
layout(location = 6) flat out vec4 v_uv_axes;   // d(uv)/ds, d(uv)/dt (splat_uv_frame)
#endif
#if PASS == 2 && TEXTURED
layout(location = 7) flat out vec3 v_specular;  // the specular term added to texture * diffuse
#endif

#if UV_FRAME
void set_uv_frame(vec4 frame_packed, float lod) {
    v_uv = vec3(frame_packed.xy, lod);
    v_uv_axes = vec4(unpack_halves(frame_packed.z), unpack_halves(frame_packed.w));
}
#endif

void main() {
#if SHAPE_QUAD
    GpuSplat s = splats[quads[gl_InstanceID]];
    SplatView o = splat_view(s);
    splat_raycast_setup(o, v_plane, v_dual_u, v_dual_v);
    if (frame.params.z == 0.0 && s.normal.w != 0.0 && dot(o.shading_n, o.c) > 0.0)
        v_plane.xyz = vec3(0.0);  // back-facing with culling off: hidden (splat_record.h), every fragment discards
#if PASS != 0
    vec3 world_n = normalize(mat3(frame.view_to_world) * o.shading_n);
    // Quantised as the records are (pack then unpack), so a splat looks the same drawn as either shape.
#if UV_FRAME
    vec4 uv_axes_i = uv_axes[quads[gl_InstanceID]];
    set_uv_frame(splat_uv_frame(s, uv_axes_i),
                 splat_texture_lod(o.c, v_plane, v_dual_u, v_dual_v, uv_axes_i, vec2(textureSize(material_texture, 0))));
#if PASS == 2
    vec3 diffuse, specular;
    splat_light_factors(o, world_n, diffuse, specular);
    v_color = unpack_light(pack_light(diffuse));
    v_specular = unpack_light(pack_light(specular));
#endif
#elif PASS == 2
    v_color = unpack_color(pack_color(splat_color(s, o, world_n, point_mark(u_quad_mark_base + quads[gl_InstanceID], frame.counts.z)).rgb));
#else
    v_plane.w = pack_color(splat_color(s, o, world_n, point_mark(u_quad_mark_base + quads[gl_InstanceID], frame.counts.z)).rgb);
#endif
#if PASS == 1 || AUX
    v_normal = world_n;
#endif
#endif
    // Two triangles (0,1,2) (2,1,3) over the corners (-1,-1) (1,-1) (-1,1) (1,1).
    const vec2 corners[6] = vec2[6](vec2(-1, -1), vec2(1, -1), vec2(-1, 1), vec2(-1, 1), vec2(1, -1), vec2(1, 1));
    vec2 k = corners[gl_VertexID];
    gl_Position = frame.projection * vec4(o.c + k.x * o.u + k.y * o.v, 1.0);
#else
    v_plane = a_plane;
    v_dual_u = a_dual_u;
    v_dual_v = a_dual_v;
#if PASS == 1 || AUX
    v_normal = a_normal.xyz;
#endif
    // The record's fields: SplatRecord (splat_record.h).
#if PASS == 1 && TEXTURED
    set_uv_frame(a_uv, a_normal.w);  // mip level
#elif PASS == 2 && TEXTURED
    set_uv_frame(a_uv, round(a_center.z));  // the preview samples one level
    v_color = unpack_light(a_normal.w);
    v_specular = unpack_light(a_plane.w);
#elif PASS == 2
    v_color = unpack_color(a_normal.w);
#elif PASS == 1
    v_plane.w = a_normal.w;
#endif
    // The sprite's centre in NDC. Its depth is irrelevant (every splat fragment shader writes gl_FragDepth)
    // and z = 0 keeps the point inside the clip volume (near-crossing splats are quads).
    gl_Position = vec4(a_center.xy, 0.0, 1.0);
    gl_PointSize = a_center.w;
#endif
}
