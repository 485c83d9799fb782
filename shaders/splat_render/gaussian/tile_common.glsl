// Tile range of a projected Gaussian (gl_render's tile path): the tiles its pixel box
// floor(c − h) .. ceil(c + h) (y down; h the half-size of footprint.glsl, at most the reference's 3σ
// radius) covers after clipping to the image. Needs u_size (vec2) declared by the including shader.
#ifndef SFFD_GAUSS_TILE_COMMON_GLSL
#define SFFD_GAUSS_TILE_COMMON_GLSL

#include "splat_render/gaussian/footprint.glsl"

// Inclusive pixel box clipped to the image: (x0, y0, x1, y1); empty when x0 > x1 or y0 > y1. Clamped
// in float on both sides before the conversion, since a float outside int's range converts to an
// undefined value: a box wholly past one side of the image (should the projection ever pass one)
// comes out empty, never wrapped into a huge one.
ivec4 pixel_box(vec4 center_depth_radius, vec4 conic_opacity) {
    const vec2 c = center_depth_radius.xy;
    const vec2 h = footprint_half_size(center_depth_radius.w, conic_opacity);
    const ivec2 lo = ivec2(clamp(floor(c - h), vec2(0.0), u_size));
    const ivec2 hi = ivec2(clamp(ceil(c + h), vec2(-1.0), u_size - 1.0));
    return ivec4(lo, hi);
}

// Inclusive tile rectangle (tx0, ty0, tx1, ty1) of a non-empty pixel box.
uvec4 tile_rect(ivec4 box) { return uvec4(box) / SFFD_GAUSS_TILE; }

#endif
