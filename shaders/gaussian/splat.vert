#version 450 core
// One instanced quad per visible Gaussian, covering exactly the pixel box the CPU reference visits:
// pixels floor(c - r) .. ceil(c + r) per axis (y down), clipped to the image by the viewport.
#include "gaussian/gaussian_layout.h"

layout(std430, binding = SFFD_GAUSS_SSBO_PROJECTED) readonly buffer Projected { GpuProjected projected[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_ORDER) readonly buffer Order { uint order[]; };

uniform vec2 u_size;

flat out vec2 v_center;
flat out vec4 v_conic_opacity;
flat out vec3 v_color;

void main() {
    const GpuProjected p = projected[order[gl_InstanceID]];
    const vec2 c = p.center_depth_radius.xy;
    const float r = p.center_depth_radius.w;
    const vec2 lo = floor(c - r), hi = ceil(c + r) + 1.0;  // pixel edges
    const vec2 corner = vec2(float(gl_VertexID & 1), float(gl_VertexID >> 1));
    const vec2 pix = mix(lo, hi, corner);
    gl_Position = vec4(pix.x / u_size.x * 2.0 - 1.0, 1.0 - pix.y / u_size.y * 2.0, 0.0, 1.0);
    v_center = c;
    v_conic_opacity = p.conic_opacity;
    v_color = p.color.rgb;
}
