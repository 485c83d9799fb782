#include "runtime/assets/formats/archive/mapped_file.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <utility>

#include "runtime/core/file_io.h"

namespace sffd::assets {

Result<MappedFile> MappedFile::open(const std::filesystem::path& path, std::uint64_t limit) {
    MappedFile f;
    // O_NONBLOCK as read_file(): opening a FIFO must not wait for a writer (it is refused below).
    const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    struct stat st {};
    if (fd >= 0 && ::fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && st.st_size > 0 &&
        std::uint64_t(st.st_size) <= limit) {
        // MAP_POPULATE: the file's pages are mapped in one pass instead of a fault per 4 KiB while parsing.
        void* p = ::mmap(nullptr, std::size_t(st.st_size), PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd, 0);
        if (p != MAP_FAILED) {
            f.m_map = static_cast<const char*>(p), f.m_size = std::size_t(st.st_size);
            f.m_guard = MappingGuard(p, f.m_size);
        }
    }
    if (fd >= 0) ::close(fd);
    if (f.m_map) return f;
    auto bytes = read_file(path, limit);
    if (!bytes) return bytes.error();
    f.m_copy = std::move(*bytes);
    return f;
}

void MappedFile::release() {
    m_guard = MappingGuard();
    if (m_map) ::munmap(const_cast<char*>(m_map), m_size);
    m_map = nullptr, m_size = 0;
}

MappedFile::MappedFile(MappedFile&& o) noexcept
    : m_map(std::exchange(o.m_map, nullptr)),
      m_size(std::exchange(o.m_size, 0)),
      m_guard(std::move(o.m_guard)),
      m_copy(std::move(o.m_copy)) {}

MappedFile& MappedFile::operator=(MappedFile&& o) noexcept {
    if (this != &o) {
        release();
        m_map = std::exchange(o.m_map, nullptr), m_size = std::exchange(o.m_size, 0);
        m_guard = std::move(o.m_guard);
        m_copy = std::move(o.m_copy);
    }
    return *this;
}

MappedFile::~MappedFile() { release(); }

}  // namespace sffd::assets
