// resize_for_overwrite (output arrays prefaulted before a parallel decode) and MappedFile (an input file
// mapped whole): the same contents as resize() and read_file(), and read_file()'s refusals.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "runtime/assets/formats/archive/fresh_array.h"
#include "runtime/assets/formats/archive/mapped_file.h"
#include "runtime/core/file_io.h"

namespace {

using namespace sffd;
namespace fs = std::filesystem;

fs::path temp(const std::string& name) {
    const fs::path d = fs::temp_directory_path() / ("sffd_fresh_" + std::to_string(getpid()));
    fs::create_directories(d);
    return d / name;
}

TEST(FreshArray, SizesLikeResizeLargeSmallReservedAndFilled) {
    // 40 MB (prefaulted), 1 KB (too small to bother), a reserved empty array, and one with contents.
    for (std::size_t n : {std::size_t(10) << 20, std::size_t(256)}) {
        std::vector<float> v;
        assets::resize_for_overwrite(v, n);
        ASSERT_EQ(v.size(), n);
        for (std::size_t i = 0; i < n; i += 4093) EXPECT_EQ(v[i], 0.0f) << i;
        EXPECT_EQ(v.back(), 0.0f);
    }
    std::vector<std::uint32_t> reserved;
    reserved.reserve(3u << 20);
    assets::resize_for_overwrite(reserved, 2u << 20);
    EXPECT_EQ(reserved.size(), 2u << 20);
    EXPECT_EQ(reserved[12345], 0u);
    std::vector<int> filled = {7, 8, 9};
    assets::resize_for_overwrite(filled, 5);
    EXPECT_EQ(filled, (std::vector<int>{7, 8, 9, 0, 0}));
    assets::resize_for_overwrite(filled, 2);
    EXPECT_EQ(filled, (std::vector<int>{7, 8}));
}

TEST(MappedFile, HoldsTheFileAndRefusesAsReadFileDoes) {
    const fs::path f = temp("bytes.bin");
    std::string bytes(3u << 20, '\0');
    for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = char(i * 131u >> 3);
    std::ofstream(f, std::ios::binary) << bytes;
    auto m = assets::MappedFile::open(f, 1u << 30);
    ASSERT_TRUE(m) << m.message();
    EXPECT_EQ(m->bytes(), bytes);
    assets::MappedFile moved = std::move(*m);
    EXPECT_EQ(moved.bytes(), bytes);

    const fs::path empty = temp("empty.bin");
    std::ofstream(empty, std::ios::binary).flush();
    auto e = assets::MappedFile::open(empty, 100);
    ASSERT_TRUE(e) << e.message();
    EXPECT_TRUE(e->bytes().empty());

    const fs::path fifo = temp("fifo");
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    for (const auto& [p, limit] : std::vector<std::pair<fs::path, std::uint64_t>>{
             {f, 1000}, {fifo, 1u << 30}, {temp("missing.bin"), 1u << 30}, {temp(""), 1u << 30}}) {
        auto r = assets::MappedFile::open(p, limit);
        auto expected = read_file(p, limit);
        ASSERT_FALSE(r) << p;
        ASSERT_FALSE(expected) << p;
        EXPECT_EQ(r.message(), expected.message());
    }
    fs::remove_all(temp("").parent_path());
}

}  // namespace
