// Stable GPU radix sort of (uint key, uint value) pairs in GL buffers, compute shaders only (GL 4.5 core,
// no subgroup or vendor extensions): per pass of 4 key bits, a histogram per block of 2,048 keys
// (shaders/common/radix_sort_count.comp: packed counters, a shared-memory tree), one exclusive scan of all
// histograms (radix_sort_scan.comp) and a stable scatter (radix_sort_scatter.comp); 8 passes for 32-bit keys,
// fewer when only the low `key_bits` bits order (e.g. 12-bit tile ids: 3 passes). Equal keys keep their input
// order, so sorting by a second key after a first gives the lexicographic order (gl_render's tiles).
//
//   auto sorter = gfx::create_radix_sorter();                 // compiles the 3 programs
//   gfx::radix_sort(*sorter, keys.id(), values.id(), count);  // in place, ascending
//
// Blocks are dispatched over a 2D grid (gfx::dispatch_1d), so counts beyond 65,535 blocks (134M keys)
// work on every conforming implementation; `max_groups_x` lowers the row width in tests. Float sort keys:
// non-negative floats order like their bit patterns (floatBitsToUint); 0xffffffff sorts after all.
// Owns its programs and scratch buffers (move-only); needs the GL context current, like every gfx object.
#pragma once

#include <cstdint>

#include "runtime/core/result.h"
#include "runtime/gfx/gl_object.h"

namespace sffd::gfx {

struct RadixSorter {
    Program count, scan, scatter;
    Program scan_reduce, scan_add;  // exclusive_scan()'s first and last steps (the middle one is `scan`)
    // Grow-only: ping-pong targets, the block histograms, exclusive_scan()'s block sums.
    Buffer keys_scratch, values_scratch, histogram, scan_sums;
    std::uint64_t scratch_elements = 0, histogram_entries = 0, scan_sum_entries = 0;
    std::uint32_t max_groups_x = 0;  // work groups per grid row; 0 = dispatch_group_limit()
};

// Compiles the three programs (errors name the shader file and line).
Result<RadixSorter> create_radix_sorter();

// Sorts the first `count` (keys[i], values[i]) pairs ascending by key, stably, in place; elements past
// `count` are not touched. `key_bits` (1..32): the keys' width; the passes cover the low `key_bits`
// rounded up to a multiple of 4, and higher bits ride along without ordering (so keys with bits set
// above that are sorted by their low bits only). Both buffers must hold `count` uints.
// Issues GL commands only (no readback, no wait); the results are visible to commands after it
// (shader storage, buffer update and command barriers are issued).
Status radix_sort(RadixSorter& sorter, GLuint keys, GLuint values, std::uint32_t count, int key_bits = 32);

// Exclusive prefix sum of the first `count` uints of `buffer`, in place, with their total written at
// element `count` (the buffer holds count + 1 uints; sums wrap modulo 2^32). Reduce-then-scan: block
// sums (scan_reduce.comp), their scan by one group (radix_sort_scan.comp: up to ~10^5 blocks is cheap),
// each block scanned with its offset (scan_add.comp). No readback.
Status exclusive_scan(RadixSorter& sorter, GLuint buffer, std::uint32_t count);

}  // namespace sffd::gfx
