#version 450
// Compute rasteriser, pass 2 (attributes): the sprites pass 1 kept, ray-cast again at every pixel of their
// square; where the true depth passes the visibility depth test (LEQUAL against the depth target, which by
// now holds the minimum of both paths' visibility depths), the weighted attributes of attribute.frag are
// added with atomicAdd as fixed-point words (SFFD_RASTER_FIXED_ONE; compute_raster.h states the overflow
// bound). Only pixels inside u_rect (the screen rectangle the accumulation and shading are scissored to) with
// a visible depth < 1 are written, so the resolve pass, which runs exactly there, reads and re-zeroes every
// word this pass touched. TEXTURED 1: the colour is the material texture at the pixel's uv (attribute.frag).
#include "splat_render/compute_raster.glsl"

layout(local_size_x = SFFD_RASTER_GROUP_SIZE) in;
#include "common/dispatch.glsl"

layout(std430, binding = SFFD_SSBO_VISIBLE_SPLATS) readonly buffer Records { SplatRecord records[]; };
layout(std430, binding = SFFD_SSBO_DRAW_INDIRECT) readonly buffer Commands { uint commands[]; };
layout(binding = SFFD_TEX_DEPTH) uniform sampler2D visible_depth;
#if TEXTURED
layout(binding = SFFD_TEX_MATERIAL) uniform sampler2D material_texture;
#endif
layout(location = 0) uniform uvec4 u_list;  // compute_visibility.comp
layout(location = 1) uniform ivec4 u_rect;  // x0, y0, x1, y1 (exclusive)

void main() {
    uint i = sffd_dispatch_index();
    if (i >= commands[u_list.y]) return;
    SplatRecord rec = records[u_list.x + i];
    if (rec.center.w > SFFD_RASTER_MAX_SPRITE) return;  // drawn by the raster path
    ivec4 box = raster_sprite_pixels(rec.center);
    box.xy = max(box.xy, u_rect.xy);
    box.zw = min(box.zw, u_rect.zw - 1);
    vec3 n01 = clamp(rec.normal.xyz * 0.5 + 0.5, 0.0, 1.0);
#if TEXTURED
    vec2 du = unpack_halves(rec.uv.z), dv = unpack_halves(rec.uv.w);
#else
    vec3 albedo = clamp(unpack_color(rec.normal.w), 0.0, 1.0);
#endif
    for (int y = box.y; y <= box.w; ++y)
        for (int x = box.x; x <= box.z; ++x) {
            vec3 ray;
            float inv_t, t;
            vec2 st;
            if (!raster_raycast(rec, ivec2(x, y), ray, inv_t, t, st)) continue;
            float visible = texelFetch(visible_depth, ivec2(x, y), 0).r;
            if (visible >= 1.0 || raster_window_depth_inv(inv_t) > visible) continue;
            float r2 = dot(st, st);
            float w = min((1.0 - r2) * (1.0 - r2) + 1e-6, 1.0);
#if TEXTURED
            vec3 albedo = clamp(textureLod(material_texture, rec.uv.xy + st.x * du + st.y * dv, rec.normal.w).rgb, 0.0, 1.0);
#endif
            uint p = raster_pixel(ivec2(x, y));
            // Depth relative to the pixel's compute-visibility depth R (t <= R up to rounding): in [0, 1].
            float R = raster_view_depth(uintBitsToFloat(raster_depth[p]));
            float f = clamp((R - t) / R, 0.0, 1.0);
            float wq = max(1.0, floor(w * SFFD_RASTER_FIXED_ONE + 0.5));
            uint base = p * uint(SFFD_RASTER_SUM_WORDS);
            atomicAdd(raster_sums[base + 0u], uint(wq * albedo.r + 0.5));
            atomicAdd(raster_sums[base + 1u], uint(wq * albedo.g + 0.5));
            atomicAdd(raster_sums[base + 2u], uint(wq * albedo.b + 0.5));
            atomicAdd(raster_sums[base + 3u], uint(wq));
            atomicAdd(raster_sums[base + 4u], uint(wq * n01.x + 0.5));
            atomicAdd(raster_sums[base + 5u], uint(wq * n01.y + 0.5));
            atomicAdd(raster_sums[base + 6u], uint(wq * n01.z + 0.5));
            float wf = wq * f;  // <= ONE
            float whole = floor(wf);
            atomicAdd(raster_sums[base + 7u], uint(whole));
            atomicAdd(raster_sums[base + 8u], uint((wf - whole) * 65536.0 + 0.5));
        }
}
