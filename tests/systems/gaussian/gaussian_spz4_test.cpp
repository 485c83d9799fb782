// SPZ version 4 (zstd streams): our writer read back, a hand-built degree-4 file with known values, and
// bad containers (each check of the reader fails a file built to break it).
#include <gtest/gtest.h>

#include <unistd.h>
#include <zstd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "systems/gaussian/gaussian_read.h"
#include "runtime/assets/formats/gaussian/gaussian_spz.h"
#include "systems/gaussian/sh.h"

namespace {

namespace fs = std::filesystem;
using namespace sffd;
using namespace sffd::gaussian;

fs::path temp(const std::string& name) {
    const fs::path d = fs::temp_directory_path() / ("sffd_spz4_" + std::to_string(getpid()));
    fs::create_directories(d);
    return d / name;
}

std::string slurp(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), {});
}

void spit(const fs::path& p, const std::string& b) { std::ofstream(p, std::ios::binary) << b; }

void put32(std::string& s, std::uint32_t v) {
    for (int i = 0; i < 4; ++i) s.push_back(char((v >> (8 * i)) & 0xff));
}
void put64(std::string& s, std::uint64_t v) { put32(s, std::uint32_t(v)), put32(s, std::uint32_t(v >> 32)); }
void set32(std::string& s, std::size_t at, std::uint32_t v) {
    for (int i = 0; i < 4; ++i) s[at + std::size_t(i)] = char((v >> (8 * i)) & 0xff);
}

std::string zstd(const std::string& raw) {
    std::string z(ZSTD_compressBound(raw.size()), '\0');
    z.resize(ZSTD_compress(z.data(), z.size(), raw.data(), raw.size(), 3));
    return z;
}

// A version-4 file: header, optional extension bytes, table, one zstd frame per non-empty array.
std::string container(std::uint32_t n, int degree, const std::vector<std::string>& arrays,
                      const std::string& extensions = "", int flags = 0) {
    std::string out;
    put32(out, 0x5053474e), put32(out, 4), put32(out, n);
    out += char(degree), out += char(12), out += char(flags);
    int streams = 0;
    for (const std::string& a : arrays) streams += !a.empty();
    out += char(streams);
    put32(out, std::uint32_t(32 + extensions.size()));
    out.append(12, '\0');
    out += extensions;
    std::string frames;
    for (const std::string& a : arrays) {
        if (a.empty()) continue;
        const std::string z = zstd(a);
        put64(out, z.size()), put64(out, a.size());
        frames += z;
    }
    return out + frames;
}

GaussianCloud cloud(std::size_t n, int degree, unsigned seed = 3) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1, 1);
    GaussianCloud g;
    g.sh_degree = degree;
    for (std::size_t i = 0; i < n; ++i) {
        g.positions.emplace_back(u(rng), u(rng), u(rng));
        g.scales.emplace_back(0.05f + 0.04f * u(rng), 0.02f + 0.01f * u(rng), 0.1f + 0.05f * u(rng));
        g.rotations.push_back(glm::normalize(glm::quat(u(rng), u(rng), u(rng), u(rng))));
        g.opacities.push_back(0.5f + 0.45f * u(rng));
        for (int k = 0; k < sh_coeffs(degree) * 3; ++k) g.sh.push_back(0.5f * u(rng));
    }
    return g;
}

void expect_refused(const fs::path& p, const std::string& part) {
    auto g = read_gaussians(p);
    ASSERT_FALSE(g) << p;
    EXPECT_NE(g.message().find(p.string()), std::string::npos) << g.message();
    EXPECT_NE(g.message().find(part), std::string::npos) << g.message();
}

