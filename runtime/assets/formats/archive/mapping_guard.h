// Files mapped for reading can shrink while they are read: another program truncates or rewrites the
// file, and touching a mapped page past its new end raises SIGBUS, which ends the process. A guarded
// mapping registers its address range; on SIGBUS inside it, the handler maps a page of zeros over the
// faulting page and marks the range, the interrupted read goes on with zeros, and the reader, which asks
// changed() once its parse is done, reports the file as changed instead of returning what it parsed.
// The handler never jumps out of the reader (its destructors and the thread pool's frames stay intact);
// a SIGBUS outside every guarded range goes to the handler installed before (default: the process ends).
#pragma once

#include <cstddef>

namespace sffd::assets {

// What a reader says of a file whose mapping changed() (after the file's name and ": ").
inline constexpr const char* kChangedWhileRead =
    "the file changed while it was read (shortened or rewritten by another program); nothing was loaded";

class MappingGuard {
public:
    MappingGuard() = default;
    // Guards [base, base + size). At most 64 mappings are guarded at once; past that (or with size 0)
    // the guard is empty and a SIGBUS in the range ends the process as without one.
    MappingGuard(const void* base, std::size_t size);
    MappingGuard(MappingGuard&& o) noexcept;
    MappingGuard& operator=(MappingGuard&& o) noexcept;
    MappingGuard(const MappingGuard&) = delete;
    MappingGuard& operator=(const MappingGuard&) = delete;
    ~MappingGuard();  // stops guarding; call before unmapping

    bool guarding() const { return m_slot >= 0; }
    // A SIGBUS in the range was answered with zeros: the file changed while it was read.
    bool changed() const;

private:
    void release();
    int m_slot = -1;
};

}  // namespace sffd::assets
