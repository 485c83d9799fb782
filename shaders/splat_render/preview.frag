#version 450
// Preview: one pass of opaque ray-cast ellipses with true depth; the vertex shader lit each splat once.
#include "splat_render/raycast.glsl"

#include "splat_render/splat_common.glsl"

#if AUX
layout(location = 3) flat in vec3 v_normal;
#endif


layout(location = 0) out vec4 out_color;   // linear rgb, alpha 1
#if AUX
layout(location = 1) out vec4 out_aux;     // world normal, view-axis depth (only when frames are captured)
#endif

void main() {
    vec3 ray;
    float r2;
    float t = raycast_splat(ray, r2);
    gl_FragDepth = window_depth_inv(dot(v_plane.xyz, ray));
    out_color = vec4(unpack_color(v_plane.w), 1.0);
#if AUX
    out_aux = vec4(v_normal, t);
#endif
}
