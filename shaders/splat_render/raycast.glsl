// Per-pixel ray-ellipse intersection shared by the splat fragment shaders (coefficients: SplatRecord).
#ifndef SFFD_RAYCAST_GLSL
#define SFFD_RAYCAST_GLSL

#include "common/bindings.h"
#include "splat_render/frame_block.h"

layout(location = 0) flat in vec4 v_plane;
layout(location = 1) flat in vec4 v_dual_u;
layout(location = 2) flat in vec4 v_dual_v;

// View-space direction of the ray through this fragment's pixel centre, scaled to z = -1.
vec3 pixel_ray() {
    return vec3(gl_FragCoord.xy * frame.ray_map.xy + frame.ray_map.zw, -1.0);
}

// Window depth of a point at view-axis depth t (view-space z = -t), as the fixed-function pipeline
// computes it, from 1/t (no division).
float window_depth_inv(float inv_t) {
    return 0.5 * (frame.projection[3][2] * inv_t - frame.projection[2][2]) + 0.5;
}
float window_depth(float t) { return window_depth_inv(1.0 / t); }

// Intersects the pixel's ray with the splat's plane; discards outside the ellipse, where the plane is not in
// front along the ray, and splats marked hidden by the cull pass (culling off, back-facing: plane.xyz = 0,
// so the dot product is exactly 0; splat_record.h). Only comparisons of finite values: no NaN or infinity.
// Returns the view-axis depth t of the hit (p = t * ray), its splat coordinates st
// (p = centre + st.x * axis_u + st.y * axis_v) and the squared elliptical radius r2 = |st|^2.
float raycast_splat(out vec3 ray, out float r2, out vec2 st) {
    ray = pixel_ray();
    float inv_t = dot(v_plane.xyz, ray);
    if (inv_t <= 0.0) discard;
    float t = 1.0 / inv_t;
    vec4 du = v_dual_u, dv = v_dual_v;
    float s = t * dot(du.xyz, ray) - du.w;
    float q = t * dot(dv.xyz, ray) - dv.w;
    r2 = s * s + q * q;
    if (r2 > 1.0) discard;
    st = vec2(s, q);
    return t;
}
float raycast_splat(out vec3 ray, out float r2) {
    vec2 st;
    return raycast_splat(ray, r2, st);
}

#endif
