// Streaming PLY reader/writer: round trips in all three formats, big-endian input written by hand,
// double coordinates, lists, chunked reading, and refusal of malformed files with file-naming messages.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <string>

#include "runtime/assets/formats/surface/ply.h"

namespace fs = std::filesystem;
using namespace sffd;

namespace {

fs::path temp_dir() {
    fs::path d = fs::temp_directory_path() / ("sffd_ply_test_" + std::to_string(::getpid()));
    fs::create_directories(d);
    return d;
}

void write_bytes(const fs::path& p, const std::string& bytes) {
    std::ofstream f(p, std::ios::binary);
    f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

template <class T>
void append_be(std::string& s, T v) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    for (std::size_t i = 0; i < sizeof(T); ++i) s.push_back(static_cast<char>(b[sizeof(T) - 1 - i]));
}
template <class T>
void append_le(std::string& s, T v) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    for (std::size_t i = 0; i < sizeof(T); ++i) s.push_back(static_cast<char>(b[i]));
}

// Reads every element of a file fully (chunk size `n`) into one chunk per element.
std::vector<ply::Chunk> read_all(const fs::path& p, std::size_t n, ply::Header* header = nullptr) {
    auto r = ply::Reader::open(p);
    EXPECT_TRUE(r.ok()) << (r ? "" : r.message());
    if (!r) return {};
    if (header) *header = r->header();
    std::vector<ply::Chunk> all;
    for (const auto& e : r->header().elements) {
        ply::Chunk acc;
        acc.reset(e);
        ply::Chunk c;
        while (true) {
            auto got = r->read_rows(n, c);
            EXPECT_TRUE(got.ok()) << (got ? "" : got.message());
            if (!got || *got == 0) break;
            for (std::size_t k = 0; k < c.columns.size(); ++k) {
                auto& dst = acc.columns[k];
                const auto& src = c.columns[k];
                if (e.properties[k].is_list) {
                    const std::uint32_t base = static_cast<std::uint32_t>(dst.values.size());
                    for (std::size_t i = 1; i < src.offsets.size(); ++i)
                        dst.offsets.push_back(base + src.offsets[i]);
                }
                dst.values.insert(dst.values.end(), src.values.begin(), src.values.end());
            }
            acc.rows += *got;
        }
        all.push_back(std::move(acc));
    }
    return all;
}

// A test file with every scalar type, a double-precision position far from the origin and a face list.
struct Sample {
    ply::Header header;
    std::vector<ply::Chunk> chunks;
};

Sample make_sample(std::size_t vertices) {
    Sample s;
    ply::Element v{"vertex", vertices, {}};
    v.properties = {{"x", ply::Type::float64},  {"y", ply::Type::float64},       {"z", ply::Type::float64},
                    {"nx", ply::Type::float32}, {"red", ply::Type::uint8},       {"c", ply::Type::int8},
                    {"s", ply::Type::int16},    {"us", ply::Type::uint16},       {"i", ply::Type::int32},
                    {"u", ply::Type::uint32},   {"f_rest_0", ply::Type::float32}};
    ply::Element f{"face", 3, {}};
    f.properties = {{"vertex_indices", ply::Type::int32, true, ply::Type::uint8}, {"flag", ply::Type::uint8}};
    s.header.comments = {"made by ply_test", "obj_info test object"};
    s.header.elements = {v, f};
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1, 1);
    ply::Chunk cv;
    cv.reset(v);
    cv.rows = vertices;
    for (std::size_t r = 0; r < vertices; ++r) {
        cv.columns[0].values.push_back(4.0e6 + u(rng));  // needs double precision
        cv.columns[1].values.push_back(-3.0e6 + u(rng) * 1e-3);
        cv.columns[2].values.push_back(u(rng));
        cv.columns[3].values.push_back(static_cast<double>(static_cast<float>(u(rng))));
        cv.columns[4].values.push_back(static_cast<double>(r % 256));
        cv.columns[5].values.push_back(static_cast<double>(static_cast<int>(r % 256) - 128));
        cv.columns[6].values.push_back(-32768.0 + static_cast<double>(r));
        cv.columns[7].values.push_back(65535.0 - static_cast<double>(r % 1000));
        cv.columns[8].values.push_back(-2147483648.0 + static_cast<double>(r));
        cv.columns[9].values.push_back(4294967295.0 - static_cast<double>(r));
        cv.columns[10].values.push_back(r == 1 ? static_cast<double>(static_cast<float>(1e-38))
                                               : static_cast<double>(static_cast<float>(u(rng) * 1e3)));
    }
    ply::Chunk cf;
    cf.reset(f);
    cf.rows = 3;
    cf.columns[0].values = {0, 1, 2, 2, 1, 3, 0, 3, 1, 2};
    cf.columns[0].offsets = {0, 3, 6, 10};
    cf.columns[1].values = {1, 0, 255};
    s.chunks = {cv, cf};
    return s;
}

