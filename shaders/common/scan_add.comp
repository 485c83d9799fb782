#version 450 core
// gfx::exclusive_scan() step 3 of 3 (runtime/gfx/radix_sort.h): each block's exclusive scan, in place,
// offset by the scanned sum of the blocks before it; block 0 also writes the total after the data.
// The block is staged in shared memory (coalesced); invocation t scans its SFFD_RADIX_ITEMS consecutive
// values serially after one group scan of the per-invocation sums.
#include "common/radix_sort_layout.h"

layout(local_size_x = SFFD_RADIX_THREADS) in;

layout(std430, binding = SFFD_RADIX_SSBO_KEYS_IN) buffer Data { uint data[]; };
layout(std430, binding = SFFD_RADIX_SSBO_HISTOGRAM) readonly buffer Sums { uint sums[]; };  // scanned, total at [blocks]

layout(location = SFFD_RADIX_LOC_COUNT) uniform uint u_count;
layout(location = SFFD_RADIX_LOC_BLOCKS) uniform uint u_blocks;

shared uint s_data[SFFD_RADIX_BLOCK];
shared uint s_sum[SFFD_RADIX_THREADS];

void main() {
    const uint block = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    if (block >= u_blocks) return;  // uniform over the work group
    const uint tid = gl_LocalInvocationID.x;
    const uint begin = block * SFFD_RADIX_BLOCK;
    const uint valid = u_count - begin < SFFD_RADIX_BLOCK ? u_count - begin : SFFD_RADIX_BLOCK;
    for (uint k = 0u; k < SFFD_RADIX_ITEMS; ++k) {
        const uint local = k * SFFD_RADIX_THREADS + tid;
        s_data[local] = local < valid ? data[begin + local] : 0u;
    }
    barrier();
    const uint first = tid * SFFD_RADIX_ITEMS;
    uint sum = 0u;
    for (uint j = 0u; j < SFFD_RADIX_ITEMS; ++j) sum += s_data[first + j];
    uint inclusive = sum;
    s_sum[tid] = inclusive;
    barrier();
    for (uint off = 1u; off < SFFD_RADIX_THREADS; off <<= 1u) {
        if (tid >= off) inclusive += s_sum[tid - off];
        barrier();
        s_sum[tid] = inclusive;
        barrier();
    }
    uint run = sums[block] + inclusive - sum;
    for (uint j = 0u; j < SFFD_RADIX_ITEMS; ++j) {
        const uint v = s_data[first + j];
        s_data[first + j] = run;
        run += v;
    }
    barrier();
    for (uint k = 0u; k < SFFD_RADIX_ITEMS; ++k) {
        const uint local = k * SFFD_RADIX_THREADS + tid;
        if (local < valid) data[begin + local] = s_data[local];
    }
    if (block == 0u && tid == 0u) data[u_count] = sums[u_blocks];
}
