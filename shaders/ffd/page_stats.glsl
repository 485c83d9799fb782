// The deform passes' counters, per page of the cloud (2^SFFD_PAGE_SHIFT points, runtime/scene/
// point_pages.h): counter k of page p is stats[SFFD_PAGE_COUNTERS * p + k]. A dispatch over some pages
// adds only into theirs, so the cloud's counts (the sum over its pages, summed on the CPU) stay right
// after a page-wise redo. Needs ffd_common.glsl (ffd_count.z: the cloud index of the batch's first point),
// the local size declared, SFFD_PAGE_COUNTERS defined and `stats` declared before it.
#ifndef SFFD_PAGE_STATS_GLSL
#define SFFD_PAGE_STATS_GLSL

// The page of batch element `id`.
uint ffd_page_of(uint id) { return (ffd_count.z + id) >> SFFD_PAGE_SHIFT; }

// True when every invocation of this work group lies in one page (the common case: a page is a whole
// number of groups, and batches start on a page, except when a lowered block limit cuts one elsewhere):
// the group adds its counts once. The same for the whole group, so it may guard a barrier.
bool ffd_group_in_one_page(uint id) {
    const uint first = ffd_count.z + id - gl_LocalInvocationIndex;
    return (first >> SFFD_PAGE_SHIFT) == ((first + gl_WorkGroupSize.x - 1u) >> SFFD_PAGE_SHIFT);
}

void ffd_count_in_page(uint id, uint counter, uint n) {
    if (n != 0u) atomicAdd(stats[SFFD_PAGE_COUNTERS * ffd_page_of(id) + counter], n);
}

#endif
