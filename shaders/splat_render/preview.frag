#version 450
// Preview: one pass of opaque ray-cast ellipses with true depth, lit per pixel with the splat's normal.
#include "splat_render/raycast.glsl"
#include "splat_render/lighting.glsl"

layout(location = 5) flat in vec4 v_color;
layout(location = 6) flat in vec3 v_normal;

layout(location = 0) out vec4 out_color;   // linear rgb, alpha 1
layout(location = 1) out vec4 out_aux;     // world normal, view-axis depth

void main() {
    vec3 ray;
    float r2;
    vec3 p = raycast_splat(ray, r2);
    gl_FragDepth = window_depth(p.z);
    out_color = vec4(shade_blinn_phong(v_color.rgb, v_normal, pixel_to_eye_world()), 1.0);
    out_aux = vec4(v_normal, -p.z);
}
