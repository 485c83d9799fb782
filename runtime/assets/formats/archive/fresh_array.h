// Output arrays that a parallel decode overwrites whole: sized without the cost of faulting their memory in
// one page at a time on one thread. A 250 MB cloud is ~60k first-touch page faults, each zeroing 4 KiB in
// the kernel; resize() alone pays them all serially. resize_for_overwrite() reserves the array, asks for
// transparent huge pages and prefaults it in parallel (MADV_POPULATE_WRITE), so resize() only writes its
// zeros to memory that is already there. Both are hints: where the kernel refuses them, resize() faults
// as it always did and the result is the same.
#pragma once

#include <cstddef>
#include <vector>

namespace sffd::assets {

// Prefaults [data, data + bytes) for writing, in parallel; huge pages where the kernel allows them.
void prefault_for_write(void* data, std::size_t bytes);

template <class T>
void resize_for_overwrite(std::vector<T>& v, std::size_t n) {
    // An empty array (perhaps reserved by the caller) is prefaulted; one with contents resizes as usual.
    if (v.empty()) {
        v.reserve(n);
        prefault_for_write(v.data(), n * sizeof(T));
    }
    v.resize(n);
}

}  // namespace sffd::assets
