// Per-pixel ray-ellipse intersection shared by the splat fragment shaders.
#ifndef SFFD_RAYCAST_GLSL
#define SFFD_RAYCAST_GLSL

#include "common/bindings.h"
#include "splat_render/frame_block.h"

layout(location = 0) flat in vec3 v_plane;
layout(location = 1) flat in vec3 v_dual_u;
layout(location = 2) flat in vec3 v_dual_v;
layout(location = 3) flat in vec3 v_consts;
layout(location = 4) flat in float v_eps;

// View-space direction of the ray through this fragment's pixel centre, scaled to z = -1.
vec3 pixel_ray() {
    vec2 ndc = gl_FragCoord.xy * frame.viewport.zw * 2.0 - 1.0;
    return vec3(ndc.x / frame.projection[0][0], ndc.y / frame.projection[1][1], -1.0);
}

// Window depth of a point at view-axis depth t (view-space z = -t), as the fixed-function pipeline computes it.
float window_depth(float t) {
    return 0.5 * (frame.projection[3][2] / t - frame.projection[2][2]) + 0.5;
}

// Intersects the pixel's ray with the splat's plane (see splat.vert for the linear form); discards
// outside the ellipse and, with culling off, where the ray sees the splat's back. Returns the view-axis
// depth t of the hit (p = t * ray); r2 = squared elliptical radius.
float raycast_splat(out vec3 ray, out float r2) {
    ray = pixel_ray();
    float denom = dot(ray, v_plane);
    if (frame.params.z == 0.0 && denom > 0.0) discard;
    float t = v_consts.x / denom;
    if (!(t > 0.0)) discard;
    float s = t * dot(v_dual_u, ray) - v_consts.y;
    float q = t * dot(v_dual_v, ray) - v_consts.z;
    r2 = s * s + q * q;
    if (r2 > 1.0) discard;
    return t;
}

#endif
