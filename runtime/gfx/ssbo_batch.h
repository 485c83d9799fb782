// Per-element passes over buffers larger than one storage block: bind ranges, one batch at a time.
//
// A shader sees at most GL_MAX_SHADER_STORAGE_BLOCK_SIZE bytes of a bound buffer (GL 4.5 guarantees only
// 2^24; many implementations report 2^27), and beyond that reads and writes are undefined. A pass whose
// element i of every buffer belongs to invocation i (the FFD and Gaussian deformations) can run over
// element ranges instead: each buffer bound with glBindBufferRange at first * stride, the offset a multiple
// of GL_SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT, and the shader indexing the range from 0.
//
//   const std::uint64_t strides[] = {sizeof(GpuSplat), sizeof(GpuSplat)};
//   auto batches = gfx::ssbo_batches(count, strides);     // one batch when everything fits
//   if (!batches) return batches.error();                   // names the limit
//   for (const gfx::SsboBatch& b : *batches) {
//       gfx::bind_ssbo_range(BINDING_IN, in, b, sizeof(GpuSplat));
//       ... set the batch's count, dispatch b.count invocations ...
//   }
//
// A pass that indexes a buffer at random cannot be cut this way as it stands: it reorders its input first
// (the CPU cull's quad list regrouped per range of splats, storage_limits.h; the Gaussian projection
// gathered into depth order, gaussian/gl_render.cpp, one dispatch per pair of ranges), or it checks
// ssbo_fits() and falls back (the radix sort's scatter, the tile entries, the compute cull).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "runtime/core/result.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/limits.h"

namespace sffd::gfx {

struct SsboBatch {
    std::uint64_t first = 0;  // element index of the batch's first element
    std::uint64_t count = 0;  // elements in the batch
};

// The element ranges of `count` elements such that, for every stride in `strides` (bytes per element of
// each buffer the pass binds per element), first * stride is a multiple of the offset alignment and
// count * stride fits one storage block. One batch {0, count} when every buffer fits whole; none for
// count 0. Fails, naming GL_MAX_SHADER_STORAGE_BLOCK_SIZE, when not even one aligned group of elements fits.
Result<std::vector<SsboBatch>> ssbo_batches(std::uint64_t count, std::span<const std::uint64_t> strides,
                                            const GlLimits& limits = gfx::limits());

// glBindBufferRange of `batch`'s elements of `buffer` (`stride` bytes each) to storage block `binding`.
void bind_ssbo_range(GLuint binding, GLuint buffer, const SsboBatch& batch, std::uint64_t stride);

}  // namespace sffd::gfx
