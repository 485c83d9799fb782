// A file that another program shortens while it is mapped for reading: the read goes on with zeros where
// the file is gone and the mapping says it changed (the readers then refuse the file), instead of the
// process ending with SIGBUS. Mappings without a guard keep the old behaviour.
#include <gtest/gtest.h>

#include <sys/mman.h>
#include <fcntl.h>
#include <unistd.h>

#include <cstdint>
#include <cstring>
#include <string>

#include "runtime/assets/formats/archive/mapped_file.h"
#include "runtime/assets/formats/archive/mapping_guard.h"
#include "runtime/assets/formats/surface/ply.h"
#include "runtime/assets/formats/surface/ply_mapped.h"
#include "tests/assets/test_util.h"

namespace {

using namespace sffd;
namespace fs = std::filesystem;

constexpr std::size_t kBytes = 256 * 1024, kKept = 4096;

// Sums every byte through a volatile pointer (each load happens, in order).
std::uint64_t sum_bytes(const void* data, std::size_t n) {
    const volatile unsigned char* p = static_cast<const volatile unsigned char*>(data);
    std::uint64_t sum = 0;
    for (std::size_t i = 0; i < n; ++i) sum += p[i];
    return sum;
}

TEST(MappingGuard, AShortenedMappedFileReadsZerosPastItsEndAndSaysSo) {
    const fs::path dir = test::fresh_dir("mapping_guard", "file");
    test::write(dir / "a.glb", std::string(kBytes, char(0xab)));
    auto file = assets::MappedFile::open(dir / "a.glb", kBytes);
    ASSERT_TRUE(file) << file.message();
    const std::string_view bytes = file->bytes();
    ASSERT_EQ(bytes.size(), kBytes);
    EXPECT_EQ(sum_bytes(bytes.data(), kBytes), kBytes * 0xabu);
    EXPECT_FALSE(file->changed());
    fs::resize_file(dir / "a.glb", kKept);  // what another program's truncate or rewrite does
    EXPECT_EQ(sum_bytes(bytes.data(), kBytes), kKept * 0xabu) << "the kept page, then zeros";
    EXPECT_TRUE(file->changed());
    // A file mapped after it is no longer guarded by the first mapping's mark.
    auto again = assets::MappedFile::open(dir / "a.glb", kBytes);
    ASSERT_TRUE(again);
    EXPECT_EQ(sum_bytes(again->bytes().data(), again->bytes().size()), kKept * 0xabu);
    EXPECT_FALSE(again->changed());
}

TEST(MappingGuard, APlyElementShortenedWhileMappedSaysSo) {
    const fs::path dir = test::fresh_dir("mapping_guard", "ply");
    const std::size_t rows = kBytes / 4;
    std::string s = "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(rows) +
                    "\nproperty float x\nend_header\n";
    s.append(rows * 4, char(0x3f));
    test::write(dir / "a.ply", s);
    std::size_t header_bytes = 0;
    auto h = ply::parse_header(s, (dir / "a.ply").string(), header_bytes);
    ASSERT_TRUE(h) << h.message();
    auto m = ply::MappedElement::map(dir / "a.ply", *h, "vertex");
    ASSERT_TRUE(m) << m.message();
    fs::resize_file(dir / "a.ply", kKept);
    EXPECT_LT(sum_bytes(m->rows(), rows * 4), rows * 4 * 0x3fu);
    EXPECT_TRUE(m->changed());
}

TEST(MappingGuardDeathTest, AnUnguardedMappingStillEndsTheProcess) {
    const fs::path dir = test::fresh_dir("mapping_guard", "unguarded");
    test::write(dir / "a.bin", std::string(kBytes, char(1)));
    test::write(dir / "guarded.bin", std::string(kBytes, char(2)));
    auto guarded = assets::MappedFile::open(dir / "guarded.bin", kBytes);  // the handler is installed
    ASSERT_TRUE(guarded);
    EXPECT_DEATH(
        {
            const int fd = ::open((dir / "a.bin").c_str(), O_RDONLY);
            void* p = ::mmap(nullptr, kBytes, PROT_READ, MAP_PRIVATE, fd, 0);
            ::ftruncate(::open((dir / "a.bin").c_str(), O_WRONLY), 0);
            std::fprintf(stderr, "sum %llu\n", static_cast<unsigned long long>(sum_bytes(p, kBytes)));
        },
        "");
}

}  // namespace