void write_sample(const fs::path& p, const Sample& s, ply::Format fmt, std::size_t chunk_rows) {
    ply::Header h = s.header;
    h.format = fmt;
    auto w = ply::Writer::create(p, h);
    ASSERT_TRUE(w.ok()) << w.message();
    // Write the vertex chunk in pieces to exercise streaming.
    const ply::Chunk& all = s.chunks[0];
    for (std::size_t start = 0; start < all.rows; start += chunk_rows) {
        ply::Chunk c;
        c.reset(all.element);
        c.rows = std::min(chunk_rows, all.rows - start);
        for (std::size_t k = 0; k < c.columns.size(); ++k)
            c.columns[k].values.assign(all.columns[k].values.begin() + static_cast<long>(start),
                                       all.columns[k].values.begin() + static_cast<long>(start + c.rows));
        ASSERT_TRUE(w->write_rows(c).ok());
    }
    ASSERT_TRUE(w->write_rows(s.chunks[1]).ok());
    auto st = w->finish();
    ASSERT_TRUE(st.ok()) << st.message();
}

void expect_same(const Sample& s, const std::vector<ply::Chunk>& got) {
    ASSERT_EQ(got.size(), 2u);
    for (int e = 0; e < 2; ++e) {
        ASSERT_EQ(got[e].rows, s.chunks[e].rows);
        for (std::size_t k = 0; k < got[e].columns.size(); ++k) {
            const auto& a = s.chunks[e].columns[k].values;
            const auto& b = got[e].columns[k].values;
            ASSERT_EQ(a.size(), b.size()) << "column " << k;
            for (std::size_t i = 0; i < a.size(); ++i)
                ASSERT_EQ(std::bit_cast<std::uint64_t>(a[i]), std::bit_cast<std::uint64_t>(b[i]))
                    << "element " << e << " column " << k << " row " << i << ": " << a[i] << " vs " << b[i];
            EXPECT_EQ(s.chunks[e].columns[k].offsets, got[e].columns[k].offsets);
        }
    }
}

}  // namespace

class PlyRoundTrip : public ::testing::TestWithParam<ply::Format> {};

TEST_P(PlyRoundTrip, AllTypesListsAndDoublesAreBitExact) {
    const fs::path p = temp_dir() / (std::string("rt_") + ply::format_name(GetParam()) + ".ply");
    const Sample s = make_sample(1000);
    write_sample(p, s, GetParam(), 97);
    ply::Header h;
    for (std::size_t n : {std::size_t{1}, std::size_t{64}, std::size_t{100000}}) {
        auto got = read_all(p, n, &h);
        expect_same(s, got);
    }
    EXPECT_EQ(h.format, GetParam());
    EXPECT_EQ(h.comments, s.header.comments);
    EXPECT_EQ(h.elements[0].properties[10].name, "f_rest_0");
    EXPECT_EQ(h.elements[0].properties[10].type, ply::Type::float32);
    EXPECT_TRUE(h.elements[1].properties[0].is_list);
    // No temporary left behind.
    for (const auto& entry : fs::directory_iterator(p.parent_path()))
        EXPECT_EQ(entry.path().string().find(".tmp-"), std::string::npos) << entry.path();
}

