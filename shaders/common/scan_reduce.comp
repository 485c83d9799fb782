#version 450 core
// gfx::exclusive_scan() step 1 of 3 (runtime/gfx/radix_sort.h): the sum of each block of
// SFFD_RADIX_BLOCK uints, into the sums buffer (scanned next by radix_sort_scan.comp, one group).
#include "common/radix_sort_layout.h"

layout(local_size_x = SFFD_RADIX_THREADS) in;

layout(std430, binding = SFFD_RADIX_SSBO_KEYS_IN) readonly buffer Data { uint data[]; };
layout(std430, binding = SFFD_RADIX_SSBO_HISTOGRAM) writeonly buffer Sums { uint sums[]; };

layout(location = SFFD_RADIX_LOC_COUNT) uniform uint u_count;
layout(location = SFFD_RADIX_LOC_BLOCKS) uniform uint u_blocks;

shared uint s_sum[SFFD_RADIX_THREADS];

void main() {
    const uint block = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    if (block >= u_blocks) return;  // uniform over the work group
    const uint tid = gl_LocalInvocationID.x;
    const uint begin = block * SFFD_RADIX_BLOCK;
    uint sum = 0u;
    for (uint k = 0u; k < SFFD_RADIX_ITEMS; ++k) {
        const uint i = begin + k * SFFD_RADIX_THREADS + tid;
        if (i < u_count) sum += data[i];
    }
    s_sum[tid] = sum;
    barrier();
    for (uint half_size = SFFD_RADIX_THREADS / 2u; half_size > 0u; half_size >>= 1u) {
        if (tid < half_size) s_sum[tid] += s_sum[tid + half_size];
        barrier();
    }
    if (tid == 0u) sums[block] = s_sum[0];
}
