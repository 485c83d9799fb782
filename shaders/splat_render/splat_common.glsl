// Shared by the cull compute pass and the splat vertex shaders: the view-space set-up of one splat (what
// the fragment shaders' ray cast needs) and its screen-space footprint.
#ifndef SFFD_SPLAT_COMMON_GLSL
#define SFFD_SPLAT_COMMON_GLSL

#include "common/bindings.h"
#include "splat_render/frame_block.h"
#include "splat_render/splat_record.h"

// Colour of a SplatRecord: the 30 bits r | g << 10 | b << 20 of sqrt(linear rgb), stored in a float's
// mantissa (bits 0..22) and exponent (bits 23..29 plus one, so 1..128): always a normal, finite float, never
// a NaN, infinity or denormal that a driver may canonicalise or flush on its way through a varying.
// The C++ twin is pack_color() in systems/splat_render/cpu_cull.cpp.
float pack_color(vec3 linear) {
    uvec3 q = uvec3(round(sqrt(clamp(linear, 0.0, 1.0)) * 1023.0));
    uint bits = q.r | (q.g << 10) | (q.b << 20);
    return uintBitsToFloat((bits & 0x7fffffu) + (((bits >> 23) + 1u) << 23));
}

vec3 unpack_color(float packed_color) {
    uint stored = floatBitsToUint(packed_color);
    uint bits = (stored & 0x7fffffu) + (((stored >> 23) - 1u) << 23);
    vec3 c = vec3(uvec3(bits, bits >> 10, bits >> 20) & 1023u) * (1.0 / 1023.0);
    return c * c;
}

// Whether every component of v is finite, from its bits (exponent not all ones): isnan/isinf and
// comparisons involving NaN are undefined in GLSL (a compiler may assume no NaN), integer tests are not.
bool all_finite(vec3 v) {
    uvec3 exponent = floatBitsToUint(v) & 0x7f800000u;
    return all(notEqual(exponent, uvec3(0x7f800000u)));
}

// Largest radius of the ellipse {s*u + t*v : s^2 + t^2 <= 1}: sqrt of the Gram matrix's larger eigenvalue
// (u and v need not be orthogonal after a deformation).
float ellipse_max_radius(vec3 u, vec3 v) {
    float a = dot(u, u), b = dot(u, v), c = dot(v, v);
    float h = 0.5 * (a + c);
    return sqrt(h + sqrt(max(0.25 * (a - c) * (a - c) + b * b, 0.0)));
}

// Screen bounds of the perspective projection of the ellipse {c + u cos t + v sin t} (view space): the
// projected conic's bounding box, from its dual (Sigg et al. 2006, Zwicker et al. 2004). With
// s = (cos t, sin t, 1), D = diag(1, 1, -1), clip x = a.s and w = b.s, the extreme x = a.s / b.s are the
// roots of x^2 (b D b) - 2 x (a D b) + a D a = 0. Written relative to the projected centre x0 (a - x0 b has
// no third component) both terms under the root are positive: no cancellation for small, far splats.
// Returns the NDC centre of the box (xy) and the side in pixels of the square sprite centred there that
// holds it (z); z = -1 when the ellipse reaches the near plane. Sprites cover the pixels whose centres lie
// inside the square, so every pixel centre the ellipse covers is drawn (SpriteCoversExactlyItsAnalyticDisc).
// The C++ twin is ellipse_sprite() in systems/splat_render/cpu_cull.cpp.
vec3 ellipse_sprite(vec3 c, vec3 u, vec3 v) {
    float near_plane = frame.projection[3][2] / (frame.projection[2][2] - 1.0);
    vec2 z = vec2(u.z, v.z);
    if (-c.z - length(z) <= near_plane) return vec3(0.0, 0.0, -1.0);
    float q = dot(z, z) - c.z * c.z;  // b D b < 0: the rim stays in front of the eye
    vec2 x0 = vec2(frame.projection[0][0] * c.x, frame.projection[1][1] * c.y) / -c.z;
    vec2 ax = frame.projection[0][0] * vec2(u.x, v.x) + x0.x * z;
    vec2 ay = frame.projection[1][1] * vec2(u.y, v.y) + x0.y * z;
    vec2 off = vec2(dot(ax, z), dot(ay, z)) / -q;
    vec2 half_extent = sqrt(off * off + vec2(dot(ax, ax), dot(ay, ay)) / -q);
    return vec3(x0 + off, max(half_extent.x * frame.viewport.x, half_extent.y * frame.viewport.y));
}

// sRGB decode without the linear toe (below 0.04045 the two differ by < 3e-4): one pow, no select.
vec3 srgb_to_linear(vec3 c) {
    return pow((c + 0.055) * (1.0 / 1.055), vec3(2.4));
}

// View-space set-up of splat s (cloud space -> view space through frame.model_view).
struct SplatView {
    vec3 c, u, v;        // centre and axes
    vec3 shading_n;      // unit shading normal (view space)
    float r;             // largest ellipse radius
};

SplatView splat_view(GpuSplat s) {
    SplatView o;
    o.c = (frame.model_view * vec4(s.center.xyz, 1.0)).xyz;
    o.u = mat3(frame.model_view) * s.axis_u.xyz;
    o.v = mat3(frame.model_view) * s.axis_v.xyz;
    o.shading_n = normalize(mat3(frame.normal_view) * s.normal.xyz);
    o.r = ellipse_max_radius(o.u, o.v);
    return o;
}

// Ray-cast coefficients (see SplatRecord) of a splat; the plane normal is oriented like the shading normal.
void splat_raycast_setup(SplatView o, out vec4 plane, out vec4 dual_u, out vec4 dual_v) {
    vec3 n = cross(o.u, o.v);
    n = dot(n, o.shading_n) < 0.0 ? -n : n;
    vec3 du = cross(o.v, n) / dot(cross(o.v, n), o.u);
    vec3 dv = cross(n, o.u) / dot(cross(n, o.u), o.v);
    plane = vec4(n / dot(o.c, n), frame.params.x * o.r);
    dual_u = vec4(du, dot(du, o.c));
    dual_v = vec4(dv, dot(dv, o.c));
}

#endif
