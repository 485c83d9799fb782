// ply::Reader: streaming rows out of ASCII and binary PLY files (see ply.h).
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cstring>

#include "runtime/assets/formats/surface/ply.h"
#include "runtime/assets/formats/surface/ply_detail.h"

namespace sffd::ply {
using namespace detail;
namespace fs = std::filesystem;

namespace {

constexpr std::size_t kMaxHeaderBytes = 64 * 1024;
constexpr std::size_t kMaxChunkListValues = std::size_t(1) << 22;  // 32 MB of doubles per chunk of list rows

// Decodes one binary scalar; `swap` for big-endian data on this little-endian machine.
inline double decode(const unsigned char* p, Type t, bool swap) {
    unsigned char b[8];
    const std::size_t n = info(t).size;
    if (swap)
        for (std::size_t i = 0; i < n; ++i) b[i] = p[n - 1 - i];
    else std::memcpy(b, p, n);
    switch (t) {
        case Type::int8: {
            std::int8_t v;
            std::memcpy(&v, b, 1);
            return v;
        }
        case Type::uint8: return b[0];
        case Type::int16: {
            std::int16_t v;
            std::memcpy(&v, b, 2);
            return v;
        }
        case Type::uint16: {
            std::uint16_t v;
            std::memcpy(&v, b, 2);
            return v;
        }
        case Type::int32: {
            std::int32_t v;
            std::memcpy(&v, b, 4);
            return v;
        }
        case Type::uint32: {
            std::uint32_t v;
            std::memcpy(&v, b, 4);
            return v;
        }
        case Type::float32: {
            float v;
            std::memcpy(&v, b, 4);
            return static_cast<double>(v);
        }
        case Type::float64: {
            double v;
            std::memcpy(&v, b, 8);
            return v;
        }
    }
    return 0.0;
}

// decode() of `rows` values `stride` bytes apart into out[0 .. rows-1], one loop per type and byte order.
template <class T>
void decode_as(const unsigned char* p, std::size_t stride, std::size_t rows, bool swap, double* out) {
    for (std::size_t r = 0; r < rows; ++r, p += stride) {
        unsigned char b[sizeof(T)];
        std::memcpy(b, p, sizeof(T));
        if (swap) std::reverse(b, b + sizeof(T));
        T v;
        std::memcpy(&v, b, sizeof(T));
        out[r] = static_cast<double>(v);
    }
}
template <class T>
void decode_typed(const unsigned char* p, std::size_t stride, std::size_t rows, bool swap, double* out) {
    if (swap) decode_as<T>(p, stride, rows, true, out);
    else decode_as<T>(p, stride, rows, false, out);
}
void decode_column(const unsigned char* p, std::size_t stride, std::size_t rows, Type t, bool swap,
                   double* out) {
    switch (t) {
        case Type::int8: return decode_typed<std::int8_t>(p, stride, rows, swap, out);
        case Type::uint8: return decode_typed<std::uint8_t>(p, stride, rows, swap, out);
        case Type::int16: return decode_typed<std::int16_t>(p, stride, rows, swap, out);
        case Type::uint16: return decode_typed<std::uint16_t>(p, stride, rows, swap, out);
        case Type::int32: return decode_typed<std::int32_t>(p, stride, rows, swap, out);
        case Type::uint32: return decode_typed<std::uint32_t>(p, stride, rows, swap, out);
        case Type::float32: return decode_typed<float>(p, stride, rows, swap, out);
        case Type::float64: return decode_typed<double>(p, stride, rows, swap, out);
    }
}

}  // namespace

struct Reader::Impl {
    fs::path path;
    std::string name;
    std::FILE* file = nullptr;
    Header header;
    std::uint64_t size = 0;
    std::uint64_t data_offset = 0;
    bool swap = false;  // binary data in the other byte order

    std::vector<unsigned char> buf;
    std::size_t pos = 0, len = 0;
    bool eof = false;

    std::size_t element = 0;  // current element index
    std::uint64_t row = 0;    // rows of the current element already read

    ~Impl() {
        if (file) std::fclose(file);
    }

    Error fail(const std::string& why) const { return make_error(name + ": " + why); }

    bool fill() {
        if (eof) return false;
        if (pos > 0) {
            std::memmove(buf.data(), buf.data() + pos, len - pos);
            len -= pos;
            pos = 0;
        }
        const std::size_t got = std::fread(buf.data() + len, 1, buf.size() - len, file);
        if (got == 0) eof = true;
        len += got;
        return got > 0;
    }

    bool read_bytes(unsigned char* dst, std::size_t n) {
        while (n > 0) {
            if (pos == len && !fill()) return false;
            const std::size_t k = std::min(n, len - pos);
            std::memcpy(dst, buf.data() + pos, k);
            pos += k;
            dst += k;
            n -= k;
        }
        return true;
    }

