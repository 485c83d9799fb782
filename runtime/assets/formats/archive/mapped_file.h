// A whole file, read-only and memory-mapped where it can be: large inputs (a 230 MB GLB) are parsed in
// place instead of first being copied into a fresh string (a serial copy and page faults per read).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include "runtime/assets/formats/archive/mapping_guard.h"
#include "runtime/core/result.h"

namespace sffd::assets {

class MappedFile {
public:
    // A regular file within `limit` bytes is mapped; anything else (and a failed mapping) goes through
    // read_file(), so refusals keep read_file()'s messages.
    static Result<MappedFile> open(const std::filesystem::path& path, std::uint64_t limit);

    std::string_view bytes() const {
        return m_map ? std::string_view(m_map, m_size) : std::string_view(m_copy);
    }
    // The mapped file shrank while it was read (mapping_guard.h): the bytes read past its new end were
    // zeros. Ask once the parse is done; a reader then refuses the file.
    bool changed() const { return m_guard.changed(); }

    MappedFile() = default;
    MappedFile(MappedFile&& o) noexcept;
    MappedFile& operator=(MappedFile&& o) noexcept;
    MappedFile(const MappedFile&) = delete;
    MappedFile& operator=(const MappedFile&) = delete;
    ~MappedFile();

private:
    void release();
    const char* m_map = nullptr;
    std::size_t m_size = 0;
    MappingGuard m_guard;
    std::string m_copy;
};

}  // namespace sffd::assets
