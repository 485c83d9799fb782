// Inclusive prefix sum of one uint per invocation over a 1D work group, in shared memory (Hillis-Steele,
// log2(size) steps). Every invocation of the group must call it: it has barriers. Define
// SFFD_GROUP_SCAN_SIZE (the local size) before the include.
#ifndef SFFD_GROUP_SCAN_GLSL
#define SFFD_GROUP_SCAN_GLSL

shared uint sffd_group_scan_words[SFFD_GROUP_SCAN_SIZE];

uint sffd_inclusive_group_scan(uint value) {
    const uint lid = gl_LocalInvocationID.x;
    sffd_group_scan_words[lid] = value;
    barrier();
    for (uint d = 1u; d < uint(SFFD_GROUP_SCAN_SIZE); d <<= 1u) {
        const uint before = lid >= d ? sffd_group_scan_words[lid - d] : 0u;
        barrier();
        sffd_group_scan_words[lid] += before;
        barrier();
    }
    return sffd_group_scan_words[lid];
}

#endif