    // Next whitespace-separated token of ASCII data (may span buffer refills).
    bool token(std::string_view& out) {
        while (true) {
            while (pos < len && std::isspace(buf[pos])) ++pos;
            if (pos < len) break;
            if (!fill()) return false;
        }
        std::size_t end = pos;
        while (true) {
            while (end < len && !std::isspace(buf[end])) ++end;
            if (end < len || eof) break;
            const std::size_t offset = end - pos;
            if (pos == 0 && len == buf.size()) return false;  // a token longer than the buffer: garbage
            fill();
            end = pos + offset;
        }
        out = std::string_view(reinterpret_cast<const char*>(buf.data()) + pos, end - pos);
        pos = end;
        return true;
    }

    std::string where() const {
        return "element '" + header.elements[element].name + "' row " + std::to_string(row);
    }

    Result<double> ascii_value(Type t) {
        std::string_view tok;
        if (!token(tok)) return fail("truncated data in " + where());
        double v = 0.0;
        const char* b = tok.data();
        const char* e = b + tok.size();
        if (*b == '+') ++b;
        auto [ptr, ec] = std::from_chars(b, e, v);
        if (ec == std::errc::result_out_of_range) {
            return fail("number out of range '" + std::string(tok.substr(0, 40)) + "' in " + where());
        }
        if (ec != std::errc() || ptr != e)
            return fail("malformed number '" + std::string(tok.substr(0, 40)) + "' in " + where());
        if (!fits(t, v))
            return fail("value '" + std::string(tok.substr(0, 40)) + "' does not fit type " + type_name(t) +
                        " in " + where());
        if (t == Type::float32) v = static_cast<double>(static_cast<float>(v));
        return v;
    }

    Result<double> binary_value(Type t) {
        unsigned char b[8];
        if (!read_bytes(b, type_size(t))) return fail("truncated data in " + where());
        return decode(b, t, swap);
    }

    Result<double> value(Type t) { return header.format == Format::ascii ? ascii_value(t) : binary_value(t); }

    Status read_row(const Element& e, std::vector<Column>* cols) {
        for (std::size_t p = 0; p < e.properties.size(); ++p) {
            const Property& prop = e.properties[p];
            if (!prop.is_list) {
                auto v = value(prop.type);
                if (!v) return v.error();
                if (cols) (*cols)[p].values.push_back(*v);
                continue;
            }
            auto n = value(prop.count_type);
            if (!n) return n.error();
            if (*n < 0 || *n > kMaxListLength)
                return fail("list length " + std::to_string(static_cast<long long>(*n)) + " of '" +
                            prop.name + "' out of range in " + where());
            const auto count = static_cast<std::uint32_t>(*n);
            for (std::uint32_t i = 0; i < count; ++i) {
                auto v = value(prop.type);
                if (!v) return v.error();
                if (cols) (*cols)[p].values.push_back(*v);
            }
            if (cols) (*cols)[p].offsets.push_back(static_cast<std::uint32_t>((*cols)[p].values.size()));
        }
        return {};
    }

    // Fixed-size binary rows: decode the rows column by column, a few hundred rows at a time so the raw
    // rows stay in cache across the columns (a whole chunk of a 62-property 3DGS file is 16 MB), with the
    // type and byte order chosen once per column, not per value.
    Status read_fixed_rows(const Element& e, std::size_t n, std::vector<Column>& cols) {
        const std::size_t stride = e.row_size();
        raw.resize(stride * n);  // kept between calls: no allocation or zeroing per chunk
        if (!read_bytes(raw.data(), stride * n)) return fail("truncated data in " + where());
        for (std::size_t p = 0; p < e.properties.size(); ++p) cols[p].values.resize(n);
        constexpr std::size_t kRowBlock = 256;
        for (std::size_t r0 = 0; r0 < n; r0 += kRowBlock) {
            const std::size_t rows = std::min(kRowBlock, n - r0);
            std::size_t offset = 0;
            for (std::size_t p = 0; p < e.properties.size(); ++p) {
                const Type t = e.properties[p].type;
                decode_column(raw.data() + r0 * stride + offset, stride, rows, t, swap,
                              cols[p].values.data() + r0);
                offset += type_size(t);
            }
        }
        return {};
    }
    std::vector<unsigned char> raw;  // read_fixed_rows' row buffer

