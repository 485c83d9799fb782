// GPU radix sort (runtime/gfx/radix_sort.h): constants, bindings and uniform locations shared by the
// shaders (#include "common/radix_sort_layout.h") and C++ (#include "shaders/common/radix_sort_layout.h").
// The sort binds its own buffers before every dispatch, so these points are local to it.
#ifndef SFFD_RADIX_SORT_LAYOUT_H
#define SFFD_RADIX_SORT_LAYOUT_H

#define SFFD_RADIX_BITS     4u                          // bits per pass: 16 buckets, 8 passes for 32-bit keys
#define SFFD_RADIX_BUCKETS  16u
#define SFFD_RADIX_THREADS  256u                        // invocations per work group
#define SFFD_RADIX_ITEMS    8u                          // elements per invocation per block
#define SFFD_RADIX_BLOCK    (SFFD_RADIX_THREADS * SFFD_RADIX_ITEMS)  // elements per block (one work group)

#define SFFD_RADIX_SSBO_KEYS_IN    0   // uint[]: keys read by this pass
#define SFFD_RADIX_SSBO_VALUES_IN  1   // uint[]: payloads read by this pass
#define SFFD_RADIX_SSBO_KEYS_OUT   2   // uint[]: keys written by the scatter
#define SFFD_RADIX_SSBO_VALUES_OUT 3   // uint[]: payloads written by the scatter
#define SFFD_RADIX_SSBO_HISTOGRAM  4   // uint[bucket * blocks + block]: counts, then their exclusive scan

#define SFFD_RADIX_LOC_COUNT  0   // uint: elements to sort
#define SFFD_RADIX_LOC_SHIFT  1   // uint: first key bit of this pass
#define SFFD_RADIX_LOC_BLOCKS 2   // uint: blocks (work groups with work; the grid may hold more)

#endif