INSTANTIATE_TEST_SUITE_P(Formats, PlyRoundTrip,
                         ::testing::Values(ply::Format::ascii, ply::Format::binary_little_endian,
                                           ply::Format::binary_big_endian));

TEST(Ply, ReadsHandWrittenBigEndianAndSkipsElements) {
    // A file produced by another tool: big-endian, a leading "camera" element, floats and a list.
    std::string bytes =
        "ply\r\nformat binary_big_endian 1.0\r\ncomment hand made\r\nelement camera 1\r\nproperty float "
        "fx\r\n"
        "element vertex 2\r\nproperty float x\r\nproperty float y\r\nproperty float z\r\nproperty uchar "
        "red\r\n"
        "element face 1\r\nproperty list uchar uint vertex_index\r\nend_header\r\n";
    append_be(bytes, 500.0f);
    append_be(bytes, 1.5f);
    append_be(bytes, -2.25f);
    append_be(bytes, 3.0f);
    bytes.push_back('\xff');
    append_be(bytes, 0.125f);
    append_be(bytes, 1e10f);
    append_be(bytes, -0.0f);
    bytes.push_back('\x07');
    bytes.push_back('\x03');
    append_be(bytes, 0u);
    append_be(bytes, 1u);
    append_be(bytes, 70000u);
    const fs::path p = temp_dir() / "be.ply";
    write_bytes(p, bytes);

    auto r = ply::Reader::open(p);
    ASSERT_TRUE(r.ok()) << r.message();
    ASSERT_TRUE(r->seek_element("vertex").ok());
    ply::Chunk c;
    auto n = r->read_rows(10, c);
    ASSERT_TRUE(n.ok()) << n.message();
    ASSERT_EQ(*n, 2u);
    EXPECT_EQ(c.columns[c.find("x")].values, (std::vector<double>{1.5, 0.125}));
    EXPECT_EQ(c.columns[c.find("y")].values, (std::vector<double>{-2.25, static_cast<double>(1e10f)}));
    EXPECT_EQ(c.columns[c.find("red")].values, (std::vector<double>{255, 7}));
    n = r->read_rows(10, c);  // end of "vertex": 0 rows, then "face" is current
    ASSERT_TRUE(n.ok());
    ASSERT_EQ(*n, 0u);
    n = r->read_rows(10, c);
    ASSERT_TRUE(n.ok());
    ASSERT_EQ(*n, 1u);
    EXPECT_EQ(c.element.name, "face");
    EXPECT_EQ(c.columns[0].values, (std::vector<double>{0, 1, 70000}));
    EXPECT_EQ(c.columns[0].offsets, (std::vector<std::uint32_t>{0, 3}));
    EXPECT_FALSE(r->seek_element("camera").ok());  // already passed
}

TEST(Ply, SeekSkipsListElementsInAscii) {
    const fs::path p = temp_dir() / "skip.ply";
    write_bytes(p,
                "ply\nformat ascii 1.0\nelement face 2\nproperty list uchar int vertex_indices\n"
                "element vertex 3\nproperty double x\nend_header\n3 0 1 2\n4 0 1 2 3\n1.5\n-2e300\n  7\n");
    auto r = ply::Reader::open(p);
    ASSERT_TRUE(r.ok()) << r.message();
    ASSERT_TRUE(r->seek_element("vertex").ok());
    ply::Chunk c;
    auto n = r->read_rows(2, c);
    ASSERT_TRUE(n.ok());
    EXPECT_EQ(c.columns[0].values, (std::vector<double>{1.5, -2e300}));
    n = r->read_rows(2, c);
    ASSERT_TRUE(n.ok());
    EXPECT_EQ(*n, 1u);
    EXPECT_EQ(c.columns[0].values, (std::vector<double>{7}));
    n = r->read_rows(2, c);
    ASSERT_TRUE(n.ok());
    EXPECT_EQ(*n, 0u);
}

