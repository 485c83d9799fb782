#version 450 core
// Radix sort pass 3 of 3 (runtime/gfx/radix_sort.h): stable scatter of one block of SFFD_RADIX_BLOCK
// keys. The block is staged in shared memory with coalesced loads; invocation t then owns the
// SFFD_RADIX_ITEMS consecutive keys t*ITEMS.. (so earlier invocations hold earlier keys), counts its
// digits into 16 packed 16-bit counters (two uvec4: digits 0-7, 8-15; a block's counts stay below
// 2^16, so no field overflows), and one shared-memory scan of those counters over the group gives each
// invocation, per digit, the number of earlier keys of the block with that digit. Output slot =
// scanned histogram[digit][block] + that count + the invocation's own earlier keys of the digit.
// One scan per block (18 barriers), no subgroup operations: plain GL 4.5 (24 KiB of shared memory).
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

shared uint s_keys[SFFD_RADIX_BLOCK];
shared uint s_values[SFFD_RADIX_BLOCK];
shared uvec4 s_low[SFFD_RADIX_THREADS];   // counters of digits 0..7 (16 bits each)
shared uvec4 s_high[SFFD_RADIX_THREADS];  // counters of digits 8..15
shared uint s_base[SFFD_RADIX_BUCKETS];

// One count of `digit` in the packed pair (low, high).
void add_one(inout uvec4 low, inout uvec4 high, uint digit) {
    const uint component = (digit >> 1u) & 3u, shift = (digit & 1u) * 16u;
    if (digit < 8u) low[component] += 1u << shift;
    else high[component] += 1u << shift;
}

uint count_of(uvec4 low, uvec4 high, uint digit) {
    const uint component = (digit >> 1u) & 3u, shift = (digit & 1u) * 16u;
    return ((digit < 8u ? low[component] : high[component]) >> shift) & 0xffffu;
}

void main() {
    // Blocks over a 2D grid; the test is uniform over the work group, so no invocation skips a barrier alone.
    const uint block = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    if (block >= u_blocks) return;
    const uint tid = gl_LocalInvocationID.x;
    const uint begin = block * SFFD_RADIX_BLOCK;
    const uint valid = u_count - begin < SFFD_RADIX_BLOCK ? u_count - begin : SFFD_RADIX_BLOCK;  // keys in this block
    if (tid < SFFD_RADIX_BUCKETS) s_base[tid] = histogram[tid * u_blocks + block];
    for (uint k = 0u; k < SFFD_RADIX_ITEMS; ++k) {
        const uint local = k * SFFD_RADIX_THREADS + tid;
        if (local < valid) {
            s_keys[local] = keys_in[begin + local];
            s_values[local] = values_in[begin + local];
        }
    }
    barrier();
    const uint first = tid * SFFD_RADIX_ITEMS;
    uvec4 low = uvec4(0u), high = uvec4(0u);
    for (uint j = 0u; j < SFFD_RADIX_ITEMS; ++j)
        if (first + j < valid) add_one(low, high, (s_keys[first + j] >> u_shift) & (SFFD_RADIX_BUCKETS - 1u));
    // Hillis-Steele inclusive scan of the packed counters over the group.
    uvec4 inc_low = low, inc_high = high;
    s_low[tid] = inc_low;
    s_high[tid] = inc_high;
    barrier();
    for (uint off = 1u; off < SFFD_RADIX_THREADS; off <<= 1u) {
        if (tid >= off) {
            inc_low += s_low[tid - off];
            inc_high += s_high[tid - off];
        }
        barrier();
        s_low[tid] = inc_low;
        s_high[tid] = inc_high;
        barrier();
    }
    uvec4 run_low = inc_low - low, run_high = inc_high - high;  // earlier invocations' keys, per digit
    for (uint j = 0u; j < SFFD_RADIX_ITEMS; ++j) {
        if (first + j >= valid) break;
        const uint key = s_keys[first + j];
        const uint digit = (key >> u_shift) & (SFFD_RADIX_BUCKETS - 1u);
        const uint dst = s_base[digit] + count_of(run_low, run_high, digit);
        keys_out[dst] = key;
        values_out[dst] = s_values[first + j];
        add_one(run_low, run_high, digit);
    }
}
