// Per-pixel ray-ellipse intersection shared by the splat fragment shaders.
#ifndef SFFD_RAYCAST_GLSL
#define SFFD_RAYCAST_GLSL

#include "common/bindings.h"
#include "splat_render/frame_block.h"

layout(location = 0) flat in vec3 v_center;
layout(location = 1) flat in vec3 v_dual_u;
layout(location = 2) flat in vec3 v_dual_v;
layout(location = 3) flat in vec3 v_plane;
layout(location = 4) flat in float v_eps;

// View-space direction (not normalised, z = -1) of the ray through this fragment's pixel centre.
vec3 pixel_ray() {
    vec2 ndc = gl_FragCoord.xy * frame.viewport.zw * 2.0 - 1.0;
    return vec3(ndc.x / frame.projection[0][0], ndc.y / frame.projection[1][1], -1.0);
}

// Window depth of a view-space z, as the fixed-function pipeline would compute it.
float window_depth(float z) {
    float ndc_z = (frame.projection[2][2] * z + frame.projection[3][2]) / -z;
    return ndc_z * 0.5 + 0.5;
}

// Intersects the pixel's ray with the splat's plane; discards outside the ellipse (and, with culling off,
// where the ray sees the splat's back). Returns the view-space hit point; r2 = squared elliptical radius.
vec3 raycast_splat(out vec3 ray, out float r2) {
    ray = pixel_ray();
    float denom = dot(ray, v_plane);
    if (frame.params.z == 0.0 && denom > 0.0) discard;
    if (abs(denom) < 1e-12) discard;
    float t = dot(v_center, v_plane) / denom;
    if (t <= 0.0) discard;
    vec3 p = ray * t;
    vec3 d = p - v_center;
    vec2 st = vec2(dot(v_dual_u, d), dot(v_dual_v, d));
    r2 = dot(st, st);
    if (r2 > 1.0) discard;
    return p;
}

#endif
