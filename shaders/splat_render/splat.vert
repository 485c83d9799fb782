#version 450
// One vertex shader for every splat pass. Defines (set by the render system):
//   SHAPE_QUAD 0: a point sprite per splat (visible list from slot 0, one vertex per splat)
//   SHAPE_QUAD 1: a world-space parallelogram c +- u +- v per splat (two triangles, instanced; visible
//                 list from slot frame.counts.z), for splats a sprite cannot draw
//   PASS 0 visibility, 1 attribute, 2 preview (the later two need colour and normal)
// The fragment shaders ray-cast the splat's ellipse from these flat values.

#include "splat_render/splat_common.glsl"
#if PASS == 2
#include "splat_render/lighting.glsl"
#endif

layout(std430, binding = SFFD_SSBO_SPLATS_DRAW) readonly buffer Splats { GpuSplat splats[]; };
layout(std430, binding = SFFD_SSBO_VISIBLE) readonly buffer Visible { uint visible[]; };
layout(binding = SFFD_TEX_MATERIAL) uniform sampler2D material_texture;

// The ray through a pixel is d = (x, y, -1) in view space (x, y from the pixel's NDC); every quantity
// the ray cast needs is linear in d, so the vertex shader hands over coefficient vectors:
//   t = v_consts.x / dot(v_plane, d)   (hit: p = t * d, view-axis depth t)
//   s = t * dot(v_dual_u, d) - v_consts.y,  q = t * dot(v_dual_v, d) - v_consts.z,  inside: s^2 + q^2 <= 1
layout(location = 0) flat out vec3 v_plane;   // plane normal u x v, oriented like the splat's normal
layout(location = 1) flat out vec3 v_dual_u;  // dual axes: s = dot(v_dual_u, p - center)
layout(location = 2) flat out vec3 v_dual_v;
layout(location = 3) flat out vec3 v_consts;  // dot(center, plane), dot(dual_u, center), dot(dual_v, center)
layout(location = 4) flat out float v_eps;    // visibility offset along the view ray (view-space units)
#if PASS == 1
layout(location = 5) flat out vec4 v_color;   // linear rgb
layout(location = 6) flat out vec3 v_normal;  // world space shading normal
#elif PASS == 2
layout(location = 5) flat out vec4 v_color;   // lit colour (preview shades per splat)
layout(location = 6) flat out vec3 v_normal;  // world space shading normal
#endif

void main() {
#if SHAPE_QUAD
    uint index = visible[frame.counts.z + uint(gl_InstanceID)];
#else
    uint index = visible[gl_VertexID];
#endif
    GpuSplat s = splats[index];
    vec3 c = (frame.model_view * vec4(s.center.xyz, 1.0)).xyz;
    vec3 u = mat3(frame.model_view) * s.axis_u.xyz;
    vec3 v = mat3(frame.model_view) * s.axis_v.xyz;
    vec3 n = cross(u, v);
    vec3 shading_n = normalize(mat3(frame.normal_view) * s.normal.xyz);
    float r = ellipse_max_radius(u, v);

    vec3 plane = dot(n, shading_n) < 0.0 ? -n : n;
    vec3 dual_u = cross(v, n) / dot(cross(v, n), u);
    vec3 dual_v = cross(n, u) / dot(cross(n, u), v);
    v_plane = plane;
    v_dual_u = dual_u;
    v_dual_v = dual_v;
    v_consts = vec3(dot(c, plane), dot(dual_u, c), dot(dual_v, c));
    v_eps = frame.params.x * r;
#if PASS != 0
    vec4 color;
    if (frame.params.w != 0.0)
        color = textureLod(material_texture, vec2(s.axis_u.w, s.axis_v.w), 0.0);  // sRGB texture: linear
    else {
        color = unpackUnorm4x8(floatBitsToUint(s.center.w));
        color.rgb = srgb_to_linear(color.rgb);
    }
    vec3 world_n = normalize(mat3(frame.view_to_world) * shading_n);
    v_normal = world_n;
#if PASS == 2
    // Preview: Blinn-Phong once per splat with its normal, towards the eye from the splat's centre.
    vec3 to_eye = -normalize(mat3(frame.view_to_world) * c);
    color.rgb = shade_blinn_phong(color.rgb, world_n, to_eye);
#endif
    v_color = color;
#endif

#if SHAPE_QUAD
    // Two triangles (0,1,2) (2,1,3) over the corners (-1,-1) (1,-1) (-1,1) (1,1).
    const vec2 corners[6] = vec2[6](vec2(-1, -1), vec2(1, -1), vec2(-1, 1), vec2(-1, 1), vec2(1, -1), vec2(1, 1));
    vec2 k = corners[gl_VertexID];
    gl_Position = frame.projection * vec4(c + k.x * u + k.y * v, 1.0);
#else
    gl_Position = frame.projection * vec4(c, 1.0);
    gl_PointSize = min(sprite_size(c, r), frame.params.y);
#endif
}
