// ply::Writer: streaming rows into ASCII and binary PLY files through an atomic temporary (see ply.h).
#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <optional>
#include <type_traits>

#include "runtime/assets/formats/surface/ply.h"
#include "runtime/assets/formats/surface/ply_detail.h"
#include "runtime/core/atomic_file.h"

namespace sffd::ply {
using namespace detail;
namespace fs = std::filesystem;

namespace {

inline void encode(unsigned char* p, Type t, double value, bool swap) {
    unsigned char b[8];
    switch (t) {
        case Type::int8: {
            auto v = static_cast<std::int8_t>(value);
            std::memcpy(b, &v, 1);
            break;
        }
        case Type::uint8: {
            auto v = static_cast<std::uint8_t>(value);
            std::memcpy(b, &v, 1);
            break;
        }
        case Type::int16: {
            auto v = static_cast<std::int16_t>(value);
            std::memcpy(b, &v, 2);
            break;
        }
        case Type::uint16: {
            auto v = static_cast<std::uint16_t>(value);
            std::memcpy(b, &v, 2);
            break;
        }
        case Type::int32: {
            auto v = static_cast<std::int32_t>(value);
            std::memcpy(b, &v, 4);
            break;
        }
        case Type::uint32: {
            auto v = static_cast<std::uint32_t>(value);
            std::memcpy(b, &v, 4);
            break;
        }
        case Type::float32: {
            auto v = static_cast<float>(value);
            std::memcpy(b, &v, 4);
            break;
        }
        case Type::float64: std::memcpy(b, &value, 8); break;
    }
    const std::size_t n = info(t).size;
    if (swap)
        for (std::size_t i = 0; i < n; ++i) p[i] = b[n - 1 - i];
    else std::memcpy(p, b, n);
}

// One column of a binary element without lists into rows of `stride` bytes: the type's conversion chosen
// once per column (writing value by value through encode() spent most of a 250 MB write in the switch).
// Returns the index of the first value that does not fit the type, or `rows`.
template <class T>
std::size_t encode_column(const double* values, std::size_t rows, unsigned char* dst, std::size_t stride,
                          Type t, bool swap) {
    for (std::size_t r = 0; r < rows; ++r) {
        const double v = values[r];
        if constexpr (std::is_integral_v<T>) {
            if (!fits(t, v)) return r;
        }
        const T x = static_cast<T>(v);
        unsigned char* p = dst + r * stride;
        std::memcpy(p, &x, sizeof(T));
        if (swap) std::reverse(p, p + sizeof(T));
    }
    return rows;
}

std::size_t encode_column(Type t, const double* values, std::size_t rows, unsigned char* dst,
                          std::size_t stride, bool swap) {
    switch (t) {
        case Type::int8: return encode_column<std::int8_t>(values, rows, dst, stride, t, swap);
        case Type::uint8: return encode_column<std::uint8_t>(values, rows, dst, stride, t, swap);
        case Type::int16: return encode_column<std::int16_t>(values, rows, dst, stride, t, swap);
        case Type::uint16: return encode_column<std::uint16_t>(values, rows, dst, stride, t, swap);
        case Type::int32: return encode_column<std::int32_t>(values, rows, dst, stride, t, swap);
        case Type::uint32: return encode_column<std::uint32_t>(values, rows, dst, stride, t, swap);
        case Type::float32: return encode_column<float>(values, rows, dst, stride, t, swap);
        case Type::float64: return encode_column<double>(values, rows, dst, stride, t, swap);
    }
    return rows;
}

}  // namespace

struct Writer::Impl {
    fs::path path;
    std::string name;
    std::optional<AtomicFile> atomic;  // the temporary; removed unless finish() commits it
    std::FILE* file = nullptr;         // atomic->file()
    Header header;
    bool swap = false;
    std::size_t element = 0;
    std::uint64_t row = 0;
    std::vector<char> out;
    bool finished = false;

    Error fail(const std::string& why) const { return make_error(name + ": " + why); }

    Status flush() {
        if (!out.empty() && std::fwrite(out.data(), 1, out.size(), file) != out.size())
            return fail(std::string("write failed: ") + std::strerror(errno));
        out.clear();
        return {};
    }

