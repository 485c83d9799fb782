// Shared by the cull compute pass and the splat vertex shaders: the splat's screen-space footprint, so
// the cull pass's point/quad decision and the sprite size the vertex shader sets always agree.
#ifndef SFFD_SPLAT_COMMON_GLSL
#define SFFD_SPLAT_COMMON_GLSL

#include "common/bindings.h"
#include "splat_render/frame_block.h"

// Largest radius of the ellipse {s*u + t*v : s^2 + t^2 <= 1}: sqrt of the Gram matrix's larger eigenvalue
// (u and v need not be orthogonal after a deformation).
float ellipse_max_radius(vec3 u, vec3 v) {
    float a = dot(u, u), b = dot(u, v), c = dot(v, v);
    float h = 0.5 * (a + c);
    return sqrt(h + sqrt(max(0.25 * (a - c) * (a - c) + b * b, 0.0)));
}

// Conservative side length in pixels of a square sprite centred on the projected centre that holds the
// projection of a ball of radius r at view-space centre c. Returns -1 when the ball crosses the near plane.
float sprite_size(vec3 c, float r) {
    float depth = -c.z;
    float near_depth = depth - r;
    // projection[3][2] / (projection[2][2] - 1) is the near-plane distance of a GL perspective matrix.
    float near_plane = frame.projection[3][2] / (frame.projection[2][2] - 1.0);
    if (near_depth <= near_plane) return -1.0;
    float ndc_x = frame.projection[0][0] * c.x / depth;
    float ndc_y = frame.projection[1][1] * c.y / depth;
    float half_x = r * (frame.projection[0][0] + abs(ndc_x)) / near_depth * 0.5 * frame.viewport.x;
    float half_y = r * (frame.projection[1][1] + abs(ndc_y)) / near_depth * 0.5 * frame.viewport.y;
    return 2.0 * max(half_x, half_y) + 0.5;  // the bound is conservative already: no more margin (fragments cost)
}

vec3 srgb_to_linear(vec3 c) {
    return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), greaterThan(c, vec3(0.04045)));
}

#endif
