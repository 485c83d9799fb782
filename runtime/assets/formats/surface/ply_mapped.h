// One binary element of a PLY file in place: the file memory-mapped read-only, the element's rows as
// bytes (row r at rows() + r * row_size()). The fast paths of the readers decode from here straight into
// their arrays, in parallel over rows, instead of going through ply::Reader's double columns.
//
// map_element() only succeeds where that is exact: binary little-endian data, an element without lists
// that only list-free elements precede (so its offset is known), and a file that holds all its rows.
// Everything else (ascii, big endian, lists, I/O errors) fails, and callers fall back to ply::Reader, which
// reads those files and names their problems; so the failure message is for logs, not for users.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string_view>

#include "runtime/assets/formats/archive/mapping_guard.h"
#include "runtime/assets/formats/surface/ply.h"
#include "runtime/core/result.h"

namespace sffd::ply {

// Owns the mapping (move-only): unmapped on destruction.
class MappedElement {
public:
    // `header` is the file's, as ply::Reader::open (or parse_header) read it: it is not parsed a second time
    // (that would repeat its warnings); the data starts after the end_header line.
    static Result<MappedElement> map(const std::filesystem::path& path, const Header& header,
                                     std::string_view element);
    MappedElement(MappedElement&& o) noexcept;
    MappedElement& operator=(MappedElement&& o) noexcept;
    MappedElement(const MappedElement&) = delete;
    MappedElement& operator=(const MappedElement&) = delete;
    ~MappedElement();

    const Header& header() const { return m_header; }
    const Element& element() const { return m_header.elements[m_index]; }
    std::size_t element_index() const { return m_index; }
    const unsigned char* rows() const { return m_base + m_offset; }
    std::size_t row_size() const { return m_row_size; }
    std::uint64_t count() const { return element().count; }
    // Byte offset of each property in a row (properties in element order).
    std::size_t property_offset(int property) const;
    // The file shrank while it was read (mapping_guard.h): rows past its new end read as zeros. Ask once
    // the decode is done; the reader then refuses the file.
    bool changed() const { return m_guard.changed(); }

private:
    MappedElement() = default;
    void release();
    Header m_header;
    std::size_t m_index = 0;
    const unsigned char* m_base = nullptr;  // the whole file
    std::size_t m_size = 0;
    std::size_t m_offset = 0;  // first byte of the element's rows
    std::size_t m_row_size = 0;
    assets::MappingGuard m_guard;
};

}  // namespace sffd::ply
