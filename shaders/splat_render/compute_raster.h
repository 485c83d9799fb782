// Constants and bindings of the compute splat rasteriser (systems/splat_render/compute_raster.h), shared by
// GLSL (compute_*.comp, compute_*.frag) and C++ like splat_record.h. Owned by systems/splat_render.
// GLSL: #include "splat_render/compute_raster.h". C++: #include "shaders/splat_render/compute_raster.h".
#ifndef SFFD_COMPUTE_RASTER_H
#define SFFD_COMPUTE_RASTER_H

// SSBO bindings of the compute rasteriser's own buffers (common/bindings.h owns 0..8; these passes also
// bind SFFD_SSBO_VISIBLE_SPLATS and SFFD_SSBO_DRAW_INDIRECT from there).
#define SFFD_SSBO_RASTER_DEPTH         9   // uint[w*h]: per-pixel min window depth (float bits), compute sprites
#define SFFD_SSBO_RASTER_SUMS         10   // uint[w*h*8]: per-pixel fixed-point attribute sums (below)
#define SFFD_SSBO_RASTER_BIG          11   // uint[2 capacity]: record indices of sprites left to the rasteriser
#define SFFD_SSBO_RASTER_BIG_COMMANDS 12   // two DrawElementsIndirectCommands over RASTER_BIG
// uint[G + 1] per record list: compute_visibility.comp's large sprites per work group, then their scan (the
// stats binding of common/bindings.h, which these passes do not use)
#define SFFD_SSBO_RASTER_GROUPS        6

// local_size_x of compute_visibility.comp and compute_attribute.comp (one invocation per sprite record).
#define SFFD_RASTER_GROUP_SIZE 64

// Sprites whose side (SplatRecord::center.w, pixels) exceeds this go to the raster path in the same frame
// (hybrid): one invocation walks every pixel of its sprite, so a large splat would serialise its work.
#define SFFD_RASTER_MAX_SPRITE 8.0

// Fixed-point attribute sums, 9 uints per pixel: sum(w r), sum(w g), sum(w b), sum(w), sum(w (n + 1) / 2)
// xyz, then sum(w f) with f = (R - t) / R in [0, 1] (t: the fragment's view-axis depth, R: the pixel's
// compute-visibility depth as a view-axis depth; t <= R for every fragment that passes the depth test) as
// two words, its integer and its fractional part times 2^16 (w f is mostly far below 1: one word would round
// it away at low-weight rim pixels; two words keep 2^-16 of a weight unit).
// Every word adds at most ONE per contribution: each term is w_q * x with x in [0, 1] and
// w_q = max(1, round(min(w, 1) * ONE)) <= ONE, the fractional word at most 2^16. So a pixel holds up to
// floor((2^32 - 1) / ONE) = 65,535 contributions without overflow. A contribution is a splat whose ellipse
// holds the pixel centre within eps of the visible depth: about the surface's overlap (2-4 for the test
// spheres), never the number of splats inside the pixel.
#define SFFD_RASTER_FIXED_ONE 65536.0
#define SFFD_RASTER_SUM_WORDS 9
#define SFFD_RASTER_MAX_CONTRIBUTIONS 65535

#endif  // SFFD_COMPUTE_RASTER_H
