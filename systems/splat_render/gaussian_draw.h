// The drawing of 3D Gaussians (GL 4.5): what the render system's Gaussian pass (gaussian_pass.h) runs for
// each cloud, from the buffers the residency keeps (gaussian::GpuGaussians: draw_buffer(), sh_buffer(),
// frames; this renderer uploads no cloud). One draw (draw_gaussians):
//   1. project (shaders/splat_render/gaussian/project.comp): EWA conic, SH colour, a sortable depth key per
//   Gaussian
//      (0xffffffff when not drawn: behind the near plane, opacity below 1/255, degenerate, or its pixel
//      box off the image: culled before the sort),
//      and the drawn count accumulated on the GPU into an indirect draw command; the projection is
//      stored as three vec4 arrays (centre, conic, colour: 16 bytes a Gaussian per storage block);
//   2. depth sort (SortPath): a stable GPU radix sort of (key, index) (runtime/gfx/radix_sort.h; no
//      readback, the drawn Gaussians come first; the indices from sort_payload.comp), or the keys read
//      back and sorted on the CPU (TBB); then the projection gathered into depth order (gather.comp),
//      which the blend reads sequentially, so it can be bound and drawn in element ranges;
//   3. blend front to back (BlendPath) into an RGBA32F target: instanced quads over the reference's
//      pixel boxes (splat.{vert,frag}, hardware blending, drawn through the indirect command), or the
//      3DGS tile renderer in compute (tile_*.comp: (tile, Gaussian) entries in depth order, a stable
//      radix sort by tile id, per-tile ranges, a 16x16 group per tile with early termination);
//      draw_gaussians takes the quads unless the cloud covers too many pixels for them
//      (quad_coverage_budget(), measured by the projection), then the tiles.
// The images match the CPU reference renderer (reference_render.h: same conventions, same pixel boxes)
// within the PSNR the GL test states; both sort paths give identical images. Every pass binds the
// per-Gaussian buffers in element ranges within GL_MAX_SHADER_STORAGE_BLOCK_SIZE (one range when they fit,
// the same loops): the image is the same, bit for bit, however many ranges a cloud takes.
// Owns its per-draw GL objects (move-only); create and use it with a GL context current, destroy it before
// the context.
#pragma once

#include <cstdint>
#include <vector>

#include "runtime/core/result.h"
#include "runtime/gfx/gl_object.h"
#include "runtime/gfx/radix_sort.h"
#include "runtime/scene/components.h"
#include "systems/gaussian/gpu_store.h"

