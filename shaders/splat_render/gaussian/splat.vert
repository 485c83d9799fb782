#version 450 core
// One instanced quad per visible Gaussian, over the pixels of the box the CPU reference visits (pixels
// floor(c - r) .. ceil(c + r) per axis, y down, clipped to the image by the viewport) narrowed to where it
// can be seen (footprint.glsl).
#include "gaussian/gaussian_layout.h"
#include "splat_render/gaussian/footprint.glsl"

// Three storage blocks, what runtime/gfx/limits.h requires of the vertex stage (GL 4.5 guarantees none).
layout(std430, binding = SFFD_GAUSS_SSBO_PROJ_CENTER) readonly buffer ProjCenter { vec4 proj_center[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_PROJ_CONIC) readonly buffer ProjConic { vec4 proj_conic[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_PROJ_COLOR) readonly buffer ProjColor { vec4 proj_color[]; };
// The arrays are the depth-ordered projection (gather.comp), bound from the first position of the range
// this draw covers: instance i is that range's i-th Gaussian front to back.

uniform vec2 u_size;
// NDC depth of the quad: u_ndc_depth.x + u_ndc_depth.y / view depth (the render system's projection, so
// the depth test hides Gaussians behind opaque surface splats); (0, 0) by default: z = 0. Clamped below
// the far plane (a Gaussian beyond it stays drawn; the depth buffer is cleared to the far plane).
uniform vec2 u_ndc_depth;

flat out vec2 v_center;
flat out vec4 v_conic_opacity;
flat out vec3 v_color;

void main() {
    const uint a_gaussian = uint(gl_InstanceID);
    const vec4 center_depth_radius = proj_center[a_gaussian];
    const vec4 q = proj_conic[a_gaussian];  // the conic Q = Σ⁻¹ (xx, xy, yy) and the opacity o
    const vec2 c = center_depth_radius.xy;
    const float r = center_depth_radius.w;
    const vec2 half_size = footprint_half_size(r, q);  // footprint.glsl: the visible part's box
    const vec2 lo = floor(c - half_size), hi = ceil(c + half_size) + 1.0;  // pixel edges
    const vec2 corner = vec2(float(gl_VertexID & 1), float(gl_VertexID >> 1));
    const vec2 pix = mix(lo, hi, corner);
    const float z = clamp(u_ndc_depth.x + u_ndc_depth.y / center_depth_radius.z, -1.0, 0.999999);
    gl_Position = vec4(pix.x / u_size.x * 2.0 - 1.0, 1.0 - pix.y / u_size.y * 2.0, z, 1.0);
    v_center = c;
    v_conic_opacity = q;
    v_color = proj_color[a_gaussian].rgb;
}
