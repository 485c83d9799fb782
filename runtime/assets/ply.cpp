#include "runtime/assets/ply.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>

#include "runtime/core/atomic_file.h"
#include "runtime/core/log.h"

namespace sffd::ply {
namespace fs = std::filesystem;

namespace {

constexpr std::size_t kMaxHeaderBytes = 64 * 1024;
constexpr std::size_t kBufferBytes = 1 << 20;
constexpr std::size_t kMaxChunkListValues = std::size_t(1) << 22;  // 32 MB of doubles per chunk of list rows

struct TypeInfo {
    Type type;
    const char* name;
    const char* alias;
    std::size_t size;
    double lo, hi;  // representable range (integers); floats use +-inf
};

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr TypeInfo kTypes[] = {
    {Type::int8, "char", "int8", 1, -128.0, 127.0},
    {Type::uint8, "uchar", "uint8", 1, 0.0, 255.0},
    {Type::int16, "short", "int16", 2, -32768.0, 32767.0},
    {Type::uint16, "ushort", "uint16", 2, 0.0, 65535.0},
    {Type::int32, "int", "int32", 4, -2147483648.0, 2147483647.0},
    {Type::uint32, "uint", "uint32", 4, 0.0, 4294967295.0},
    {Type::float32, "float", "float32", 4, -kInf, kInf},
    {Type::float64, "double", "float64", 8, -kInf, kInf},
};

const TypeInfo& info(Type t) { return kTypes[static_cast<int>(t)]; }
bool is_integer(Type t) { return t != Type::float32 && t != Type::float64; }

std::string trim(std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '\r')) s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
    return std::string(s);
}

std::vector<std::string_view> split_words(std::string_view s) {
    std::vector<std::string_view> words;
    std::size_t i = 0;
    while (i < s.size()) {
        while (i < s.size() && (s[i] == ' ' || s[i] == '\t' || s[i] == '\r')) ++i;
        std::size_t j = i;
        while (j < s.size() && s[j] != ' ' && s[j] != '\t' && s[j] != '\r') ++j;
        if (j > i) words.push_back(s.substr(i, j - i));
        i = j;
    }
    return words;
}

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

// Integer-typed values must be integral and in range; NaN is only representable in float types.
bool fits(Type t, double v) {
    if (!is_integer(t)) return true;
    return std::isfinite(v) && v == std::floor(v) && v >= info(t).lo && v <= info(t).hi;
}

constexpr bool kLittleEndianHost = std::endian::native == std::endian::little;

}  // namespace

std::size_t type_size(Type t) { return info(t).size; }
const char* type_name(Type t) { return info(t).name; }
const char* format_name(Format f) {
    switch (f) {
        case Format::ascii: return "ascii";
        case Format::binary_little_endian: return "binary_little_endian";
        case Format::binary_big_endian: return "binary_big_endian";
    }
    return "?";
}

Result<Type> parse_type(std::string_view name) {
    for (const TypeInfo& t : kTypes)
        if (name == t.name || name == t.alias) return t.type;
    return make_error("unknown PLY type '" + std::string(name) + "'");
}

int Element::find(std::string_view property) const {
    for (std::size_t i = 0; i < properties.size(); ++i)
        if (properties[i].name == property) return static_cast<int>(i);
    return -1;
}

bool Element::has_lists() const {
    return std::any_of(properties.begin(), properties.end(), [](const Property& p) { return p.is_list; });
}

std::size_t Element::row_size() const {
    std::size_t n = 0;
    for (const Property& p : properties) n += p.is_list ? type_size(p.count_type) : type_size(p.type);
    return n;
}

int Header::find(std::string_view element) const {
    for (std::size_t i = 0; i < elements.size(); ++i)
        if (elements[i].name == element) return static_cast<int>(i);
    return -1;
}

std::string Header::to_string() const {
    std::string s = "ply\nformat ";
    s += format_name(format);
    s += " 1.0\n";
    for (const std::string& c : comments) {
        if (c.rfind("obj_info ", 0) == 0) s += c + "\n";
        else s += "comment " + c + "\n";
    }
    for (const Element& e : elements) {
        s += "element " + e.name + " " + std::to_string(e.count) + "\n";
        for (const Property& p : e.properties) {
            if (p.is_list)
                s += std::string("property list ") + type_name(p.count_type) + " " + type_name(p.type) + " " +
                     p.name + "\n";
            else s += std::string("property ") + type_name(p.type) + " " + p.name + "\n";
        }
    }
    s += "end_header\n";
    return s;
}

void Chunk::clear() {
    rows = 0;
    for (Column& c : columns) {
        c.values.clear();
        c.offsets.clear();
    }
}

void Chunk::reset(const Element& e) {
    element = e;
    rows = 0;
    columns.assign(e.properties.size(), Column{});
    for (std::size_t i = 0; i < e.properties.size(); ++i)
        if (e.properties[i].is_list) columns[i].offsets.push_back(0);
}

