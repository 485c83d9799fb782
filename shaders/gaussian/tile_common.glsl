// Tile range of a projected Gaussian (gl_render's tile path): the tiles its pixel box
// floor(c − r) .. ceil(c + r) (y down; the reference's box) covers after clipping to the image.
// Needs u_size (vec2) and u_tiles (uvec2: tiles per row, rows) declared by the including shader.
#ifndef SFFD_GAUSS_TILE_COMMON_GLSL
#define SFFD_GAUSS_TILE_COMMON_GLSL

// Inclusive pixel box clipped to the image: (x0, y0, x1, y1); empty when x0 > x1 or y0 > y1.
ivec4 pixel_box(vec4 center_depth_radius) {
    const vec2 c = center_depth_radius.xy;
    const float r = center_depth_radius.w;
    const ivec2 lo = ivec2(max(floor(c - r), vec2(0.0)));
    const ivec2 hi = ivec2(min(ceil(c + r), u_size - 1.0));
    return ivec4(lo, hi);
}

// Inclusive tile rectangle (tx0, ty0, tx1, ty1) of a non-empty pixel box.
uvec4 tile_rect(ivec4 box) { return uvec4(box) / SFFD_GAUSS_TILE; }

#endif