    Status put(Type t, double v, const std::string& prop) {
        if (!fits(t, v))
            return fail("value " + std::to_string(v) + " of '" + prop + "' does not fit type " +
                        type_name(t));
        if (header.format == Format::ascii) {
            char b[64];
            std::to_chars_result r;
            if (is_integer(t)) r = std::to_chars(b, b + sizeof b, static_cast<long long>(v));
            else if (t == Type::float32) r = std::to_chars(b, b + sizeof b, static_cast<float>(v));
            else r = std::to_chars(b, b + sizeof b, v);
            out.insert(out.end(), b, r.ptr);
            out.push_back(' ');
        } else {
            unsigned char b[8];
            encode(b, t, v, swap);
            out.insert(out.end(), b, b + type_size(t));
        }
        return {};
    }
};

Writer::Writer(std::unique_ptr<Impl> impl) : m_impl(std::move(impl)) {}
Writer::Writer(Writer&&) noexcept = default;
Writer& Writer::operator=(Writer&&) noexcept = default;
Writer::~Writer() = default;

Result<Writer> Writer::create(const fs::path& path, const Header& header) {
    auto impl = std::make_unique<Impl>();
    impl->path = path;
    impl->name = path.string();
    impl->header = header;
    for (const Element& e : header.elements)
        if (e.count > 0 && e.properties.empty())
            return impl->fail("element '" + e.name + "' has rows but no properties");
    impl->swap = (header.format == Format::binary_big_endian) == kLittleEndianHost;
    auto atomic = AtomicFile::create(path);
    if (!atomic) return atomic.error();
    impl->atomic.emplace(std::move(*atomic));
    impl->file = impl->atomic->file();
    const std::string text = header.to_string();
    impl->out.assign(text.begin(), text.end());
    if (auto s = impl->flush(); !s) return s.error();
    impl->out.reserve(kBufferBytes + 4096);
    return Writer(std::move(impl));
}

Status Writer::write_rows(const Chunk& chunk) {
    Impl& m = *m_impl;
    while (m.element < m.header.elements.size() && m.header.elements[m.element].count == m.row &&
           m.header.elements[m.element].name != chunk.element.name) {
        ++m.element;
        m.row = 0;
    }
    if (m.element >= m.header.elements.size())
        return m.fail("write_rows(): no element '" + chunk.element.name + "' left to write");
    const Element& e = m.header.elements[m.element];
    if (e.name != chunk.element.name)
        return m.fail("write_rows(): expected rows of element '" + e.name + "', got '" + chunk.element.name +
                      "'");
    if (m.row + chunk.rows > e.count)
        return m.fail("write_rows(): element '" + e.name + "' declares " + std::to_string(e.count) +
                      " rows, got more");
    // Map the header's properties to the chunk's columns by name.
    std::vector<int> map(e.properties.size());
    for (std::size_t p = 0; p < e.properties.size(); ++p) {
        map[p] = chunk.find(e.properties[p].name);
        if (map[p] < 0 || chunk.element.properties[map[p]].is_list != e.properties[p].is_list ||
            static_cast<std::size_t>(map[p]) >= chunk.columns.size())
            return m.fail("write_rows(): chunk has no " +
                          std::string(e.properties[p].is_list ? "list " : "") + "property '" +
                          e.properties[p].name + "'");
        const Column& c = chunk.columns[map[p]];
        if (e.properties[p].is_list
                ? c.offsets.size() < chunk.rows + 1 || c.offsets[chunk.rows] > c.values.size()
                : c.values.size() < chunk.rows)
            return m.fail("write_rows(): column '" + e.properties[p].name + "' is shorter than the chunk");
    }
    const bool lists = std::any_of(e.properties.begin(), e.properties.end(),
                                   [](const Property& prop) { return prop.is_list; });
    if (m.header.format != Format::ascii && !lists) {
        std::size_t row_bytes = 0;
        for (const Property& prop : e.properties) row_bytes += type_size(prop.type);
        const std::size_t per_block = std::max<std::size_t>(1, kBufferBytes / row_bytes);
        for (std::size_t first = 0; first < chunk.rows; first += per_block) {
            const std::size_t rows = std::min(per_block, chunk.rows - first);
            const std::size_t base = m.out.size();
            m.out.resize(base + rows * row_bytes);
            auto* dst = reinterpret_cast<unsigned char*>(m.out.data()) + base;
            for (std::size_t p = 0, offset = 0; p < e.properties.size(); ++p) {
                const Property& prop = e.properties[p];
                const double* values = chunk.columns[std::size_t(map[p])].values.data() + first;
                const std::size_t bad =
                    encode_column(prop.type, values, rows, dst + offset, row_bytes, m.swap);
                if (bad < rows) return m.put(prop.type, values[bad], prop.name);  // names the value
                offset += type_size(prop.type);
            }
            if (m.out.size() >= kBufferBytes)
                if (auto s = m.flush(); !s) return s;
        }
        m.row += chunk.rows;
        return {};
    }
    for (std::size_t r = 0; r < chunk.rows; ++r) {
        for (std::size_t p = 0; p < e.properties.size(); ++p) {
            const Property& prop = e.properties[p];
            const Column& c = chunk.columns[map[p]];
            if (!prop.is_list) {
                if (auto s = m.put(prop.type, c.values[r], prop.name); !s) return s;
                continue;
            }
            const std::uint32_t b = c.offsets[r], en = c.offsets[r + 1];
            if (en < b) return m.fail("write_rows(): list offsets of '" + prop.name + "' decrease");
            if (auto s = m.put(prop.count_type, en - b, prop.name); !s) return s;
            for (std::uint32_t i = b; i < en; ++i)
                if (auto s = m.put(prop.type, c.values[i], prop.name); !s) return s;
        }
        if (m.header.format == Format::ascii) m.out.back() = '\n';
        if (m.out.size() >= kBufferBytes)
            if (auto s = m.flush(); !s) return s;
    }
    m.row += chunk.rows;
    return {};
}

Status Writer::finish() {
    Impl& m = *m_impl;
    if (m.finished) return m.fail("finish(): called twice");
    for (std::size_t i = m.element; i < m.header.elements.size(); ++i) {
        const std::uint64_t done = i == m.element ? m.row : 0;
        if (done != m.header.elements[i].count)
            return m.fail("finish(): element '" + m.header.elements[i].name + "' has " +
                          std::to_string(done) + " of " + std::to_string(m.header.elements[i].count) +
                          " rows");
    }
    if (auto s = m.flush(); !s) return s;
    m.file = nullptr;
    m.finished = true;
    if (Status s = m.atomic->commit(); !s) return s;
    return {};
}

}  // namespace sffd::ply