struct BadFile {
    const char* label;
    std::string bytes;
    const char* expected;  // substring of the error message
};

class PlyRefuses : public ::testing::TestWithParam<BadFile> {};

TEST_P(PlyRefuses, WithAMessageNamingTheFile) {
    const fs::path p = temp_dir() / (std::string("bad_") + GetParam().label + ".ply");
    write_bytes(p, GetParam().bytes);
    std::string message;
    auto r = ply::Reader::open(p);
    if (!r) {
        message = r.message();
    } else {
        ply::Chunk c;
        while (true) {
            auto n = r->read_rows(1000, c);
            if (!n) {
                message = n.message();
                break;
            }
            if (*n == 0 && r->current_element() >= r->header().elements.size()) break;
        }
    }
    ASSERT_FALSE(message.empty()) << "accepted " << GetParam().label;
    EXPECT_NE(message.find(p.string()), std::string::npos) << message;
    EXPECT_NE(message.find(GetParam().expected), std::string::npos) << message;
}

std::string header_le(const std::string& elements) {
    return "ply\nformat binary_little_endian 1.0\n" + elements + "end_header\n";
}

INSTANTIATE_TEST_SUITE_P(
    Malformed, PlyRefuses,
    ::testing::Values(
        BadFile{"magic", "PK\x03\x04 not a ply", "bad magic"}, BadFile{"empty", "", "bad magic"},
        BadFile{"no_end_header", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n",
                "truncated PLY header"},
        BadFile{"no_format", "ply\nelement vertex 0\nproperty float x\nend_header\n", "no format"},
        BadFile{"bad_format", "ply\nformat binary_middle_endian 1.0\nend_header\n", "unknown format"},
        BadFile{"unknown_type", header_le("element vertex 1\nproperty float128 x\n"),
                "unknown PLY type 'float128'"},
        BadFile{"float_list_count", header_le("element face 1\nproperty list float int idx\n"),
                "integer type"},
        BadFile{"property_first", header_le("property float x\n"), "property before any element"},
        BadFile{"negative_count", header_le("element vertex -5\nproperty float x\n"), "bad count"},
        BadFile{"huge_count", header_le("element vertex 18446744073709551615\nproperty float x\n") + "abcd",
                "more than the file"},
        BadFile{"count_exceeds_size",
                header_le("element vertex 10\nproperty float x\n") + std::string(36, '\0'),
                "more than the file"},
        BadFile{"duplicate_property", header_le("element vertex 1\nproperty float x\nproperty float x\n"),
                "duplicate property"},
        BadFile{"truncated_list",
                header_le("element face 1\nproperty list uchar int vertex_indices\n") +
                    std::string("\x03\x01\0\0\0", 5),
                "truncated data in element 'face' row 0"},
        BadFile{"huge_list",
                header_le("element face 1\nproperty list uint int vertex_indices\n") +
                    std::string("\xff\xff\xff\xff", 4),
                "list length"},
        BadFile{"ascii_garbage",
                "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nend_header\n1.0\nbanana\n",
                "malformed number 'banana' in element 'vertex' row 1"},
        BadFile{
            "ascii_truncated",
            "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nend_header\n1 2 3 ",
            "more than the file"},
        BadFile{"ascii_short",
                "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nend_header\n1 "
                "2\n3      \n",
                "truncated data in element 'vertex' row 1"},
        BadFile{"wrong_type",
                "ply\nformat ascii 1.0\nelement vertex 1\nproperty uchar red\nend_header\n300\n",
                "does not fit type uchar"},
        BadFile{"no_properties", header_le("element vertex 3\n") + "abc", "no properties"}),
    [](const auto& param_info) { return std::string(param_info.param.label); });

TEST(Ply, MissingFileIsNamed) {
    auto r = ply::Reader::open("/nonexistent/dir/cloud.ply");
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.message(), "/nonexistent/dir/cloud.ply: no such file");
}

