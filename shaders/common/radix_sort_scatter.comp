#version 450 core
// Radix sort pass 3 of 3 (runtime/gfx/radix_sort.h): stable scatter of one block. The block is read in
// SFFD_RADIX_ITEMS chunks of SFFD_RADIX_THREADS keys, in order; within a chunk, the rank of a key among
// the earlier keys of its digit comes from one shared-memory scan of packed one-hot counters (16 digits
// x 8 bits in a uvec4: an exclusive count over 256 invocations is at most 255, so no byte overflows;
// inclusive sums may carry, but the carry cancels when the invocation's own one-hot is subtracted).
// Output slot = scanned histogram[digit][block] + keys of that digit in earlier chunks + rank.
// No subgroup operations: plain GL 4.5.
#include "common/radix_sort_layout.h"

layout(local_size_x = SFFD_RADIX_THREADS) in;

layout(std430, binding = SFFD_RADIX_SSBO_KEYS_IN) readonly buffer KeysIn { uint keys_in[]; };
layout(std430, binding = SFFD_RADIX_SSBO_VALUES_IN) readonly buffer ValuesIn { uint values_in[]; };
layout(std430, binding = SFFD_RADIX_SSBO_KEYS_OUT) writeonly buffer KeysOut { uint keys_out[]; };
layout(std430, binding = SFFD_RADIX_SSBO_VALUES_OUT) writeonly buffer ValuesOut { uint values_out[]; };
layout(std430, binding = SFFD_RADIX_SSBO_HISTOGRAM) readonly buffer Histogram { uint histogram[]; };

layout(location = SFFD_RADIX_LOC_COUNT) uniform uint u_count;
layout(location = SFFD_RADIX_LOC_SHIFT) uniform uint u_shift;
layout(location = SFFD_RADIX_LOC_BLOCKS) uniform uint u_blocks;

shared uvec4 s_scan[2][SFFD_RADIX_THREADS];
shared uint s_base[SFFD_RADIX_BUCKETS];
shared uvec4 s_last_exclusive;
shared uint s_last_digit;

uint byte_of(uvec4 counts, uint digit) { return (counts[digit >> 2u] >> ((digit & 3u) * 8u)) & 0xffu; }

void main() {
    const uint block = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    if (block >= u_blocks) return;  // uniform over the work group
    const uint tid = gl_LocalInvocationID.x;
    if (tid < SFFD_RADIX_BUCKETS) s_base[tid] = histogram[tid * u_blocks + block];
    barrier();
    const uint begin = block * SFFD_RADIX_BLOCK;
    for (uint k = 0u; k < SFFD_RADIX_ITEMS; ++k) {
        const uint i = begin + k * SFFD_RADIX_THREADS + tid;
        const bool valid = i < u_count;
        const uint key = valid ? keys_in[i] : 0u;
        const uint value = valid ? values_in[i] : 0u;
        const uint digit = (key >> u_shift) & (SFFD_RADIX_BUCKETS - 1u);
        uvec4 one = uvec4(0u);
        if (valid) one[digit >> 2u] = 1u << ((digit & 3u) * 8u);
        s_scan[0][tid] = one;
        barrier();
        uint src = 0u;
        for (uint off = 1u; off < SFFD_RADIX_THREADS; off <<= 1u) {
            uvec4 v = s_scan[src][tid];
            if (tid >= off) v += s_scan[src][tid - off];
            s_scan[1u - src][tid] = v;
            src = 1u - src;
            barrier();
        }
        const uvec4 exclusive = s_scan[src][tid] - one;
        if (valid) {
            const uint dst = s_base[digit] + byte_of(exclusive, digit);
            keys_out[dst] = key;
            values_out[dst] = value;
        }
        if (tid == SFFD_RADIX_THREADS - 1u) {
            s_last_exclusive = exclusive;
            s_last_digit = valid ? digit : SFFD_RADIX_BUCKETS;
        }
        barrier();  // every invocation has read s_base and s_scan
        if (tid < SFFD_RADIX_BUCKETS) s_base[tid] += byte_of(s_last_exclusive, tid) + (s_last_digit == tid ? 1u : 0u);
        barrier();
    }
}