TEST(SpzVersion4, OurFileHasTheLayoutAndReadsLikeVersion3) {
    for (int degree : {0, 3}) {
        const GaussianCloud g = cloud(300, degree);
        // Built piecewise: GCC 12 flags operator+(const char*, string&&) with a false -Wrestrict.
        std::string stem = "d";
        stem += std::to_string(degree);
        const fs::path v3 = temp(stem + "_v3.spz"), v4 = temp(stem + "_v4.spz");
        ASSERT_TRUE(write_spz(v3, g, 3));
        ASSERT_TRUE(write_spz(v4, g, 4));
        const std::string b = slurp(v4);
        ASSERT_GE(b.size(), 32u);
        EXPECT_EQ(b.substr(0, 4), "NGSP");
        EXPECT_EQ(b[4], 4);
        EXPECT_EQ(b[15], degree == 0 ? 5 : 6) << "one stream per non-empty array";
        EXPECT_EQ(b[16], 32) << "no extensions: the table follows the header";
        auto a = read_gaussians(v3), c = read_gaussians(v4);
        ASSERT_TRUE(a) << a.message();
        ASSERT_TRUE(c) << c.message();
        // The same quantised arrays in another container: identical clouds.
        EXPECT_EQ(a->positions, c->positions);
        EXPECT_EQ(a->scales, c->scales);
        EXPECT_EQ(a->opacities, c->opacities);
        EXPECT_EQ(a->sh, c->sh);
        for (std::size_t i = 0; i < g.size(); ++i) {
            EXPECT_EQ(a->rotations[i], c->rotations[i]) << i;
            EXPECT_LT(glm::length(c->positions[i] - g.positions[i]), 2.5e-4f) << i;
        }
    }
    EXPECT_FALSE(write_spz(temp("v5.spz"), cloud(2, 0), 5));
    EXPECT_FALSE(write_spz(temp("empty.spz"), GaussianCloud{}, 4));
}

// Arrays of one splat at (1, -2, 3) stored (RUB), degree 4: band 4 is dropped on reading.
std::vector<std::string> one_splat_degree4() {
    std::vector<std::string> a(6);
    auto fixed = [&](int v) {
        a[0] += char(v & 0xff), a[0] += char((v >> 8) & 0xff), a[0] += char((v >> 16) & 0xff);
    };
    fixed(4096), fixed(-2 * 4096), fixed(3 * 4096);
    a[1] = std::string(1, char(255));
    a[2] = std::string(3, char(128));  // DC 0
    a[3] = std::string(3, char(160));  // log scale 0: scale 1
    put32(a[4], 3u << 30);             // identity
    for (int k = 0; k < 24; ++k)       // coefficients 1..24, RGB: value (k+1)/128 in red, 0 elsewhere
        for (int c = 0; c < 3; ++c) a[5] += char(c == 0 ? 128 + k + 1 : 128);
    return a;
}

TEST(SpzVersion4, HandBuiltDegree4ReadsAsDegree3InThePlyFrame) {
    const fs::path p = temp("deg4.spz");
    spit(p, container(1, 4, one_splat_degree4()));
    auto g = read_gaussians(p);
    ASSERT_TRUE(g) << g.message();
    ASSERT_EQ(g->size(), 1u);
    EXPECT_EQ(g->sh_degree, 3);
    // RUB (1, -2, 3) is (1, 2, -3) in the PLY frame.
    EXPECT_NEAR(g->positions[0].x, 1.0f, 1e-6f);
    EXPECT_NEAR(g->positions[0].y, 2.0f, 1e-6f);
    EXPECT_NEAR(g->positions[0].z, -3.0f, 1e-6f);
    EXPECT_NEAR(g->opacities[0], 1.0f, 1e-6f);
    EXPECT_NEAR(g->scales[0].x, 1.0f, 1e-6f);
    // Coefficients 1..15 kept (up to the sign the x turn gives each basis function), 16..24 dropped.
    for (int k = 1; k < 16; ++k) EXPECT_NEAR(std::abs(g->sh[std::size_t(k) * 3]), k / 128.0f, 1e-6f) << k;
}

