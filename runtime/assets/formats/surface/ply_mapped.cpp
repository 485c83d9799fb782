#include "runtime/assets/formats/surface/ply_mapped.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <string>
#include <utility>

namespace sffd::ply {

namespace {

// ply::Reader refuses headers longer than this as well.
constexpr std::size_t kMaxHeaderBytes = 64 * 1024;

struct Fd {
    int fd = -1;
    ~Fd() {
        if (fd >= 0) ::close(fd);
    }
};

// Bytes up to and including the end_header line (the first line whose first word is end_header, as
// parse_header reads it), or 0 when there is none within kMaxHeaderBytes.
std::size_t header_end(std::string_view text) {
    std::size_t pos = 0;
    while (pos < text.size()) {
        const std::size_t nl = text.find('\n', pos);
        if (nl == std::string_view::npos) return 0;
        std::string_view line = text.substr(pos, nl - pos);
        const std::size_t first = line.find_first_not_of(" \t\r");
        if (first != std::string_view::npos) {
            line.remove_prefix(first);
            const std::string_view word = line.substr(0, line.find_first_of(" \t\r"));
            if (word == "end_header") return nl + 1;
        }
        pos = nl + 1;
    }
    return 0;
}

}  // namespace

Result<MappedElement> MappedElement::map(const std::filesystem::path& path, const Header& header,
                                         std::string_view element) {
    const std::string name = path.string();
    Fd f;
    f.fd = ::open(name.c_str(), O_RDONLY | O_CLOEXEC);
    if (f.fd < 0) return make_error(name + ": cannot open");
    struct stat st {};
    if (::fstat(f.fd, &st) != 0 || !S_ISREG(st.st_mode) || st.st_size <= 0)
        return make_error(name + ": not a regular file");
    const std::size_t size = std::size_t(st.st_size);
    if (header.format != Format::binary_little_endian) return make_error(name + ": not binary little endian");
    // MAP_POPULATE reads the whole file in ahead (one pass through the page cache) instead of a page fault
    // per 4 KiB in the decoding threads.
    void* p = ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE | MAP_POPULATE, f.fd, 0);
    if (p == MAP_FAILED) return make_error(name + ": cannot map");
    MappedElement m;
    m.m_base = static_cast<const unsigned char*>(p);
    m.m_guard = assets::MappingGuard(p, size);
    m.m_size = size;
    const std::size_t header_bytes = header_end(
        std::string_view(reinterpret_cast<const char*>(m.m_base), std::min(size, kMaxHeaderBytes)));
    if (header_bytes == 0) return make_error(name + ": no end_header");
    m.m_header = header;
    if (m.m_header.format != Format::binary_little_endian)
        return make_error(name + ": not binary little endian");
    const int at = m.m_header.find(element);
    if (at < 0) return make_error(name + ": no element '" + std::string(element) + "'");
    std::uint64_t offset = header_bytes;
    for (int e = 0; e < at; ++e) {
        const Element& before = m.m_header.elements[std::size_t(e)];
        if (before.has_lists())
            return make_error(name + ": a list element precedes '" + std::string(element) + "'");
        offset += std::uint64_t(before.row_size()) * before.count;  // counts fit the file (checked below)
        if (offset > size) return make_error(name + ": truncated");
    }
    const Element& e = m.m_header.elements[std::size_t(at)];
    if (e.has_lists()) return make_error(name + ": element '" + e.name + "' has lists");
    m.m_index = std::size_t(at);
    m.m_offset = std::size_t(offset);
    m.m_row_size = e.row_size();
    if (m.m_row_size == 0 || e.count > (size - m.m_offset) / m.m_row_size)
        return make_error(name + ": truncated");
    return m;
}

std::size_t MappedElement::property_offset(int property) const {
    std::size_t o = 0;
    for (int i = 0; i < property; ++i) o += type_size(element().properties[std::size_t(i)].type);
    return o;
}

void MappedElement::release() {
    m_guard = assets::MappingGuard();
    if (m_base) ::munmap(const_cast<unsigned char*>(m_base), m_size);
    m_base = nullptr, m_size = 0;
}

MappedElement::MappedElement(MappedElement&& o) noexcept
    : m_header(std::move(o.m_header)),
      m_index(o.m_index),
      m_base(std::exchange(o.m_base, nullptr)),
      m_size(std::exchange(o.m_size, 0)),
      m_offset(o.m_offset),
      m_row_size(o.m_row_size),
      m_guard(std::move(o.m_guard)) {}

MappedElement& MappedElement::operator=(MappedElement&& o) noexcept {
    if (this != &o) {
        release();
        m_header = std::move(o.m_header), m_index = o.m_index;
        m_base = std::exchange(o.m_base, nullptr), m_size = std::exchange(o.m_size, 0);
        m_offset = o.m_offset, m_row_size = o.m_row_size;
        m_guard = std::move(o.m_guard);
    }
    return *this;
}

MappedElement::~MappedElement() { release(); }

}  // namespace sffd::ply
