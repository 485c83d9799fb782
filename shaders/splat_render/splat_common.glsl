// Shared by the cull compute pass and the splat vertex shaders: the view-space set-up of one splat (what
// the fragment shaders' ray cast needs) and its screen-space footprint.
#ifndef SFFD_SPLAT_COMMON_GLSL
#define SFFD_SPLAT_COMMON_GLSL

#include "common/bindings.h"
#include "splat_render/frame_block.h"

// A visible sprite splat, prepared by the cull pass so the vertex shaders of both HQ passes only copy it
// (llvmpipe spends its time per primitive: vertex work runs once, in the compute pass). std430, 96 bytes,
// bound as a vertex buffer. The ray through a pixel is d = (x, y, -1) in view space; the ray cast is
// linear in d:
//   t = 1 / dot(plane.xyz, d)                     view-axis depth of the hit p = t * d
//   s = t * dot(dual_u.xyz, d) - dual_u.w,  q = t * dot(dual_v.xyz, d) - dual_v.w,  inside: s^2 + q^2 <= 1
// plane.xyz = NaN marks a back-facing splat kept with culling off (every fragment discards).
// Colour travels packed (10-10-10 bits of sqrt(linear rgb)) so that, with the normal, every pass hands at
// most four vec4 varyings per sprite to the rasteriser (each costs per-primitive set-up on llvmpipe).
struct SplatRecord {
    vec4 center;   // xy: NDC centre of the sprite (ellipse_sprite), z: view-space z of the splat centre,
                   // w: sprite side in pixels
    vec4 plane;    // xyz: plane normal / dot(center, normal), w: visibility offset eps (view units)
    vec4 dual_u;   // xyz: dual axis (s = dot(dual_u, p - center)), w: dot(dual_u, center)
    vec4 dual_v;
    vec4 normal;   // xyz world-space shading normal, w: packed colour (pack_color; HQ albedo, preview lit)
    vec4 uv;       // textured clouds: xy uv at the centre, z / w: packHalf2x16 of the uv derivatives along
                   // axis_u / axis_v (splat_uv_frame); the HQ attribute pass samples the texture per pixel
};
// Textured clouds sample the texture per pixel, so some slots change meaning:
//   HQ (unlit records):   normal.w = mip level (splat_texture_lod)
//   preview (lit):        normal.w = pack_light(diffuse factor), plane.w = pack_light(specular term) (the
//                         preview has no visibility pass, so no eps), center.z = mip level
// (pixel colour = texture * diffuse + specular: splat_light_factors).


// The uv frame of a splat as the fragment shaders read it: uv at the centre, and the uv derivatives along
// the two axes (SplatCloud::uv_axes) packed as halves. The derivatives are per axis, so they stay valid
// when a lattice deforms the axes: the point centre + s * axis_u + t * axis_v maps to uv + s du + t dv
// before and after (first order).
vec4 splat_uv_frame(GpuSplat s, vec4 uv_axes) {
    return vec4(s.axis_u.w, s.axis_v.w, uintBitsToFloat(packHalf2x16(uv_axes.xy)), uintBitsToFloat(packHalf2x16(uv_axes.zw)));
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

float pack_color(vec3 linear) {
    uvec3 q = uvec3(round(sqrt(clamp(linear, 0.0, 1.0)) * 1023.0));
    return uintBitsToFloat(q.r | (q.g << 10) | (q.b << 20));
}

vec3 unpack_color(float packed_color) {
    uint bits = floatBitsToUint(packed_color);
    vec3 c = vec3(uvec3(bits, bits >> 10, bits >> 20) & 1023u) * (1.0 / 1023.0);
    return c * c;
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
