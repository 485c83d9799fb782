// Shared by the compute rasteriser's passes (systems/splat_render/compute_raster.h): its buffers, the
// sprite's pixel rectangle and the per-pixel ray cast of raycast.glsl for an explicit pixel (compute shaders
// have no gl_FragCoord and no flat inputs).
#ifndef SFFD_COMPUTE_RASTER_GLSL
#define SFFD_COMPUTE_RASTER_GLSL

#include "splat_render/splat_common.glsl"
#include "splat_render/compute_raster.h"

layout(std430, binding = SFFD_SSBO_RASTER_DEPTH) buffer RasterDepth { uint raster_depth[]; };
layout(std430, binding = SFFD_SSBO_RASTER_SUMS) buffer RasterSums { uint raster_sums[]; };

// The cleared depth word: window depth 1.0 (far plane). Non-negative floats order like their bits, so
// atomicMin on the bits is a depth test.
const uint RASTER_DEPTH_CLEAR = 0x3f800000u;

uint raster_pixel(ivec2 p) { return uint(p.y) * uint(frame.viewport.x) + uint(p.x); }

// Window depth from 1 / view-axis depth: the formula of raycast.glsl's window_depth_inv (which cannot be
// included here: it declares fragment inputs).
float raster_window_depth_inv(float inv_t) {
    return 0.5 * (frame.projection[3][2] * inv_t - frame.projection[2][2]) + 0.5;
}
// View-axis depth of a window depth (its inverse).
float raster_view_depth(float window) {
    return frame.projection[3][2] / (2.0 * window - 1.0 + frame.projection[2][2]);
}

// Pixels whose centres lie inside the record's sprite square (what the rasteriser would shade for the
// point sprite: centre center.xy in NDC, side center.w pixels), clipped to the viewport: [lo, hi] inclusive.
ivec4 raster_sprite_pixels(vec4 center) {
    vec2 win = (center.xy * 0.5 + 0.5) * frame.viewport.xy;
    float h = 0.5 * center.w;
    ivec2 lo = max(ivec2(ceil(win - h - 0.5)), ivec2(0));
    ivec2 hi = min(ivec2(floor(win + h - 0.5)), ivec2(frame.viewport.xy) - 1);
    return ivec4(lo, hi);
}

// raycast_splat() of raycast.glsl for pixel p: false where the fragment shader discards (outside the
// ellipse, plane not in front, hidden record). inv_t = 1 / t, t the view-axis depth of the hit.
bool raster_raycast(SplatRecord rec, ivec2 p, out vec3 ray, out float inv_t, out float t, out vec2 st) {
    ray = vec3((vec2(p) + 0.5) * frame.ray_map.xy + frame.ray_map.zw, -1.0);
    inv_t = dot(rec.plane.xyz, ray);
    t = 0.0;
    st = vec2(0.0);
    if (inv_t <= 0.0) return false;
    t = 1.0 / inv_t;
    float s = t * dot(rec.dual_u.xyz, ray) - rec.dual_u.w;
    float q = t * dot(rec.dual_v.xyz, ray) - rec.dual_v.w;
    st = vec2(s, q);
    return s * s + q * q <= 1.0;
}

#endif
