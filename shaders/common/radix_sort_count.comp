#version 450 core
// Radix sort pass 1 of 3 (runtime/gfx/radix_sort.h): the histogram of this pass's 4-bit digit in one
// block of SFFD_RADIX_BLOCK keys, written bucket-major (histogram[bucket * blocks + block]) so that one
// exclusive scan of the whole array gives every (bucket, block) its first output slot.
#include "common/radix_sort_layout.h"

layout(local_size_x = SFFD_RADIX_THREADS) in;

layout(std430, binding = SFFD_RADIX_SSBO_KEYS_IN) readonly buffer KeysIn { uint keys_in[]; };
layout(std430, binding = SFFD_RADIX_SSBO_HISTOGRAM) writeonly buffer Histogram { uint histogram[]; };

layout(location = SFFD_RADIX_LOC_COUNT) uniform uint u_count;
layout(location = SFFD_RADIX_LOC_SHIFT) uniform uint u_shift;
layout(location = SFFD_RADIX_LOC_BLOCKS) uniform uint u_blocks;

shared uint s_hist[SFFD_RADIX_BUCKETS];

void main() {
    // Blocks over a 2D grid (gfx::dispatch_1d: at most 65,535 groups per row); the last row is partly
    // empty. The test is uniform over the work group, so no invocation skips a barrier alone.
    const uint block = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    if (block >= u_blocks) return;
    const uint tid = gl_LocalInvocationID.x;
    if (tid < SFFD_RADIX_BUCKETS) s_hist[tid] = 0u;
    barrier();
    const uint begin = block * SFFD_RADIX_BLOCK;
    for (uint k = 0u; k < SFFD_RADIX_ITEMS; ++k) {
        const uint i = begin + k * SFFD_RADIX_THREADS + tid;
        if (i < u_count) atomicAdd(s_hist[(keys_in[i] >> u_shift) & (SFFD_RADIX_BUCKETS - 1u)], 1u);
    }
    barrier();
    if (tid < SFFD_RADIX_BUCKETS) histogram[tid * u_blocks + block] = s_hist[tid];
}