TEST(Ply, WriterRejectsWrongCountsAndLeavesOldFile) {
    const fs::path p = temp_dir() / "keep.ply";
    write_bytes(p, "old contents");
    ply::Header h;
    h.elements = {{"vertex", 2, {{"x", ply::Type::float32}}}};
    {
        auto w = ply::Writer::create(p, h);
        ASSERT_TRUE(w.ok());
        ply::Chunk c;
        c.reset(h.elements[0]);
        c.rows = 1;
        c.columns[0].values = {1.0};
        ASSERT_TRUE(w->write_rows(c).ok());
        auto st = w->finish();
        ASSERT_FALSE(st.ok());
        EXPECT_NE(st.message().find("has 1 of 2 rows"), std::string::npos) << st.message();
    }
    std::ifstream f(p);
    std::string s((std::istreambuf_iterator<char>(f)), {});
    EXPECT_EQ(s, "old contents");
    for (const auto& entry : fs::directory_iterator(p.parent_path()))
        EXPECT_EQ(entry.path().string().find("keep.ply.tmp-"), std::string::npos);

    auto w = ply::Writer::create(p, h);
    ASSERT_TRUE(w.ok());
    ply::Chunk c;
    c.reset(ply::Element{"vertex", 0, {{"x", ply::Type::float64}}});
    c.rows = 3;
    c.columns[0].values = {1, 2, 3};
    EXPECT_FALSE(w->write_rows(c).ok());  // more rows than declared
    ply::Chunk wrong;
    wrong.reset(ply::Element{"vertex", 0, {{"y", ply::Type::float32}}});
    wrong.rows = 1;
    wrong.columns[0].values = {1};
    EXPECT_FALSE(w->write_rows(wrong).ok());  // no x column
}

TEST(Ply, WriterRefusesValuesThatDoNotFitTheType) {
    // Binary elements without lists are encoded column by column, the others value by value: the same
    // refusal, naming the value and the property, in every format.
    for (auto fmt : {ply::Format::ascii, ply::Format::binary_little_endian, ply::Format::binary_big_endian}) {
        const fs::path p = temp_dir() / "range.ply";
        ply::Header h;
        h.format = fmt;
        h.elements = {{"vertex", 3, {{"x", ply::Type::float32}, {"red", ply::Type::uint8}}}};
        auto w = ply::Writer::create(p, h);
        ASSERT_TRUE(w.ok());
        ply::Chunk c;
        c.reset(h.elements[0]);
        c.rows = 3;
        c.columns[0].values = {1, 2, 3};
        c.columns[1].values = {0, 255, 256};
        auto st = w->write_rows(c);
        ASSERT_FALSE(st.ok()) << ply::format_name(fmt);
        EXPECT_NE(st.message().find("value 256.000000 of 'red' does not fit type uchar"), std::string::npos)
            << st.message();
    }
}

TEST(Ply, NanSurvivesFloatRoundTrip) {
    // NaN is a valid float value in a PLY file; the reader keeps it and importers decide (they refuse).
    for (auto fmt : {ply::Format::ascii, ply::Format::binary_little_endian}) {
        const fs::path p = temp_dir() / "nan.ply";
        ply::Header h;
        h.format = fmt;
        h.elements = {{"vertex", 1, {{"x", ply::Type::float32}}}};
        auto w = ply::Writer::create(p, h);
        ASSERT_TRUE(w.ok());
        ply::Chunk c;
        c.reset(h.elements[0]);
        c.rows = 1;
        c.columns[0].values = {std::numeric_limits<double>::quiet_NaN()};
        ASSERT_TRUE(w->write_rows(c).ok());
        ASSERT_TRUE(w->finish().ok());
        auto got = read_all(p, 10);
        ASSERT_EQ(got.size(), 1u);
        EXPECT_TRUE(std::isnan(got[0].columns[0].values[0]));
    }
}
