#version 450 core
// Radix sort pass 1 of 3 (runtime/gfx/radix_sort.h): the histogram of this pass's 4-bit digit in one
// block of SFFD_RADIX_BLOCK keys, written bucket-major (histogram[bucket * blocks + block]) so that one
// exclusive scan of the whole array gives every (bucket, block) its first output slot. Each invocation
// counts its keys (strided: coalesced loads) into 16 packed 16-bit counters (two uvec4, as in the
// scatter; a block's counts stay below 2^16), and a shared-memory tree adds them: no atomics.
#include "common/radix_sort_layout.h"

layout(local_size_x = SFFD_RADIX_THREADS) in;

layout(std430, binding = SFFD_RADIX_SSBO_KEYS_IN) readonly buffer KeysIn { uint keys_in[]; };
layout(std430, binding = SFFD_RADIX_SSBO_HISTOGRAM) writeonly buffer Histogram { uint histogram[]; };

layout(location = SFFD_RADIX_LOC_COUNT) uniform uint u_count;
layout(location = SFFD_RADIX_LOC_SHIFT) uniform uint u_shift;
layout(location = SFFD_RADIX_LOC_BLOCKS) uniform uint u_blocks;

shared uvec4 s_low[SFFD_RADIX_THREADS];   // counters of digits 0..7 (16 bits each)
shared uvec4 s_high[SFFD_RADIX_THREADS];  // counters of digits 8..15

void main() {
    // Blocks over a 2D grid (gfx::dispatch_1d: at most 65,535 groups per row); the last row is partly
    // empty. The test is uniform over the work group, so no invocation skips a barrier alone.
    const uint block = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    if (block >= u_blocks) return;
    const uint tid = gl_LocalInvocationID.x;
    const uint begin = block * SFFD_RADIX_BLOCK;
    uvec4 low = uvec4(0u), high = uvec4(0u);
    for (uint k = 0u; k < SFFD_RADIX_ITEMS; ++k) {
        const uint i = begin + k * SFFD_RADIX_THREADS + tid;
        if (i < u_count) {
            const uint digit = (keys_in[i] >> u_shift) & (SFFD_RADIX_BUCKETS - 1u);
            const uint component = (digit >> 1u) & 3u, shift = (digit & 1u) * 16u;
            if (digit < 8u) low[component] += 1u << shift;
            else high[component] += 1u << shift;
        }
    }
    s_low[tid] = low;
    s_high[tid] = high;
    barrier();
    for (uint half_size = SFFD_RADIX_THREADS / 2u; half_size > 0u; half_size >>= 1u) {
        if (tid < half_size) {
            s_low[tid] += s_low[tid + half_size];
            s_high[tid] += s_high[tid + half_size];
        }
        barrier();
    }
    if (tid < SFFD_RADIX_BUCKETS) {
        const uint component = (tid >> 1u) & 3u, shift = (tid & 1u) * 16u;
        const uint counters = tid < 8u ? s_low[0][component] : s_high[0][component];
        histogram[tid * u_blocks + block] = (counters >> shift) & 0xffffu;
    }
}
