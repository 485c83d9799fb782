// Compute-shader splat rasteriser for the HQ passes: Botsch et al. 2005's visibility / attribute /
// normalise passes done by compute shaders with 32-bit atomics, after Schuetz, Kerbl and Wimmer 2021
// ("Rendering point clouds with compute shaders and vertex order optimization"), for clouds whose splats are
// a few pixels or less on screen. Only core GL 4.5: no 64-bit atomics (the paper packs depth and colour in
// one 64-bit word; here depth and attributes are separate passes, like Botsch's).
//
// It consumes the cull pass's sprite records (either cull path) and shares everything after accumulation
// with the raster path (shade.frag, textures, display, capture):
//   1. visibility (compute_visibility.comp): per record with a sprite side <= SFFD_RASTER_MAX_SPRITE px,
//      ray-cast each pixel of its square, atomicMin of the eps-pushed window depth into `depth` (uint per
//      pixel); larger sprites are appended to the cloud's `big` index list (hybrid).
//   2. the raster visibility pass draws the big sprites (glDrawElementsIndirect over `big`) and the quads;
//      merge (compute_merge.frag) copies `depth` into the depth target with depth test LESS: both paths'
//      minimum.
//   3. the raster attribute pass blends the big sprites and quads; compute_attribute.comp adds the small
//      sprites' weighted attributes as fixed-point words into `sums` (compute_raster.h: layout, overflow
//      bound); resolve (compute_resolve.frag) adds them, as floats, to the accumulation targets and zeroes
//      the words. Then shade.frag as usual.
// Frames with clouds of different materials (a per-pixel blended specular/shininess target) stay on the
// raster path.
//
// Who owns what: ComputeRaster (programs, per-pixel buffers) lives in SplatRenderState; ComputeRasterCloud
// (big list and its draw commands) in the renderer's per-cloud objects. Nothing here reads anything back.
#pragma once

#include <array>
#include <cstdint>
#include <span>

#include <glm/glm.hpp>

#include "runtime/core/result.h"
#include "runtime/gfx/gl_object.h"
#include "runtime/gfx/radix_sort.h"
#include "runtime/scene/components.h"

namespace sffd::render {

// Per cloud: the sprites the compute rasteriser leaves to the rasteriser this frame.
struct ComputeRasterCloud {
    gfx::Buffer big;  // uint[2 capacity]: record indices; [0, capacity) from the sprite list,
                      // [capacity, 2 capacity) from the flat-coloured list (values = record indices)
    gfx::Buffer
        commands;  // two DrawElementsIndirectCommands over `big`: {n, 1, 0, 0, 0}, {n, 1, capacity, 0, 0}
    std::array<gfx::Buffer, 2> groups;  // per list: large sprites per work group, then their scan (G + 1)
    std::uint32_t capacity = 0;
};

// Renderer-wide: programs (compiled on first use) and the per-pixel words.
struct ComputeRaster {
    gfx::Program visibility;
    std::array<gfx::Program, 2> attribute;  // [textured]
    gfx::Program merge, resolve;
    gfx::Buffer depth;  // uint[w h]: window depth bits, cleared to 1.0 every frame
    gfx::Buffer sums;   // uint[w h 8]: zero between frames (the resolve pass re-zeroes what it reads)
    int width = 0, height = 0;
};

// RasterPath::automatic takes the compute rasteriser when the drawn splats' mean on-screen diameter
// (splat_footprint_px, weighted by splat count) is at most this many pixels. Software rasterizer (llvmpipe,
// bench_raster_path on a quiet machine, RESULTS.md): compute 1.08x faster at 1.7 px (1M-splat sphere: 147
// vs 159 ms), 1.13x slower at 2.1 px (600k: bench_render's HQ row, 124 vs 110 ms), 1.85x slower at 3.3 px
// (250k) and 2x at 6.7 px (59,650). (Runs on the machine loaded by other builds had put the break-even near
// 3 px: llvmpipe's raster threads suffer more from the load.) Hardware GPU (NVIDIA H200,
// bench_raster_break_even, HQ at 1280x720): compute 3.6-4.8x faster at 1 px, 2.4x at 2 px, 1.9x at 3 px,
// 1.7x at 4 px, 1.13x at 6 px, then 0.89-0.92x at 8 px and 0.90-0.96x from 12 to 24 px: the largest
// footprint measured still at >= 1 is 6 px. An NVIDIA H100 gives the same threshold: 3.4-4.4x at 1 px,
// 2.3-2.4x at 2 px, 1.9x at 3 px, 1.7x at 4 px, 1.12-1.15x at 6 px, 0.88-0.91x at 8 px, 0.89-0.93x from 12
// to 24 px.
inline constexpr double compute_raster_software_max_footprint = 1.8;
inline constexpr double compute_raster_hardware_max_footprint = 6.0;

// One cloud's inputs for a frame (the cull pass's outputs; buffers owned by the renderer).
struct ComputeRasterDraw {
    ComputeRasterCloud* cloud = nullptr;
    GLuint frame_ubo = 0;
    GLuint records = 0;       // SplatRecord[2 capacity] (splat_record.h)
    GLuint commands = 0;      // the cull's three DrawArraysIndirectCommands (counts in words 0 and 8)
    GLuint texture = 0;       // material texture (0: untextured)
    std::uint32_t count = 0;  // splats of the cloud: an upper bound of each list's length
    std::uint32_t capacity = 0;
    bool flat_list = false;  // the CPU cull filled the flat-coloured list (textured clouds)
};

// Compiles the programs once (shader errors as a Status naming the file).
Status init_compute_raster(ComputeRaster& raster);

// The per-cloud objects for a record capacity (reallocated when it grows).
void ensure_compute_raster_cloud(ComputeRasterCloud& cloud, std::uint32_t capacity);

// Pass 1 for every cloud: clears the depth words (and sizes them for w x h), resets each cloud's big lists,
// dispatches compute_visibility.comp per record list.
void compute_raster_visibility(ComputeRaster& raster, gfx::RadixSorter& scan,
                               std::span<const ComputeRasterDraw> draws, int width, int height);

// After the raster visibility pass, with the depth-only framebuffer bound and depth test LESS, writes on:
// the compute depths into the depth target (inside the current scissor/viewport).
void compute_raster_merge(const ComputeRaster& raster, GLuint frame_ubo);

// Pass 2 for every cloud: the fixed-point sums of the pixels inside `rect` (x, y, width, height).
void compute_raster_attribute(const ComputeRaster& raster, std::span<const ComputeRasterDraw> draws,
                              const glm::ivec4& rect, GLuint depth_texture);

// Pass 3, with the accumulation framebuffer bound (attachments 0, 1), additive blending, depth test
// NOTEQUAL and no depth writes: adds the sums to the accumulation targets and zeroes them.
void compute_raster_resolve(const ComputeRaster& raster, GLuint frame_ubo);

// Diameter in pixels of a splat of `radius` (cloud units) at the cloud's bounding centre `center`, seen
// through `model_view` with projection[1][1] = p11 in a frame `height` pixels tall (infinity at or behind
// the eye): the automatic choice's estimate of how large the splats are on screen.
double splat_footprint_px(const glm::dmat4& model_view, const glm::dvec3& center, double radius, double p11,
                          int height);

// Mean splat radius of a cloud (cloud units; max(|axis_u|, |axis_v|) per splat), for the automatic choice.
double mean_splat_radius(const SplatCloud& cloud);

}  // namespace sffd::render
