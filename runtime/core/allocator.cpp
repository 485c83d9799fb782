#include "runtime/core/allocator.h"

#include <cstdlib>  // defines __GLIBC__ on glibc

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace sffd {

void keep_freed_frame_memory() {
#if defined(__GLIBC__)
    constexpr int kReuseBelow = 32 << 20;  // served from the heap, kept there when freed
    constexpr int kTrimAbove = 256 << 20;  // free memory at the heap's top returned past this much
    mallopt(M_MMAP_THRESHOLD, kReuseBelow);
    mallopt(M_TRIM_THRESHOLD, kTrimAbove);
#endif
}

}  // namespace sffd
