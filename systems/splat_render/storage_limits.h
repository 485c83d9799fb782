// The splat renderer's storage blocks against GL_MAX_SHADER_STORAGE_BLOCK_SIZE (runtime/gfx/limits.h).
// A shader sees at most that many bytes of one bound buffer; beyond it reads and writes are undefined, so
// passes whose buffers outgrow it take the path that needs no such block instead:
//   - the compute rasteriser (depth and 36-byte sums per pixel): the raster path (plan_compute_raster);
//   - the compute cull (192-byte records per splat): the CPU cull when the cull path is automatic; a
//     forced compute cull skips the cloud with an error.
// Each refusal is logged once per message (not every frame).
#pragma once

#include <cstddef>
#include <string>

#include "runtime/core/result.h"

namespace sffd::render {

// Whether the compute rasteriser's per-pixel buffers at width x height fit one storage block each.
Status compute_raster_fits(int width, int height);

// Whether the compute cull's buffers for a cloud of `splats` (records, quads, splats) fit.
Status compute_cull_fits(std::size_t splats);

// Logs `message` at warn level the first time it is seen in this process.
void warn_once(const std::string& message);

}  // namespace sffd::render
