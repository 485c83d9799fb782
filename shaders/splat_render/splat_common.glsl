// Shared by the cull compute pass and the splat vertex shaders: the view-space set-up of one splat (what
// the fragment shaders' ray cast needs) and its screen-space footprint.
#ifndef SFFD_SPLAT_COMMON_GLSL
#define SFFD_SPLAT_COMMON_GLSL

#include "common/bindings.h"
#include "splat_render/frame_block.h"
#include "splat_render/splat_record.h"

// Two halves in one float that survives any varying or store: packHalf2x16 less each half's lowest mantissa
// bit (30 bits), stored like pack_color (mantissa, exponent plus one): always normal and finite. A raw
// packHalf2x16 with a zero upper half is a denormal, which GLSL lets a driver flush to zero.
// C++ twin: pack_halves() in systems/splat_render/cpu_cull.cpp.
float pack_halves(vec2 v) {
    uint h = packHalf2x16(v);
    uint bits = ((h & 0xffffu) >> 1) | ((h >> 17) << 15);
    return uintBitsToFloat((bits & 0x7fffffu) + (((bits >> 23) + 1u) << 23));
}
vec2 unpack_halves(float packed_halves) {
    uint stored = floatBitsToUint(packed_halves);
    uint bits = (stored & 0x7fffffu) + (((stored >> 23) - 1u) << 23);
    return unpackHalf2x16(((bits & 0x7fffu) << 1) | ((bits >> 15) << 17));
}

// The uv frame of a splat as the fragment shaders read it: uv at the centre, and the uv derivatives along
// the two axes (SplatCloud::uv_axes) packed as halves (pack_halves). The derivatives are per axis, so they stay valid
// when a lattice deforms the axes: the point centre + s * axis_u + t * axis_v maps to uv + s du + t dv
// before and after (first order).
vec4 splat_uv_frame(GpuSplat s, vec4 uv_axes) {
    return vec4(s.axis_u.w, s.axis_v.w, pack_halves(uv_axes.xy), pack_halves(uv_axes.zw));
}

// Mip level of a splat's texture footprint, once per splat (GL's LOD, the larger side of the pixel's
// footprint in texels, at the splat's centre: it changes little across a splat of a few pixels). The
// attribute pass samples with it (textureLod with a flat LOD): per-fragment derivatives (textureGrad) made
// the HQ frame of the textured sphere ~1.5x slower on llvmpipe, for 51.4 instead of 51.x dB.
// d(s, t)/d(window x, y) of raycast.glsl's ray cast, at the centre: ray = (x ray_map.x + ray_map.z, ...,
// -1), t = 1 / dot(plane, ray) = -c.z there, s = t dot(dual_u, ray) - dual_u.w, so
// ds/dx = t ray_map.x (dual_u.x - plane.x dual_u.w) (s = 0). C++ twin in cpu_cull.cpp.
float splat_texture_lod(vec3 c, vec4 plane, vec4 dual_u, vec4 dual_v, vec4 uv_axes, vec2 texture_size) {
    vec2 scale = -c.z * frame.ray_map.xy;
    vec2 ds = scale * (dual_u.xy - plane.xy * dual_u.w);
    vec2 dq = scale * (dual_v.xy - plane.xy * dual_v.w);
    vec2 ddx = (ds.x * uv_axes.xy + dq.x * uv_axes.zw) * texture_size;
    vec2 ddy = (ds.y * uv_axes.xy + dq.y * uv_axes.zw) * texture_size;
    return 0.5 * log2(max(max(dot(ddx, ddx), dot(ddy, ddy)), 1e-20));
}

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

// Lighting factors (>= 0, up to 4: brighter saturates) packed like colours.
float pack_light(vec3 factor) { return pack_color(factor * 0.25); }
vec3 unpack_light(float packed_factor) { return unpack_color(packed_factor) * 4.0; }

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
    o.c = (frame.model_view * vec4(s.center, 1.0)).xyz;
    o.u = mat3(frame.model_view) * s.axis_u.xyz;
    o.v = mat3(frame.model_view) * s.axis_v.xyz;
    o.shading_n = normalize(mat3(frame.normal_view) * s.normal.xyz);
    o.r = ellipse_max_radius(o.u, o.v);
    return o;
}

// Ray-cast coefficients (see SplatRecord) of a splat; the plane normal is oriented like the shading normal.
// A splat seen edge-on (the eye in its plane, to 1e-6 of |c| |n|: far below float's rounding of c · n
// would be 6e-8) covers no area, and n / (c · n) would be infinite, every pixel's ray cast NaN: it is
// hidden as a back face is (plane.xyz = 0, splat_record.h). The CPU cull does the same (cpu_cull.cpp).
void splat_raycast_setup(SplatView o, out vec4 plane, out vec4 dual_u, out vec4 dual_v) {
    vec3 n = cross(o.u, o.v);
    n = dot(n, o.shading_n) < 0.0 ? -n : n;
    vec3 du = cross(o.v, n) / dot(cross(o.v, n), o.u);
    vec3 dv = cross(n, o.u) / dot(cross(n, o.u), o.v);
    const float cn = dot(o.c, n);
    const bool edge_on = abs(cn) <= 1e-6 * length(o.c) * length(n);
    plane = vec4(edge_on ? vec3(0.0) : n / cn, frame.params.x * o.r);
    dual_u = vec4(du, dot(du, o.c));
    dual_v = vec4(dv, dot(dv, o.c));
}

#endif