namespace sffd::render {

// Which depth sort a frame uses. automatic: the GPU sort on hardware GPUs; on a software rasterizer
// (gfx::software_rasterizer(): llvmpipe) the faster one there, see gpu_sort_preferred().
enum class SortPath { automatic, cpu, gpu };
// How the sorted Gaussians are blended: instanced quads (raster blending) or the compute tile renderer.
// As GlRenderer::blend_path, `tiles` makes draw_gaussians take the tile renderer whenever it is given
// TileTargets, whatever the coverage; `quads` leaves the choice to the coverage budget.
enum class BlendPath { quads, tiles };

// Quad blending has no early termination (fixed-function blending cannot stop a pixel at saturated
// alpha on every GL 4.5 implementation), so its fragment work is the screen area the Gaussians cover:
// 20,000 screen-filling Gaussians are 6e9 fragments at 640x480. draw_gaussians() sums that area (the
// pixel boxes clipped to the image) during the projection and, past this many images, blends the cloud
// with the tile renderer instead, which stops each pixel at transmittance 1e-4 and each tile once all of
// its pixels have (its preparation is per covered 16x16 tile, up to 256 times less than per pixel).
// On a software rasterizer, 128 images keep dense test scenes on the quads (3,000 random Gaussians at
// 200x150 cover ~63) and bound a quad frame at 640x480 to 39M fragments (llvmpipe here: about 110M
// fragments per CPU second).
inline constexpr std::uint64_t kQuadCoverageBudget = 128;
// On a hardware GPU the quads are bound by its blending units, which compute-oriented GPUs have few of.
// NVIDIA H100 (bench_gaussian_gl, 1200x797, GPU sort; counters covered_images and blend_ms): quads blend
// 2-3.5G fragments/s, so 23 images took 10.6 ms against 1.0 ms for the tiles, 71 images 26.6 against
// 3.2 ms, 401 images 112 against 35 ms; the tiles' fixed cost (counts, scan, sort) is under a
// millisecond there, so they win past about 3 images. 4 images: a GPU with several times the blending
// rate loses at most a fraction of a millisecond to the tiles between 4 images and its own break-even.
inline constexpr std::uint64_t kQuadCoverageBudgetHardware = 4;
// The budget draw_gaussians() applies, in images of the view's size: kQuadCoverageBudget on a software
// rasterizer (gfx::software_rasterizer()), kQuadCoverageBudgetHardware on a hardware GPU.
constexpr std::uint64_t quad_coverage_budget(bool software) {
    return software ? kQuadCoverageBudget : kQuadCoverageBudgetHardware;
}
// The tile path's entry buffers: 8 bytes per (tile, Gaussian) entry, 2 GiB at most.
inline constexpr std::uint64_t kMaxTileEntries = std::uint64_t(1) << 28;

// Where draw_gaussians() blends a cloud it routes to the tile renderer: the render system's accumulation
// targets, blended into (the same result as its quads, gaussian_accum.frag).
struct TileTargets {
    GLuint color = 0;           // RGBA32F: premultiplied colour, coverage (read and written)
    GLuint depth_sum = 0;       // RGBA32F: Σ T α view depth (x), coverage (w); 0: none
    GLuint surface_depth = 0;   // depth texture: a Gaussian is hidden where it is <= the Gaussian's
                                // window depth (the quads' GL_LESS test); 0: no test
    int width = 1, height = 1;  // set by draw_gaussians from the view
    glm::dvec2 ndc_depth{0.0};  // set by draw_gaussians from the view (GaussianView::ndc_depth)
};

// Tile blends since reset_tile_stats(): (tile, Gaussian) entries prepared, and entries the tile groups
// staged before every pixel of their tile stopped (the blending work early termination left).
struct TileStats {
    std::uint64_t entries = 0;
    std::uint64_t staged = 0;
};

struct GlRenderer {
    gfx::Program project;
    gfx::Program splat;
    gfx::Program tile_count, tile_emit, tile_ranges, tile_blend;
    gfx::Program sort_payload;  // the GPU sort's payloads (indices), its own pass (sort_payload.comp)
    gfx::Program gather;        // the projection into depth order (gather.comp)
    gfx::Program marks;         // gone Gaussians out, overlay colours in (marks.comp), clouds with marks
    gfx::RadixSorter sorter;
    gfx::VertexArray vao;  // the quads: no attributes (instances index the depth-ordered arrays)
    gfx::Buffer order, depth;
    // The projection, three vec4 arrays (gaussian_layout.h: SFFD_GAUSS_SSBO_PROJ_*) per Gaussian, and the
    // same gathered into depth order for the blend. Every pass binds them in element ranges of at most
    // GL_MAX_SHADER_STORAGE_BLOCK_SIZE (blend_ranges() in gaussian_draw.cpp): no cloud needs one block for
    // all.
    gfx::Buffer proj_center, proj_conic, proj_color;
    gfx::Buffer sorted_center, sorted_conic, sorted_color;
    // DrawArraysIndirectCommand (its instance count is the drawn count, written on the GPU), the covered
    // pixels, then one command per range of the depth-ordered arrays (gaussian_layout.h).
    gfx::Buffer draw;
    std::size_t draw_ranges = 0;  // range commands `draw` holds
    gfx::Texture tile_state;      // rg32f: the tile blend's transmittance and stop, range to range
    int tile_state_width = 0, tile_state_height = 0;
    bool tile_fallback_warned = false;  // draw_gaussians said once why a cloud took the quads,
    bool sort_fallback_warned = false;  // or the CPU sort
    gfx::Buffer tile_touched, tile_keys, tile_values, tile_ranges_buffer;  // tile path, grow-only
    gfx::Buffer tile_stats;                // uint: entries staged by the tile blend (TileStats::staged)
    std::uint64_t tile_entries_total = 0;  // TileStats::entries
    std::uint64_t tile_entry_capacity = 0, tile_ranges_buffer_tiles = 0;
    SortPath sort_path = SortPath::automatic;
    BlendPath blend_path = BlendPath::quads;
    bool software = false;  // gfx::software_rasterizer() when created
    // Benchmarks: glFinish after each stage so that the stage wall times below mean something (GL timer
    // queries do not on llvmpipe: 0 ms for compute, nonsense for draws). Off: no extra waits.
    bool stage_timing = false;
    // Last frame: which sort ran; stage wall times in ms (with stage_timing; sort_ms of the CPU path is
    // always measured: key readback, which waits for the projection, + sort + upload); (tile path) the
    // number of (tile, Gaussian) entries.
    bool gpu_sort_used = false;
    // blend_ms includes, on the tile path, tile_prepare_ms: tile counts, scan, entries, their sort, ranges.
    double project_ms = 0.0, sort_ms = 0.0, blend_ms = 0.0, tile_prepare_ms = 0.0;
    std::uint64_t tile_entries = 0;
    // Last draw_gaussians(): the pixels its Gaussians' clipped pixel boxes cover (UINT64_MAX past 2^32;
    // measured only when it was given TileTargets), and the blend it used.
    std::uint64_t covered_pixels = 0;
    BlendPath last_blend = BlendPath::quads;
    // Work groups per row of every 1D dispatch (projection, GPU sort blocks, tile passes). GL guarantees
    // only 65,535 groups per dimension (64 × 65,535 = 4.19M Gaussians), so larger clouds are dispatched
    // as a 2D grid; tests lower this to exercise the grid with small clouds.
    unsigned max_groups_x = 65535;
    std::size_t scratch = 0;  // Gaussians the per-draw buffers (projection, depth keys) hold
};

// What one draw reads: a resident cloud's GPU buffers (systems/gaussian/gpu_store.h: draw_buffer(),
// sh_buffer(), frames; gaussian_buffers() below), drawn without copying them.
struct GaussianBuffers {
    GLuint gaussians = 0;  // GpuGaussian[count] (shaders/gaussian/gaussian_layout.h)
    GLuint sh = 0;         // float[count * K * 3]
    GLuint frames = 0;     // vec4[3 * count], read when has_frames
    std::size_t count = 0;
    int sh_degree = 0;
    bool has_frames = false;
    // Point marks (runtime/gfx/point_marks.h): the residency's buffers (0: none) and the mode bits
    // (SFFD_MARKS_*: gone Gaussians not drawn, overlays; 0: the marks pass does not run).
    GLuint marks = 0, preview_index = 0;
    std::uint32_t marks_mode = 0;
};

// The camera of one draw, in the cloud's coordinates.
struct GaussianView {
    glm::dmat4 view{1.0};  // cloud coordinates (relative to the cloud origin) -> camera, composed in double
    glm::dvec3 eye{0.0};   // camera position in cloud coordinates (view direction of the SH)
    double fov_y_degrees = 45.0;
    double near_plane = 0.01;
    int width = 1, height = 1;
    // NDC depth of a splat quad, z = ndc_depth.x + ndc_depth.y / view_depth (a perspective projection's
    // -P[2][2] and P[3][2]), clamped below the far plane; (0, 0): every quad at z = 0 (no depth test).
    glm::dvec2 ndc_depth{0.0};
    // Gaussians whose projected 3σ radius, before the 0.3 px² low-pass, is below this are not drawn (a
    // preview while moving drops the sub-pixel ones: fewer to sort and blend). 0: all are drawn.
    float min_footprint_px = 0.0f;
};

// One cloud: projection, front-to-back order of the visible Gaussians, and the instanced splat quads
// blended front to back (GL_ONE_MINUS_DST_ALPHA, GL_ONE) into the framebuffer bound now, through the
// viewport the caller set. Depth test state is the caller's (the render system tests against the surface
// splats' depth); `splat_program` replaces the renderer's splat program (same vertex shader, its own
// fragment shader), null: the renderer's. With `tiles`, a cloud covering more than kQuadCoverageBudget
// images is blended by the tile renderer into those targets instead (last_blend says which).
// Per-Gaussian buffers past GL_MAX_SHADER_STORAGE_BLOCK_SIZE are bound in element ranges, the blend run
// range by range of the depth order (front to back: the image does not depend on the ranges). Buffers
// that cannot be cut are checked and the frame takes another way, logged once naming the buffer and the
// limit: the GPU sort's keys (sorted on the CPU instead) and the tile path's counts and entries (the
// quads instead). Refused before anything is drawn, naming the limit, only when not one aligned range
// of Gaussians fits a block.
Status draw_gaussians(GlRenderer& renderer, const GaussianBuffers& buffers, const GaussianView& view,
                      const gfx::Program* splat_program = nullptr, const TileTargets* tiles = nullptr);
// The pixels the last projection's Gaussians cover (their pixel boxes clipped to the image, summed;
// UINT64_MAX past 2^32): the quads' fragment work that draw_gaussians() weighs against
// quad_coverage_budget(). Reads 8 bytes back: waits for the projection.
std::uint64_t read_covered_pixels(const GlRenderer& renderer);
void reset_tile_stats(GlRenderer& renderer);
// Reads the staged count back (a sync): call it when the numbers are wanted, not every frame.
TileStats tile_stats(const GlRenderer& renderer);
// What draw_gaussians reads of a resident cloud now (its drawn count, SH degree and buffers as the
// residency's state says).
GaussianBuffers gaussian_buffers(const gaussian::GpuGaussians& gpu);

// Compiles the programs (errors name the shader file and line).
Result<GlRenderer> create_gl_renderer();

// The sort SortPath::automatic picks: the GPU sort except on a software rasterizer, at any cloud size
// (see gaussian_draw.cpp for the llvmpipe measurements behind it).
bool gpu_sort_preferred(const GlRenderer& renderer);

}  // namespace sffd::render