TEST(SpzVersion4, RefusesBrokenContainers) {
    const std::vector<std::string> arrays = one_splat_degree4();
    const std::string good = container(1, 4, arrays);
    spit(temp("good.spz"), good);
    ASSERT_TRUE(read_gaussians(temp("good.spz")));

    spit(temp("short.spz"), good.substr(0, 20));
    expect_refused(temp("short.spz"), "truncated header");
    std::string b = good;
    b[12] = 5;
    spit(temp("deg5.spz"), b);
    expect_refused(temp("deg5.spz"), "unsupported SH degree 5");
    b = good;
    b[15] = 5;
    spit(temp("streams.spz"), b);
    expect_refused(temp("streams.spz"), "5 streams; SH degree 4 has 6");
    b = good;
    set32(b, 16, 4000);
    spit(temp("toc.spz"), b);
    expect_refused(temp("toc.spz"), "table of contents at byte 4000");
    b = good;
    set32(b, 8, 1000000);  // a million splats from a ~200-byte file
    spit(temp("count.spz"), b);
    expect_refused(temp("count.spz"), "more than its");
    b = good;
    set32(b, 8, 0);
    spit(temp("zero.spz"), b);
    expect_refused(temp("zero.spz"), "declares no splats");
    b = good;
    b[32 + 8] = 10;  // first stream's decoded size: 10 instead of 9
    spit(temp("size.spz"), b);
    expect_refused(temp("size.spz"), "stream 0 decodes to 10 bytes; 1 splats need 9");
    spit(temp("tail.spz"), good + "x");
    expect_refused(temp("tail.spz"), "1 bytes after the last stream");
    spit(temp("cut.spz"), good.substr(0, good.size() - 1));
    expect_refused(temp("cut.spz"), "runs past the end of the file");
    b = good;
    b[32 + 6 * 16] ^= 0x55;  // the first frame's magic
    spit(temp("frame.spz"), b);
    expect_refused(temp("frame.spz"), "stream 0 is not a zstd frame");

    // A frame with a checksum whose content was altered: zstd's XXH64 check refuses it.
    std::vector<std::string> a = arrays;
    std::string raw = a[0];
    ZSTD_CCtx* cctx = ZSTD_createCCtx();
    ZSTD_CCtx_setParameter(cctx, ZSTD_c_checksumFlag, 1);
    ZSTD_CCtx_setParameter(cctx, ZSTD_c_compressionLevel, 1);
    std::string z(ZSTD_compressBound(raw.size()), '\0');
    z.resize(ZSTD_compress2(cctx, z.data(), z.size(), raw.data(), raw.size()));
    ZSTD_freeCCtx(cctx);
    std::string file = good.substr(0, 32 + 6 * 16);
    set32(file, 32, std::uint32_t(z.size()));
    z[z.size() - 5] ^= 0x01;  // last byte of the raw block before the 4-byte checksum
    std::string rest = good.substr(32 + 6 * 16);
    const std::size_t old = ZSTD_findFrameCompressedSize(rest.data(), rest.size());
    file += z + rest.substr(old);
    spit(temp("checksum.spz"), file);
    expect_refused(temp("checksum.spz"), "corrupt zstd data");

    // Extensions: an unknown record is skipped, the coordinate-system one refused, and bytes before the
    // table without the extension flag, or a record running past the table, are refused.
    std::string ext;
    put32(ext, 0x12340001u), put32(ext, 4), put32(ext, 0xdeadbeefu);
    spit(temp("ext.spz"), container(1, 4, arrays, ext, 2));
    EXPECT_TRUE(read_gaussians(temp("ext.spz")));
    spit(temp("noflag.spz"), container(1, 4, arrays, ext, 0));
    expect_refused(temp("noflag.spz"), "flags no extensions");
    std::string coord;
    put32(coord, 0xADBE0003u), put32(coord, 1), coord += char(1), coord.append(3, '\0');
    spit(temp("coord.spz"), container(1, 4, arrays, coord, 2));
    expect_refused(temp("coord.spz"), "SPZ_ADOBE_coordinate_system");
    std::string longer;
    put32(longer, 0x12340001u), put32(longer, 100);
    spit(temp("ext_long.spz"), container(1, 4, arrays, longer, 2));
    expect_refused(temp("ext_long.spz"), "runs past the table of contents");
}

}  // namespace