    void advance_element() {
        ++element;
        row = 0;
    }
};

Reader::Reader(std::unique_ptr<Impl> impl) : m_impl(std::move(impl)) {}
Reader::Reader(Reader&&) noexcept = default;
Reader& Reader::operator=(Reader&&) noexcept = default;
Reader::~Reader() = default;

const Header& Reader::header() const { return m_impl->header; }
const fs::path& Reader::path() const { return m_impl->path; }
std::uint64_t Reader::file_size() const { return m_impl->size; }
std::size_t Reader::current_element() const { return m_impl->element; }

Result<Reader> Reader::open(const fs::path& path) {
    auto impl = std::make_unique<Impl>();
    impl->path = path;
    impl->name = path.string();
    // O_NONBLOCK and fstat on the open descriptor: a FIFO or device named as input is refused, not waited on.
    const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0)
        return impl->fail(errno == ENOENT ? std::string("no such file")
                                          : std::string("cannot open: ") + std::strerror(errno));
    struct stat st {};
    if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        ::close(fd);
        return impl->fail("not a regular file");
    }
    impl->size = static_cast<std::uint64_t>(st.st_size);
    impl->file = ::fdopen(fd, "rb");
    if (!impl->file) {
        ::close(fd);
        return impl->fail(std::string("cannot open: ") + std::strerror(errno));
    }

    std::string head(static_cast<std::size_t>(std::min<std::uint64_t>(impl->size, kMaxHeaderBytes)), '\0');
    if (std::fread(head.data(), 1, head.size(), impl->file) != head.size())
        return impl->fail("read error in header");
    std::size_t header_bytes = 0;
    auto header = parse_header(head, impl->name, header_bytes);
    if (!header) return header.error();
    impl->header = std::move(*header);
    impl->data_offset = header_bytes;
    impl->swap = (impl->header.format == Format::binary_big_endian) == kLittleEndianHost;

    // Every element's rows need a minimum number of bytes: refuse counts the file cannot hold, so no
    // reader ever allocates or loops on a hostile count.
    const std::uint64_t remaining = impl->size - header_bytes;
    long double need = 0;
    for (const Element& e : impl->header.elements) {
        const std::size_t min_row =
            impl->header.format == Format::ascii ? 2 * e.properties.size() : e.row_size();
        need += static_cast<long double>(e.count) * static_cast<long double>(min_row);
        if (need > static_cast<long double>(remaining) + 1)
            return impl->fail("element '" + e.name + "' declares " + std::to_string(e.count) +
                              " rows, more than the file's " + std::to_string(remaining) +
                              " data bytes can hold");
    }

    impl->buf.resize(kBufferBytes);
    if (std::fseek(impl->file, static_cast<long>(header_bytes), SEEK_SET) != 0)
        return impl->fail("cannot seek");
    return Reader(std::move(impl));
}

Status Reader::seek_element(std::string_view element) {
    Impl& m = *m_impl;
    const int target = m.header.find(element);
    if (target < 0) return m.fail("no element '" + std::string(element) + "'");
    if (static_cast<std::size_t>(target) < m.element ||
        (static_cast<std::size_t>(target) == m.element && m.row > 0))
        return m.fail("element '" + std::string(element) +
                      "' was already read (PLY elements are read in order)");
    while (m.element < static_cast<std::size_t>(target)) {
        const Element& e = m.header.elements[m.element];
        if (m.header.format != Format::ascii && !e.has_lists()) {
            // Skip in one seek: drop the buffered bytes and move the file position.
            const std::uint64_t skip = (e.count - m.row) * e.row_size();
            const std::uint64_t buffered = m.len - m.pos;
            if (skip <= buffered) {
                m.pos += static_cast<std::size_t>(skip);
            } else {
                if (std::fseek(m.file, static_cast<long>(skip - buffered), SEEK_CUR) != 0)
                    return m.fail("cannot seek");
                m.pos = m.len = 0;
            }
        } else {
            for (; m.row < e.count; ++m.row)
                if (auto s = m.read_row(e, nullptr); !s) return s;
        }
        m.advance_element();
    }
    return {};
}

Result<std::size_t> Reader::read_rows(std::size_t max_rows, Chunk& chunk) {
    Impl& m = *m_impl;
    if (m.element >= m.header.elements.size()) {
        chunk.clear();
        return std::size_t{0};
    }
    const Element& e = m.header.elements[m.element];
    if (chunk.element.name != e.name || chunk.columns.size() != e.properties.size()) chunk.reset(e);
    else {
        chunk.element = e;
        chunk.clear();
        for (std::size_t i = 0; i < e.properties.size(); ++i)
            if (e.properties[i].is_list) chunk.columns[i].offsets.push_back(0);
    }
    const std::uint64_t left = e.count - m.row;
    if (left == 0) {
        m.advance_element();
        return std::size_t{0};
    }
    const auto n =
        static_cast<std::size_t>(std::min<std::uint64_t>(left, std::max<std::size_t>(max_rows, 1)));
    if (m.header.format != Format::ascii && !e.has_lists()) {
        if (auto s = m.read_fixed_rows(e, n, chunk.columns); !s) return s.error();
        m.row += n;
    } else {
        // Rows with lists can be huge (2^20 entries each): a chunk stops early once it holds
        // kMaxChunkListValues list entries, so callers can budget before the next chunk is expanded.
        std::size_t r = 0;
        for (; r < n; ++r, ++m.row) {
            if (auto s = m.read_row(e, &chunk.columns); !s) return s.error();
            std::size_t values = 0;
            for (std::size_t i = 0; i < e.properties.size(); ++i)
                if (e.properties[i].is_list) values += chunk.columns[i].values.size();
            if (values >= kMaxChunkListValues) {
                ++r, ++m.row;
                break;
            }
        }
        chunk.rows = r;
        return r;
    }
    chunk.rows = n;
    return n;
}

}  // namespace sffd::ply
