// The splat renderer's storage blocks against GL_MAX_SHADER_STORAGE_BLOCK_SIZE (runtime/gfx/limits.h).
// A shader sees at most that many bytes of one bound buffer; beyond it reads and writes are undefined, so
// passes whose buffers outgrow it take the path that needs no such block instead:
//   - the compute rasteriser (depth and 36-byte sums per pixel): the raster path (plan_compute_raster);
//   - the compute cull (96-byte sprite records per splat): the CPU cull, whatever the cull path, its splats
//   read
//     back once per deformation when only the GPU holds them (the FFD compute pass wrote them);
//   - the splats (64 bytes each) and uv axes of the CPU cull's quad pass: drawn per range of splats
//     (runtime/gfx/ssbo_batch.h), each range's quads uploaded as indices relative to its first splat
//     (layout_quad_batches); the sprites are vertex attributes, which have no such limit;
//   - the compute rasteriser's records (as the cull's): the raster path.
// Each refusal is logged once per message (not every frame).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "runtime/core/result.h"
#include "runtime/gfx/ssbo_batch.h"

namespace sffd::render {

// Whether the compute rasteriser's per-pixel buffers at width x height fit one storage block each.
Status compute_raster_fits(int width, int height);

// Whether the compute cull's buffers for a cloud of `splats` (records, quads, splats) fit.
Status compute_cull_fits(std::size_t splats);

// Whether the compute rasteriser's read of a cloud's records (`capacity` sprites, twice that with the CPU
// cull's flat-coloured list) fits one block.
Status compute_raster_records_fit(std::size_t capacity, bool flat_list);

// One draw of the quad pass over a range of splats: the splats (and uv axes) bound from `splats.first`,
// `quad_count` quads at element `quad_first` of the uploaded list, relative to that first splat.
struct QuadBatch {
    gfx::SsboBatch splats;
    std::uint32_t quad_first = 0, quad_count = 0;
};

// CPU only: regroups `quads` (ascending splat indices, as the CPU cull writes them) by the ranges of
// `batches` into `out`: each group's indices relative to its range's first splat, each group starting at
// a multiple of `align_words` (GL_SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT / 4, at least 1) so it can be
// bound as a range. Returns one QuadBatch per range (empty ranges included, with quad_count 0).
std::vector<QuadBatch> layout_quad_batches(std::span<const std::uint32_t> quads,
                                           std::span<const gfx::SsboBatch> batches, std::uint32_t align_words,
                                           std::vector<std::uint32_t>& out);

// Logs `message` at warn level the first time it is seen in this process.
void warn_once(const std::string& message);

}  // namespace sffd::render
