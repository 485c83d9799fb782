#version 450
// HQ pass 2: additive blending of weighted attributes into two RGBA32F targets. Depth test against the
// visibility pass (LEQUAL, no depth writes) keeps only splats within eps of the visible surface.
//   accum_color  = sum(w * linear rgb), sum(w)
//   accum_normal = sum(w * world normal), sum(w * view-axis depth)
//   accum_material (MATERIALS 1) = sum(w * specular), sum(w * shininess)
#include "splat_render/raycast.glsl"

#include "splat_render/splat_common.glsl"

layout(location = 3) flat in vec3 v_normal;


layout(location = 0) out vec4 accum_color;
layout(location = 1) out vec4 accum_normal;
#if MATERIALS
// Clouds with different materials in one frame: their specular and shininess blend like the colour.
layout(location = 2) out vec4 accum_material;
#endif

void main() {
    vec3 ray;
    float r2;
    float t = raycast_splat(ray, r2);
    gl_FragDepth = window_depth_inv(dot(v_plane.xyz, ray));
    // Smooth radial kernel that reaches 0 at the ellipse's edge: no visible disc borders.
    float w = (1.0 - r2) * (1.0 - r2) + 1e-6;
    accum_color = vec4(w * unpack_color(v_plane.w), w);
    accum_normal = vec4(w * v_normal, w * t);
#if MATERIALS
    accum_material = vec4(w * frame.material.xy, 0.0, 0.0);
#endif
}
