// Buffer layouts and binding points of the Gaussian GL renderer (systems/gaussian/gl_render.h), shared
// by GLSL (#include "gaussian/gaussian_layout.h") and C++ (#include "shaders/gaussian/gaussian_layout.h").
// The passes bind their own buffers before every dispatch/draw, so these points are local to them.
#ifndef SFFD_GAUSSIAN_LAYOUT_H
#define SFFD_GAUSSIAN_LAYOUT_H

#define SFFD_GAUSS_SSBO_IN        0   // GpuGaussian[]: centre (relative to the cloud origin), rotation, scale
#define SFFD_GAUSS_SSBO_SH        1   // float[]: SH coefficients, GaussianCloud::sh layout
// The projection, written by project.comp per Gaussian, then gathered into depth order (gather.comp) and
// read by the blend (splat.vert, tile_*.comp) at the same points: three vec4 arrays. No pass reads either
// at random across the whole cloud, so every pass binds them in element ranges (gl_render: a cloud past
// GL_MAX_SHADER_STORAGE_BLOCK_SIZE is drawn range by range, front to back).
#define SFFD_GAUSS_SSBO_PROJ_CENTER 2 // vec4[]: pixel centre (x right, y DOWN, pixel (i,j) centred at
                                      // i+0.5, j+0.5), view depth, footprint radius in pixels (0 = not drawn)
#define SFFD_GAUSS_SSBO_ORDER     3   // uint[]: visible Gaussians, front to back (read by gather.comp)
#define SFFD_GAUSS_SSBO_FRAMES    4   // vec4[3] per Gaussian: columns of its SH frame (view-direction mode)
#define SFFD_GAUSS_SSBO_DEPTH     5   // uint[]: sort key of each Gaussian: floatBitsToUint(view depth) when drawn
                                      // (positive floats order like their bits), SFFD_GAUSS_NOT_DRAWN when not
#define SFFD_GAUSS_SSBO_DRAW      6   // DrawArraysIndirectCommand {4, visible count, 0, 0}, covered pixels and
                                      // their wrap flag (uint[2]), 2 uints of padding, then one command per
                                      // range of the depth-ordered arrays (uvec4 at byte 32 + 16 k: the quads'
                                      // draw of range k, written by gather.comp)
#define SFFD_GAUSS_DRAW_RANGE_COMMANDS 32  // byte offset of the per-range commands in the DRAW buffer
// gather.comp writes the depth-ordered projection here (it reads the per-Gaussian one at PROJ_*); the
// blend then binds the depth-ordered arrays at the PROJ_* points.
#define SFFD_GAUSS_SSBO_SORTED_CENTER 0
#define SFFD_GAUSS_SSBO_SORTED_CONIC  1
#define SFFD_GAUSS_SSBO_SORTED_COLOR  5
#define SFFD_GAUSS_NOT_DRAWN      0xffffffffu  // sort key of a Gaussian not drawn: after every depth
// Tile path (gl_render BlendPath::tiles): 16x16-pixel tiles, one (tile, Gaussian) entry per overlap.
#define SFFD_GAUSS_TILE           16u
#define SFFD_GAUSS_SSBO_TOUCHED   7   // uint[]: tiles touched by the p-th Gaussian in depth order, then their exclusive scan
#define SFFD_GAUSS_SSBO_TILE_KEYS 8   // uint[]: tile id of each entry (sort key)
#define SFFD_GAUSS_SSBO_TILE_VALUES 9 // uint[]: depth-order position of each entry's Gaussian (payload)
#define SFFD_GAUSS_SSBO_RANGES    10  // uvec2[tile]: the tile's entries [begin, end) after the sort
#define SFFD_GAUSS_IMAGE_COLOR    0   // image unit: rgba32f target of the tile blend (rgb premultiplied, a = 1 − T)
#define SFFD_GAUSS_IMAGE_DEPTH    1   // image unit: rgba32f Σ T α view depth (x), coverage (w) (render system)
#define SFFD_GAUSS_IMAGE_STATE    2   // image unit: rg32f, per pixel the tile blend's transmittance (x, exact:
                                      // the colour target holds 1 - T, which does not round-trip) and y: 0
                                      // untouched, 1 carried, 2 stopped (early termination). The blend runs
                                      // once per range of the depth order; each pass resumes from it
#define SFFD_GAUSS_SSBO_TILE_STATS 11 // uint: entries the tile blend's groups staged before they stopped
// The other two projection arrays share points 7 and 8 with the tile preparation's TOUCHED and TILE_KEYS:
// no program binds both (project.comp, splat.vert and tile_blend.comp read these; tile_count/emit.comp
// read the conics at SFFD_GAUSS_SSBO_TILE_CONIC), so every Gaussian program stays within GL_MAX_SHADER_STORAGE_BUFFER_BINDINGS
// and the blocks per stage runtime/gfx/limits.h requires (splat.vert: 3; project.comp: 8).
#define SFFD_GAUSS_SSBO_PROJ_CONIC 7  // vec4[]: inverse 2D covariance (a, b, c) of [[a b][b c]], opacity
#define SFFD_GAUSS_SSBO_PROJ_COLOR 8  // vec4[]: rgb from the SH, w unused
// The tile preparation (tile_count/emit.comp) reads the conics too (their pixel boxes are narrowed by
// them, footprint.glsl), at point 4: point 7 is its TOUCHED there, and FRAMES is the projection's alone.
#define SFFD_GAUSS_SSBO_TILE_CONIC 4
// The GPU deformation (shaders/gaussian/deform.comp, its own program: points 7-9 below mean something
// else there than in the tile passes) reads SFFD_GAUSS_SSBO_IN, writes SFFD_GAUSS_SSBO_DEFORMED and
// SFFD_GAUSS_SSBO_FRAMES; it also uses the ffd pass's points 2 (control points) and 6 (statistics).
#define SFFD_GAUSS_SSBO_DEFORMED  7   // GpuGaussian[]: deformed Gaussians (may be the same buffer as IN)
#define SFFD_GAUSS_SSBO_DEFORMED_SH 8 // float[]: rotated SH coefficients (ShMode::rotate_coefficients), SH layout
#define SFFD_GAUSS_SSBO_SH_TABLES 9   // float[128]: SH rotation tables (sh_sample_tables: 15 directions, A_l⁻¹)

// GpuGaussian, std430, 48 bytes:
//   vec4 pos_opacity;  // xyz centre relative to the origin, w linear opacity
//   vec4 rotation;     // unit quaternion (w, x, y, z)
//   vec4 scale;        // xyz linear standard deviations, w unused
// The projection: one vec4 per Gaussian in each of the SFFD_GAUSS_SSBO_PROJ_* arrays (std430, 16 bytes).
#define SFFD_GPU_GAUSSIAN_BYTES 48
#define SFFD_GPU_PROJECTED_ARRAYS 3
#define SFFD_GPU_PROJECTED_STRIDE 16

#ifdef __cplusplus
namespace sffd::gpu {
struct alignas(16) GpuGaussian {
    float pos_opacity[4];
    float rotation[4];
    float scale[4];
};
// One element of a projection array.
struct alignas(16) GpuProjectedVec4 {
    float v[4];
};
static_assert(sizeof(GpuGaussian) == SFFD_GPU_GAUSSIAN_BYTES);
static_assert(sizeof(GpuProjectedVec4) == SFFD_GPU_PROJECTED_STRIDE);
}  // namespace sffd::gpu
#else
struct GpuGaussian {
    vec4 pos_opacity;
    vec4 rotation;
    vec4 scale;
};
#endif

#endif
