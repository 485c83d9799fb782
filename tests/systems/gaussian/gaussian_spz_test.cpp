// SPZ v2/v3 reading: a hand-built file with known values, and bad files.
#include <gtest/gtest.h>

#include <unistd.h>
#include <zlib.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "systems/gaussian/gaussian_read.h"
#include "runtime/assets/formats/gaussian/gaussian_spz.h"
#include "systems/gaussian/sh.h"

namespace {

namespace fs = std::filesystem;
using namespace sffd;
using namespace sffd::gaussian;

fs::path temp(const std::string& name) {
    const fs::path d = fs::temp_directory_path() / ("sffd_spz_" + std::to_string(getpid()));
    fs::create_directories(d);
    return d / name;
}

void put32(std::string& s, std::uint32_t v) {
    for (int i = 0; i < 4; ++i) s.push_back(char((v >> (8 * i)) & 0xff));
}

void write_gz(const fs::path& p, const std::string& bytes) {
    gzFile f = gzopen(p.c_str(), "wb");
    ASSERT_NE(f, nullptr);
    ASSERT_EQ(gzwrite(f, bytes.data(), unsigned(bytes.size())), int(bytes.size()));
    gzclose(f);
}

std::string header(std::uint32_t version, std::uint32_t n, int degree, int frac) {
    std::string s;
    put32(s, 0x5053474e), put32(s, version), put32(s, n);
    s += char(degree), s += char(frac), s += char(0), s += char(0);
    return s;
}

TEST(GaussianSpz, HandBuiltVersion3WithKnownValues) {
    // Two splats, degree 1, 12 fractional bits.
    std::string b = header(3, 2, 1, 12);
    auto fixed = [&](int v) { b += char(v & 0xff), b += char((v >> 8) & 0xff), b += char((v >> 16) & 0xff); };
    fixed(int(1.5 * 4096)), fixed(-4096), fixed(0);                       // (1.5, -1, 0)
    fixed(2048), fixed(0), fixed(-int(0.25 * 4096));                      // (0.5, 0, -0.25)
    b += char(255), b += char(51);                                        // alphas: 1.0, 0.2
    for (unsigned char c : {128, 255, 0, 200, 200, 200}) b += char(c);    // colours
    for (unsigned char s : {160, 144, 176, 160, 160, 160}) b += char(s);  // log scale s/16 - 10
    put32(b, 3u << 30);                                                   // identity: w largest, x y z 0
    // 90° about z: (x,y,z,w) = (0,0,√½,√½): largest index 2 (z) or 3 (w); take w, z = √½ (mag 511).
    put32(b, (3u << 30) | (511u << 0));  // components in order j = 2, 1, 0 from the low bits: z first
    for (int k = 0; k < 18; ++k) b += char(k < 9 ? 128 + 64 : 128);  // splat 0: band 1 all 0.5, splat 1: 0
    const fs::path p = temp("two.spz");
    write_gz(p, b);
    auto g = read_gaussians(p);
    ASSERT_TRUE(g) << g.message();
    ASSERT_EQ(g->size(), 2u);
    EXPECT_EQ(g->sh_degree, 1);
    // SPZ is stored RUB; read into the 3DGS PLY frame by the turn (x, y, z) -> (x, -y, -z).
    EXPECT_EQ(g->positions[0], glm::vec3(1.5f, 1.0f, 0.0f));
    EXPECT_EQ(g->positions[1], glm::vec3(0.5f, 0.0f, 0.25f));
    EXPECT_EQ(g->opacities[0], 1.0f);
    EXPECT_NEAR(g->opacities[1], 0.2f, 1e-7);
    EXPECT_NEAR(g->sh[0], (128 / 255.0 - 0.5) / 0.15, 1e-6);
    EXPECT_NEAR(g->sh[1], 0.5 / 0.15, 1e-6);
    EXPECT_NEAR(g->scales[0].x, 1.0f, 1e-6);
    EXPECT_NEAR(g->scales[0].y, std::exp(-1.0f), 1e-6);
    EXPECT_NEAR(g->scales[0].z, std::exp(1.0f), 1e-5);
    // The turn q -> (0, 1, 0, 0)·q: identity becomes the half turn about x, and 90 degrees about z
    // (w = z = √½) becomes (w, x, y, z) = (0, √½, -√½, 0).
    EXPECT_EQ(g->rotations[0], glm::quat(0, 1, 0, 0));
    EXPECT_NEAR(g->rotations[1].x, std::sqrt(0.5f), 1e-6);
    EXPECT_NEAR(g->rotations[1].y, -std::sqrt(0.5f), 1e-6);
    // Band 1 is (−y, z, −x): the turn flips the y and z coefficients, keeps x's.
    for (int k = 3; k < 9; ++k) EXPECT_EQ(g->sh[std::size_t(k)], -0.5f) << k;
    for (int k = 9; k < 12; ++k) EXPECT_EQ(g->sh[std::size_t(k)], 0.5f) << k;
    for (int k = 15; k < 24; ++k) EXPECT_EQ(g->sh[std::size_t(k)], 0.0f) << k;
}

TEST(GaussianSpz, BadFiles) {
    auto expect = [](const fs::path& p, const std::string& fragment) {
        auto g = read_spz(p);
        ASSERT_FALSE(g);
        EXPECT_NE(g.message().find(p.string()), std::string::npos) << g.message();
        EXPECT_NE(g.message().find(fragment), std::string::npos) << g.message();
    };
    std::ofstream(temp("plain.spz")) << "hello";
    expect(temp("plain.spz"), "no gzip stream");
    std::ofstream(temp("v4.spz"), std::ios::binary) << header(4, 1, 0, 12) + std::string(16, '\0');
    expect(temp("v4.spz"), "SPZ version 4: 0 streams; SH degree 0 has 5");  // read as version 4
    std::ofstream(temp("raw2.spz"), std::ios::binary) << header(2, 1, 0, 12) + std::string(16, '\0');
    expect(temp("raw2.spz"), "uncompressed SPZ version 2 data");
    write_gz(temp("magic.spz"), "XXXX" + header(3, 1, 0, 12).substr(4));
    expect(temp("magic.spz"), "bad magic");
    write_gz(temp("trunc.spz"), header(3, 10, 0, 12) + std::string(50, '\0'));
    expect(temp("trunc.spz"), "truncated data");
    write_gz(temp("huge.spz"), header(3, 4000000000u, 3, 12));
    expect(temp("huge.spz"), "declares 4000000000 splats");
    write_gz(temp("deg.spz"), header(3, 1, 5, 12));  // SPZ allows degree 4
    expect(temp("deg.spz"), "unsupported SH degree 5");
    write_gz(temp("ver.spz"), header(9, 1, 0, 12));
    expect(temp("ver.spz"), "unsupported SPZ version 9");
}

}  // namespace
