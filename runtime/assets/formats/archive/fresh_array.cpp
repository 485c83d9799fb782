#include "runtime/assets/formats/archive/fresh_array.h"

#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace sffd::assets {

void prefault_for_write(void* data, std::size_t bytes) {
    // Small arrays fault in quickly; the system calls would cost more than they save.
    constexpr std::size_t kMinBytes = std::size_t(4) << 20, kHuge = std::size_t(2) << 20;
    if (!data || bytes < kMinBytes) return;
    const std::uintptr_t page = std::uintptr_t(::sysconf(_SC_PAGESIZE));
    // madvise takes whole pages: the pages wholly inside the array (the partial ends fault as usual).
    const std::uintptr_t begin = (std::uintptr_t(data) + page - 1) / page * page;
    const std::uintptr_t end = (std::uintptr_t(data) + bytes) / page * page;
    if (end <= begin) return;
#ifdef MADV_HUGEPAGE
    ::madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
#endif
#ifdef MADV_POPULATE_WRITE
    // Pieces of whole huge pages, so that each thread's kernel zeroing covers its own 2 MiB pages.
    const std::uintptr_t base = begin / kHuge * kHuge;
    const std::size_t pieces = (end - base + kHuge - 1) / kHuge;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pieces, 4),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          const std::uintptr_t lo = std::max<std::uintptr_t>(begin, base + r.begin() * kHuge);
                          const std::uintptr_t hi = std::min<std::uintptr_t>(end, base + r.end() * kHuge);
                          if (hi > lo) ::madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_POPULATE_WRITE);
                      });
#endif
}

}  // namespace sffd::assets
