// Shader binding points and shared buffer layouts, defined once for GLSL and C++.
// GLSL: #include "common/bindings.h" (the shader loader resolves it). C++: #include "shaders/common/bindings.h".
#ifndef SFFD_BINDINGS_H
#define SFFD_BINDINGS_H

// --- SSBO binding points --------------------------------------------------------------------------
#define SFFD_SSBO_SPLATS_IN        0   // GpuSplat[]: rest splats (authored cloud, uploaded once)
#define SFFD_SSBO_SPLATS_OUT       1   // GpuSplat[]: deformed splats written by the FFD compute pass
#define SFFD_SSBO_CONTROL_POINTS   2   // vec4[]: lattice control points (or displacements), xyz + pad
#define SFFD_SSBO_VISIBLE          3   // uint[]: indices of splats that survived culling
#define SFFD_SSBO_DRAW_INDIRECT    4   // DrawArraysIndirectCommand
#define SFFD_SSBO_SPLATS_DRAW      5   // GpuSplat[]: the buffer a render pass reads (deformed or rest)
#define SFFD_SSBO_STATS            6   // uint counters written by compute passes (e.g. inverted splats);
                                       // the deform passes' are per page (ffd/page_stats.glsl)
#define SFFD_SSBO_VISIBLE_SPLATS   7   // view-space records of visible sprite splats (splat_render cull pass)
#define SFFD_SSBO_UV_AXES          8   // vec4[]: per-splat uv derivatives along axis_u (xy) and axis_v (zw)
#define SFFD_SSBO_WEIGHTS         13   // float[]: per-point deformation weights (PointWeights), deform passes
                                       // of weighted clouds only (FFD_WEIGHTS; 9-12 are the raster's)
#define SFFD_SSBO_POINT_MARKS     14   // uint[]: per-point marks, two 16-bit marks a word (below), draw passes
#define SFFD_SSBO_PREVIEW_INDEX   15   // uint[]: the authored index of each drawn element of a preview subset

// Points per page of a cloud, as a shift (runtime/scene/point_pages.h: kPageShift, checked equal there):
// the deform passes count per page, so a dispatch over some pages leaves the others' counts as they were.
#define SFFD_PAGE_SHIFT           16

// --- UBO binding points ---------------------------------------------------------------------------
#define SFFD_UBO_FRAME             0   // camera matrices, viewport, lights
#define SFFD_UBO_FFD               1   // lattice parameters for the deformation pass
#define SFFD_UBO_FFD_CONTROL       2   // small Bernstein lattices: displacements as a UBO (uniform loads)

// --- Texture units --------------------------------------------------------------------------------
#define SFFD_TEX_MATERIAL          0
#define SFFD_TEX_ACCUM_COLOR       1
#define SFFD_TEX_ACCUM_NORMAL      2
#define SFFD_TEX_DEPTH             3
#define SFFD_TEX_ACCUM_MATERIAL    4   // splat_render: sum(w * specular), sum(w * shininess) per pixel
#define SFFD_TEX_OVERLAY_CACHE     0   // editor: the lattice overlay's cached edges (lattice_cache.frag)

// --- Uniform locations (explicit, so C++ never looks uniforms up by name) --------------------------
#define SFFD_LOC_OVERLAY_VIEW_PROJ 0   // mat4 (locations 0..3): editor lattice overlay, anchor -> clip
#define SFFD_LOC_OVERLAY_POINTS    4   // int: 1 round point sprites, 0 lines
#define SFFD_LOC_OVERLAY_PIXEL     5   // float: frame pixels per window pixel (a reduced preview: < 1)
#define SFFD_LOC_DISPLAY_SCALE     0   // vec2: splat_render display copy, window pixel -> frame pixel

// Per-point marks (runtime/gfx/point_marks.h): what the draw passes know of PointFlags and PointWeights
// (runtime/scene/point_columns.h), one 16-bit mark a point, point j in bits 16 (j & 1) .. of word j >> 1:
//   bits 0..7   the PointFlags byte (SFFD_MARK_SELECTED, SFFD_MARK_HIDDEN, SFFD_MARK_DELETED)
//   bits 8..15  the weight as unorm8 (255: weight 1, also for a cloud without weights)
// The draw passes read them only when their mode says so (a uint of bits below: FrameBlock counts.z for
// surface splats, a uniform for Gaussians): a cloud without marks binds no marks buffer and reads none.
#define SFFD_MARK_SELECTED         1u
#define SFFD_MARK_HIDDEN           2u
#define SFFD_MARK_DELETED          4u
#define SFFD_MARK_GONE             6u  // hidden or deleted: never drawn
#define SFFD_MARKS_PRESENT         1u  // mode: the marks buffer is bound; gone points are not drawn
#define SFFD_MARKS_INDEXED         2u  // mode: drawn element i is point preview_index[i] (a preview subset)
#define SFFD_MARKS_SELECTION       4u  // mode: selected points are drawn tinted (mark_overlay)
#define SFFD_MARKS_WEIGHTS         8u  // mode: every point is drawn in the weight ramp's colour
#define SFFD_MARKS_TEXEL          16u  // mode: a textured cloud drawn flat under an overlay: each splat's
                                       // colour is its texel at its centre's uv (level 0, bilinear)

// GpuSplat, std430, 64 bytes; the same layout for rest and deformed splats, so a render pass reads
// either one. Positions are relative to the cloud's origin (SplatCloud::origin).
//   vec3 center;   // position
//   uint color;    // RGBA8 (packUnorm4x8's layout; 0xffffffff: uncoloured). A uint in GLSL, not the float
//                  // slot's bits: as a float most colours are NaNs, infinities or denormals, which a
//                  // driver may canonicalise or flush on the way through a shader. C++: center[3]
//   vec4 normal;   // xyz unit normal; w = 1 (0 marks a splat flipped by an inverted lattice cell)
//   vec4 axis_u;   // xyz tangent axis scaled by its radius; w = texture u
//   vec4 axis_v;   // xyz bitangent axis scaled by its radius; w = texture v
#define SFFD_GPU_SPLAT_BYTES 64

#ifdef __cplusplus
namespace sffd::gpu {
struct alignas(16) GpuSplat {
    float center[4];
    float normal[4];
    float axis_u[4];
    float axis_v[4];
};
static_assert(sizeof(GpuSplat) == SFFD_GPU_SPLAT_BYTES);
}  // namespace sffd::gpu
#else
struct GpuSplat {
    vec3 center;
    uint color;
    vec4 normal;
    vec4 axis_u;
    vec4 axis_v;
};
#endif

#endif  // SFFD_BINDINGS_H