Result<Header> parse_header(std::string_view text, const std::string& name, std::size_t& header_bytes) {
    auto fail = [&](const std::string& why) { return make_error(name + ": " + why); };
    Header h;
    std::size_t pos = 0;
    int line_no = 0;
    bool have_format = false;
    constexpr int kMaxUnknownWarnings = 5;
    int unknown_lines = 0;
    auto next_line = [&](std::string_view& line) {
        if (pos >= text.size()) return false;
        const std::size_t nl = text.find('\n', pos);
        if (nl == std::string_view::npos) return false;  // a header line must end with a newline
        line = text.substr(pos, nl - pos);
        pos = nl + 1;
        ++line_no;
        return true;
    };
    std::string_view line;
    if (!next_line(line) || trim(line) != "ply")
        return fail(text.substr(0, 3) == "ply" ? "truncated PLY header"
                                               : "not a PLY file (bad magic: expected 'ply')");
    while (true) {
        if (!next_line(line)) return fail("truncated PLY header (no end_header)");
        const auto words = split_words(line);
        const std::string where = "header line " + std::to_string(line_no) + ": ";
        if (words.empty()) continue;
        const std::string_view key = words[0];
        if (key == "end_header") break;
        if (key == "comment") {
            const std::size_t at = line.find("comment") + 7;
            h.comments.push_back(trim(line.substr(std::min(line.size(), at + 1))));
        } else if (key == "obj_info") {
            h.comments.push_back("obj_info " +
                                 trim(line.substr(std::min(line.size(), line.find("obj_info") + 9))));
        } else if (key == "format") {
            if (have_format) return fail(where + "duplicate format line");
            if (words.size() != 3) return fail(where + "expected 'format <type> 1.0'");
            if (words[1] == "ascii") h.format = Format::ascii;
            else if (words[1] == "binary_little_endian") h.format = Format::binary_little_endian;
            else if (words[1] == "binary_big_endian") h.format = Format::binary_big_endian;
            else return fail(where + "unknown format '" + std::string(words[1]) + "'");
            if (words[2] != "1.0" && words[2] != "1")
                return fail(where + "unsupported PLY version '" + std::string(words[2]) + "'");
            have_format = true;
        } else if (key == "element") {
            if (words.size() != 3) return fail(where + "expected 'element <name> <count>'");
            Element e;
            e.name = std::string(words[1]);
            if (h.find(e.name) >= 0) return fail(where + "duplicate element '" + e.name + "'");
            const auto c = words[2];
            auto [ptr, ec] = std::from_chars(c.data(), c.data() + c.size(), e.count);
            if (ec != std::errc() || ptr != c.data() + c.size())
                return fail(where + "bad count '" + std::string(c) + "' for element '" + e.name + "'");
            h.elements.push_back(std::move(e));
        } else if (key == "property") {
            if (h.elements.empty()) return fail(where + "property before any element");
            Element& e = h.elements.back();
            Property p;
            if (words.size() >= 2 && words[1] == "list") {
                if (words.size() != 5)
                    return fail(where + "expected 'property list <count type> <type> <name>'");
                auto ct = parse_type(words[2]);
                if (!ct) return fail(where + ct.message());
                auto vt = parse_type(words[3]);
                if (!vt) return fail(where + vt.message());
                if (!is_integer(*ct)) return fail(where + "list count type must be an integer type");
                p.is_list = true;
                p.count_type = *ct;
                p.type = *vt;
                p.name = std::string(words[4]);
            } else {
                if (words.size() != 3) return fail(where + "expected 'property <type> <name>'");
                auto t = parse_type(words[1]);
                if (!t) return fail(where + t.message());
                p.type = *t;
                p.name = std::string(words[2]);
            }
            if (e.find(p.name) >= 0)
                return fail(where + "duplicate property '" + p.name + "' in element '" + e.name + "'");
            e.properties.push_back(std::move(p));
        } else {
            // Writers add their own lines (Blender 2.4's "Created by Blender3D ..." in assimp's Wuson.ply);
            // readers such as rply and assimp skip them. Skipped with a warning, a few at most, so a
            // hostile header of junk lines cannot flood the log (it still needs an end_header).
            if (++unknown_lines <= kMaxUnknownWarnings)
                log::warn(name, ": ", where, "unknown keyword '", std::string(key).substr(0, 64),
                          "', line ignored");
            else if (unknown_lines == kMaxUnknownWarnings + 1)
                log::warn(name, ": further unknown header lines ignored without a warning");
        }
    }
    if (!have_format) return fail("PLY header has no format line");
    for (const Element& e : h.elements)
        if (e.count > 0 && e.properties.empty())
            return fail("element '" + e.name + "' has rows but no properties");
    header_bytes = pos;
    return h;
}

// ---------------------------------------------------------------------------------------------------
// Reader

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

// ---------------------------------------------------------------------------------------------------
// Writer

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
