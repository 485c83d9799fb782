#version 450 core
// One instanced quad per visible Gaussian, over the pixels of the box the CPU reference visits (pixels
// floor(c - r) .. ceil(c + r) per axis, y down, clipped to the image by the viewport) where it can be seen.
#include "gaussian/gaussian_layout.h"

// Three storage blocks, what runtime/gfx/limits.h requires of the vertex stage (GL 4.5 guarantees none).
layout(std430, binding = SFFD_GAUSS_SSBO_PROJ_CENTER) readonly buffer ProjCenter { vec4 proj_center[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_PROJ_CONIC) readonly buffer ProjConic { vec4 proj_conic[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_PROJ_COLOR) readonly buffer ProjColor { vec4 proj_color[]; };
// This instance's Gaussian: order[gl_InstanceID], fetched as an instanced attribute (divisor 1), which
// needs no storage block.
layout(location = SFFD_GAUSS_ATTR_ORDER) in uint a_gaussian;

uniform vec2 u_size;
// NDC depth of the quad: u_ndc_depth.x + u_ndc_depth.y / view depth (the render system's projection, so
// the depth test hides Gaussians behind opaque surface splats); (0, 0) by default: z = 0. Clamped below
// the far plane (a Gaussian beyond it stays drawn; the depth buffer is cleared to the far plane).
uniform vec2 u_ndc_depth;

flat out vec2 v_center;
flat out vec4 v_conic_opacity;
flat out vec3 v_color;

void main() {
    const vec4 center_depth_radius = proj_center[a_gaussian];
    const vec4 q = proj_conic[a_gaussian];  // the conic Q = Σ⁻¹ (xx, xy, yy) and the opacity o
    const vec2 c = center_depth_radius.xy;
    const float r = center_depth_radius.w;
    // Within that box only the ellipse dᵀ Q d <= 2 ln(255 o) can pass the fragment stage's α >= 1/255:
    // the quad covers its bounding box, half-widths sqrt(2 ln(255 o) Σxx) and sqrt(.. Σyy), Σ = Q⁻¹, with
    // a margin for rounding. The same pixels are drawn; a thin Gaussian seen across the image's axes costs
    // a fraction of the square (the fill is the quads' cost). Where Q is nearly singular relative to its
    // diagonal (thin and near 45°, where the box is close to the square anyway) Σ is not taken from it.
    vec2 half_size = vec2(r);
    const float qdet = q.x * q.z - q.y * q.y;
    if (qdet > 1e-2 * q.x * q.z) {
        const float k = 2.0 * log(255.0 * q.w);
        const vec2 e = sqrt(max(k, 0.0) * vec2(q.z, q.x) / qdet) * 1.001 + 0.01;
        half_size = min(half_size, e);
    }
    const vec2 lo = floor(c - half_size), hi = ceil(c + half_size) + 1.0;  // pixel edges
    const vec2 corner = vec2(float(gl_VertexID & 1), float(gl_VertexID >> 1));
    const vec2 pix = mix(lo, hi, corner);
    const float z = clamp(u_ndc_depth.x + u_ndc_depth.y / center_depth_radius.z, -1.0, 0.999999);
    gl_Position = vec4(pix.x / u_size.x * 2.0 - 1.0, 1.0 - pix.y / u_size.y * 2.0, z, 1.0);
    v_center = c;
    v_conic_opacity = q;
    v_color = proj_color[a_gaussian].rgb;
}
