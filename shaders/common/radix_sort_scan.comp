#version 450 core
// Radix sort pass 2 of 3 (runtime/gfx/radix_sort.h), and gfx::exclusive_scan(): exclusive prefix sum,
// in place, of u_count uints (the SFFD_RADIX_BUCKETS x blocks histogram), the total written after them
// (element u_count), by one work group: each invocation sums a contiguous run, the
// run totals are scanned in shared memory, each invocation rewrites its run. The array is small
// (16 entries per 2,048 keys: 47k for 6M keys), so one group is enough and needs no second level.
#include "common/radix_sort_layout.h"

layout(local_size_x = SFFD_RADIX_THREADS) in;

layout(std430, binding = SFFD_RADIX_SSBO_HISTOGRAM) buffer Histogram { uint histogram[]; };

layout(location = SFFD_RADIX_LOC_COUNT) uniform uint u_count;

shared uint s_sum[SFFD_RADIX_THREADS];

void main() {
    const uint tid = gl_LocalInvocationID.x;
    const uint total = u_count;
    const uint per = (total + SFFD_RADIX_THREADS - 1u) / SFFD_RADIX_THREADS;
    const uint begin = min(tid * per, total), end = min(begin + per, total);
    uint sum = 0u;
    for (uint i = begin; i < end; ++i) sum += histogram[i];
    s_sum[tid] = sum;
    barrier();
    // Hillis-Steele inclusive scan of the run totals.
    for (uint off = 1u; off < SFFD_RADIX_THREADS; off <<= 1u) {
        const uint v = tid >= off ? s_sum[tid - off] : 0u;
        barrier();
        s_sum[tid] += v;
        barrier();
    }
    if (tid == SFFD_RADIX_THREADS - 1u) histogram[total] = s_sum[tid];
    uint run = s_sum[tid] - sum;
    for (uint i = begin; i < end; ++i) {
        const uint h = histogram[i];
        histogram[i] = run;
        run += h;
    }
}
