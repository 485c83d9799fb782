// Streaming PLY reader and writer.
//
// PLY files can be far larger than memory (`splatffd deform` streams multi-GB scans with < 256 MB peak),
// so neither side ever holds a whole element: the reader hands out chunks of up to N rows, the writer
// takes chunks and appends them. Everything else in runtime/assets (importers, converters) is built on
// these two classes.
//
// Reading:
//     auto reader = ply::Reader::open("scan.ply");          // parses and validates the header
//     if (!reader) return reader.error();                    // message: "scan.ply: <problem>"
//     const ply::Header& h = reader->header();
//     if (auto s = reader->seek_element("vertex"); !s) ...   // skips earlier elements (e.g. none)
//     ply::Chunk chunk;
//     while (true) {
//         auto rows = reader->read_rows(65536, chunk);       // up to 65536 rows of "vertex"
//         if (!rows) return rows.error();                    // truncated data, NaN-free not checked here
//         if (*rows == 0) break;                             // element finished
//         const auto& x = chunk.columns[chunk.find("x")].values;   // x[0 .. rows-1] as double
//     }
//
// Every scalar PLY type (int8 .. uint32, float32, float64) converts to double exactly, so a Chunk's
// `double` columns are a lossless copy of the file: writing them back with the same property types
// reproduces the original values bit for bit. List properties (e.g. face vertex_indices, or the rare
// list on vertices) are kept as flat values plus per-row offsets.
//
// Elements must be read in file order (the format has no index). seek_element() skips whole elements
// (fast for binary files without lists: one fseek); read_rows() on an element that is not the current
// one is an error. After the vertex element you may stop: trailing elements are not required to be read.
//
// Writing (atomic: rows go to `<path>.tmp-<pid>`, finish() fsyncs and renames; a Writer destroyed
// without finish() removes the temporary and leaves any old file untouched):
//     ply::Header out;                       // format, comments, elements with counts and properties
//     out.format = ply::Format::binary_little_endian;
//     out.elements.push_back(reader->header().elements[v]);   // same properties, same types, same count
//     auto writer = ply::Writer::create("out.ply", out);
//     writer->write_rows(chunk);             // chunk.element must name the element being written
//     writer->finish();
// The element's row count is fixed in the header; finish() fails if fewer or more rows were written.
//
// Validation (all errors name the file): bad magic, unknown format or type, properties outside an
// element, truncated header (no end_header within 64 KiB), counts whose minimum row size cannot fit in
// the rest of the file, list counts that are negative or exceed kMaxListLength, truncated or malformed
// data rows (with the element name and row number). Header lines with an unknown keyword (writers'
// own notes, e.g. "Created by Blender3D ...") are skipped with a warning naming the file, line and keyword.
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "runtime/core/result.h"

namespace sffd::ply {

enum class Format : std::uint8_t { ascii, binary_little_endian, binary_big_endian };
enum class Type : std::uint8_t { int8, uint8, int16, uint16, int32, uint32, float32, float64 };

std::size_t type_size(Type t);
const char* type_name(Type t);  // canonical names: char uchar short ushort int uint float double
Result<Type> parse_type(std::string_view name);  // also accepts int8 uint8 ... float32 float64
const char* format_name(Format f);

// A list never has more entries than this (hostile files declare 2^32 - 1 entries per row).
constexpr std::uint32_t kMaxListLength = 1u << 20;

struct Property {
    std::string name;
    Type type = Type::float32;  // value type (of the list entries for a list)
    bool is_list = false;
    Type count_type = Type::uint8;  // type of the list length, when is_list
};

struct Element {
    std::string name;
    std::uint64_t count = 0;
    std::vector<Property> properties;

    int find(std::string_view property) const;  // index or -1
    bool has_lists() const;
    std::size_t row_size() const;  // bytes per binary row; only meaningful without lists
};

struct Header {
    Format format = Format::binary_little_endian;
    std::vector<std::string>
        comments;  // text after "comment " (obj_info lines are kept with prefix "obj_info ")
    std::vector<Element> elements;

    int find(std::string_view element) const;  // index or -1
    std::string to_string() const;             // the header text, "ply\n" .. "end_header\n"
};

// One column per property of the element, in property order.
struct Column {
    std::vector<double> values;          // scalar: values[row]; list: entries of all rows back to back
    std::vector<std::uint32_t> offsets;  // list only: row r has values[offsets[r] .. offsets[r+1])
};

struct Chunk {
    Element element;  // the element these rows belong to (name, properties)
    std::size_t rows = 0;
    std::vector<Column> columns;  // columns.size() == element.properties.size()

    int find(std::string_view property) const { return element.find(property); }
    // Empties the rows but keeps the element and column capacity.
    void clear();
    // Sets up an empty chunk for `e` (used by writers that build chunks from scratch).
    void reset(const Element& e);
};

// Parses a header from the bytes of a file's beginning (exposed for tests and fuzzing). `name` is used
// in error messages. On success `header_bytes` is the offset of the first data byte.
Result<Header> parse_header(std::string_view text, const std::string& name, std::size_t& header_bytes);

class Reader {
public:
    static Result<Reader> open(const std::filesystem::path& path);
    Reader(Reader&&) noexcept;
    Reader& operator=(Reader&&) noexcept;
    ~Reader();

    const Header& header() const;
    const std::filesystem::path& path() const;
    std::uint64_t file_size() const;

    // Makes `element` the current element, skipping (and validating the syntax of) all elements before it.
    // It must not come before the current element.
    Status seek_element(std::string_view element);
    // Reads up to max_rows (>= 1) rows of the current element into `chunk` (replacing its contents).
    // Returns the number of rows read; 0 when the element is exhausted (then the next element becomes
    // current).
    Result<std::size_t> read_rows(std::size_t max_rows, Chunk& chunk);
    // Index of the current element in header().elements (== elements.size() at the end).
    std::size_t current_element() const;

private:
    struct Impl;
    explicit Reader(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> m_impl;
};

class Writer {
public:
    // Writes the header (every element's count is final) to a temporary next to `path`.
    // Only ascii and binary_little_endian/big_endian are accepted.
    static Result<Writer> create(const std::filesystem::path& path, const Header& header);
    Writer(Writer&&) noexcept;
    Writer& operator=(Writer&&) noexcept;
    ~Writer();  // without finish(): removes the temporary

    // Appends chunk.rows rows to the element currently being written (elements in header order).
    // chunk.element.name must match that element and its properties must match by name and list-ness
    // (values are converted to the header's declared types; out-of-range values are an error).
    Status write_rows(const Chunk& chunk);
    // Checks all counts were written, flushes, fsyncs and renames the temporary over `path`.
    Status finish();

private:
    struct Impl;
    explicit Writer(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> m_impl;
};

}  // namespace sffd::ply
