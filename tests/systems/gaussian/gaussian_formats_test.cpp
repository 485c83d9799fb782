// Files as real pipelines write them: the infinities splat-transform writes, the axis turn between the
// 3DGS PLY frame and SPZ's, and PlayCanvas's compressed PLY (hand-built files with known values, our
// writer's round trip, bad files).
#include <gtest/gtest.h>

#include <unistd.h>
#include <zlib.h>

#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include "runtime/assets/formats/surface/ply.h"
#include "runtime/core/log.h"
#include "runtime/assets/formats/gaussian/gaussian_axes.h"
#include "systems/gaussian/gaussian_read.h"
#include "runtime/assets/formats/gaussian/gaussian_compressed_ply.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "runtime/assets/formats/gaussian/gaussian_ksplat.h"
#include "runtime/assets/formats/gaussian/gaussian_spz.h"
#include "runtime/assets/formats/gaussian/gaussian_spz_detail.h"
#include "systems/gaussian/gaussian_math.h"
#include "systems/gaussian/sh.h"
#include "tests/systems/gaussian/test_math.h"

namespace {

namespace fs = std::filesystem;
using namespace sffd;
using namespace sffd::gaussian;

fs::path temp(const std::string& name) {
    const fs::path d = fs::temp_directory_path() / ("sffd_formats_" + std::to_string(getpid()));
    fs::create_directories(d);
    return d / name;
}

GaussianCloud cloud(std::size_t n, int degree, unsigned seed = 7) {
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

// A 3DGS PLY of degree 0 with the given opacity and scale_0 columns (the rest ordinary).
fs::path ply_with(const std::string& name, const std::vector<double>& opacity,
                  const std::vector<double>& scale0) {
    ply::Element e = ply_element(0, opacity.size());
    ply::Header h;
    h.elements.push_back(e);
    ply::Chunk c;
    c.reset(e);
    c.rows = opacity.size();
    for (ply::Column& col : c.columns) col.values.assign(c.rows, 0.0);
    for (std::size_t r = 0; r < c.rows; ++r) {
        c.columns[std::size_t(e.find("opacity"))].values[r] = opacity[r];
        c.columns[std::size_t(e.find("scale_0"))].values[r] = scale0[r];
        c.columns[std::size_t(e.find("rot_0"))].values[r] = 1.0;
        c.columns[std::size_t(e.find("x"))].values[r] = double(r);
    }
    const fs::path p = temp(name);
    auto w = ply::Writer::create(p, h);
    EXPECT_TRUE(w) << w.message();
    EXPECT_TRUE(w->write_rows(c));
    EXPECT_TRUE(w->finish());
    return p;
}

TEST(GaussianInfinity, PlyOpacityAndScaleInfinitiesReadAsLimitsAndCounted) {
    const fs::path p =
        ply_with("inf.ply", {INFINITY, -INFINITY, 0.0, 2.0}, {0.0, -INFINITY, -INFINITY, std::log(0.5)});
    log::ScopedLogCapture capture;
    auto g = read_gaussians(p);
    ASSERT_TRUE(g) << g.message();
    ASSERT_EQ(g->size(), 4u);
    EXPECT_EQ(g->opacities[0], 1.0f);
    EXPECT_EQ(g->opacities[1], 0.0f);
    EXPECT_EQ(g->opacities[2], 0.5f);
    EXPECT_NEAR(g->opacities[3], 1.0 / (1.0 + std::exp(-2.0)), 1e-7);
    EXPECT_EQ(g->scales[0].x, 1.0f);
    EXPECT_EQ(g->scales[1].x, 0.0f);  // flat along x
    EXPECT_EQ(g->scales[2].x, 0.0f);
    EXPECT_NEAR(g->scales[3].x, 0.5f, 1e-7);
    EXPECT_TRUE(validate(*g, "read"));
    EXPECT_TRUE(capture.contains(p.string() + ": read 4 infinite values as limits (2 logit opacities"))
        << (capture.entries().empty() ? "no log" : capture.entries()[0].message);
    EXPECT_TRUE(capture.contains("2 log scales of -inf as flat axes"));
}

TEST(GaussianInfinity, NoLogLineForAnOrdinaryFile) {
    const fs::path p = ply_with("plain.ply", {0.0, 1.0}, {0.0, 0.0});
    log::ScopedLogCapture capture;
    ASSERT_TRUE(read_gaussians(p));
    EXPECT_FALSE(capture.contains("infinite values"));
}

TEST(GaussianInfinity, NanAndPositiveInfiniteLogScaleAreRefusedNamingTheFileAndRow) {
    auto expect = [](const fs::path& p, const std::string& fragment) {
        auto g = read_gaussians(p);
        ASSERT_FALSE(g);
        EXPECT_NE(g.message().find(p.string() + ": vertex 1: "), std::string::npos) << g.message();
        EXPECT_NE(g.message().find(fragment), std::string::npos) << g.message();
    };
    expect(ply_with("nan_opacity.ply", {0.0, NAN}, {0.0, 0.0}), "non-finite 'opacity'");
    expect(ply_with("nan_scale.ply", {0.0, 0.0}, {0.0, NAN}), "non-finite 'scale_0'");
    expect(ply_with("inf_scale.ply", {0.0, 0.0}, {0.0, INFINITY}), "'scale_0'");
}

TEST(GaussianInfinity, TheMappingFunction) {
    InfinityCount n;
    float v = -1;
    EXPECT_TRUE(opacity_from_logit(INFINITY, v, n) && v == 1.0f);
    EXPECT_TRUE(opacity_from_logit(-INFINITY, v, n) && v == 0.0f);
    EXPECT_FALSE(opacity_from_logit(NAN, v, n));
    EXPECT_TRUE(scale_from_log(-INFINITY, v, n) && v == 0.0f);
    EXPECT_FALSE(scale_from_log(INFINITY, v, n));
    EXPECT_FALSE(scale_from_log(NAN, v, n));
    EXPECT_FALSE(scale_from_log(1000.0, v, n));  // overflows a float
    EXPECT_EQ(n.opacity, 2u);
    EXPECT_EQ(n.scale, 1u);
}

// The colour a splat shows along direction d.
glm::vec3 colour(const GaussianCloud& g, std::size_t i, const glm::vec3& d) {
    return sh_color(g.sh_degree, &g.sh[i * std::size_t(sh_coeffs(g.sh_degree)) * 3], d);
}

TEST(GaussianAxes, TurnMovesCentresCovariancesAndSeenColoursTogether) {
    for (AxisTurn turn : {AxisTurn::x180, AxisTurn::z180}) {
        const glm::dmat3 r = turn == AxisTurn::x180 ? glm::dmat3(1, 0, 0, 0, -1, 0, 0, 0, -1)
                                                    : glm::dmat3(-1, 0, 0, 0, -1, 0, 0, 0, 1);
        const GaussianCloud g = cloud(50, 3);
        GaussianCloud t = g;
        turn_axes(t, turn);
        std::mt19937 rng(1);
        std::uniform_real_distribution<float> u(-1, 1);
        for (std::size_t i = 0; i < g.size(); ++i) {
            EXPECT_EQ(glm::dvec3(t.positions[i]), r * glm::dvec3(g.positions[i]));
            const glm::dmat3 sg = covariance(glm::dvec3(g.scales[i]), glm::dquat(g.rotations[i]));
            const glm::dmat3 st = covariance(glm::dvec3(t.scales[i]), glm::dquat(t.rotations[i]));
            EXPECT_LT(test::max_abs(st - r * sg * glm::transpose(r)), 1e-6 * test::max_abs(sg)) << i;
            // The turned splat seen along the turned direction looks as the original along the original.
            const glm::vec3 d = glm::normalize(glm::vec3(u(rng), u(rng), u(rng)));
            const glm::vec3 a = colour(g, i, d), b = colour(t, i, glm::vec3(r * glm::dvec3(d)));
            EXPECT_LT(glm::length(a - b), 1e-5f) << i;
        }
        turn_axes(t, turn);  // its own inverse, exactly
        EXPECT_EQ(t.positions, g.positions);
        EXPECT_EQ(t.sh, g.sh);
        for (std::size_t i = 0; i < g.size(); ++i)
            EXPECT_LT(std::abs(std::abs(glm::dot(t.rotations[i], g.rotations[i])) - 1.0f), 1e-6f);
    }
}

// A compressed PLY from explicit rows (chunk bounds, packed words, sh bytes).
fs::path compressed(const std::string& name, std::uint64_t n,
                    const std::vector<std::vector<double>>& chunk_rows,
                    const std::vector<std::array<double, 4>>& packed, int sh_props = 0, double sh_byte = 0,
                    std::uint64_t chunk_count = ~0ull) {
    ply::Header h;
    ply::Element ce;
    ce.name = "chunk";
    ce.count = chunk_count == ~0ull ? chunk_rows.size() : chunk_count;
    for (const char* p :
         {"min_x", "min_y", "min_z", "max_x", "max_y", "max_z", "min_scale_x", "min_scale_y", "min_scale_z",
          "max_scale_x", "max_scale_y", "max_scale_z", "min_r", "min_g", "min_b", "max_r", "max_g", "max_b"})
        ce.properties.push_back({p, ply::Type::float32, false, ply::Type::uint8});
    ply::Element ve;
    ve.name = "vertex";
    ve.count = n;
    for (const char* p : {"packed_position", "packed_rotation", "packed_scale", "packed_color"})
        ve.properties.push_back({p, ply::Type::uint32, false, ply::Type::uint8});
    h.elements = {ce, ve};
    if (sh_props) {
        ply::Element se;
        se.name = "sh";
        se.count = n;
        for (int i = 0; i < sh_props; ++i)
            se.properties.push_back(
                {"f_rest_" + std::to_string(i), ply::Type::uint8, false, ply::Type::uint8});
        h.elements.push_back(se);
    }
    // Write the header and rows ourselves (a wrong chunk count is not something ply::Writer would emit).
    std::string bytes = h.to_string();
    auto put = [&](const void* p, std::size_t size) { bytes.append(static_cast<const char*>(p), size); };
    for (const auto& row : chunk_rows)
        for (double v : row) {
            const float f = float(v);
            put(&f, 4);
        }
    for (const auto& w : packed)
        for (double v : w) {
            const std::uint32_t u = std::uint32_t(v);
            put(&u, 4);
        }
    for (std::uint64_t i = 0; i < n && sh_props; ++i)
        for (int k = 0; k < sh_props; ++k) bytes.push_back(char(int(sh_byte)));
    const fs::path p = temp(name);
    std::ofstream(p, std::ios::binary) << bytes;
    return p;
}

TEST(CompressedPly, HandBuiltFileWithKnownValues) {
    // One chunk: positions in [-1, 1] x [0, 2] x [10, 12], log scales in [-2, 0], colours in [0, 1].
    const std::vector<double> bounds = {-1, 0, 10, 1, 2, 12, -2, -2, -2, 0, 0, 0, 0, 0, 0, 1, 1, 1};
    // Splat 0: position (max, min, max) = (1, 0, 12); w largest with the other three at code 512 (the
    // nearest to 0: 10 bits have no exact middle); scales at the ends; colour (1, 0, 1), opacity 1.
    const std::uint32_t pos0 = (2047u << 21) | (0u << 11) | 2047u;
    const std::uint32_t rot0 = (0u << 30) | (512u << 20) | (512u << 10) | 512u;
    const std::uint32_t sc0 = (2047u << 21) | (0u << 11) | 0u;
    const std::uint32_t col0 = (255u << 24) | (0u << 16) | (255u << 8) | 255u;
    // Splat 1: mid values, rotation 90 degrees about z stored with z largest (index 3).
    const std::uint32_t rot1 = (3u << 30) | (1023u << 20) | (512u << 10) | 512u;  // w = (1 - 0.5)·√2 = √½
    const std::uint32_t col1 = (0u << 24) | (0u << 16) | (0u << 8) | 0u;
    const fs::path p = compressed(
        "known.compressed.ply", 2, {bounds},
        {{double(pos0), double(rot0), double(sc0), double(col0)}, {0.0, double(rot1), 0.0, double(col1)}}, 9,
        255);
    log::ScopedLogCapture capture;
    auto g = read_gaussians(p);
    ASSERT_TRUE(g) << g.message();
    ASSERT_EQ(g->size(), 2u);
    EXPECT_EQ(g->sh_degree, 1);
    EXPECT_EQ(g->positions[0], glm::vec3(1, 0, 12));
    EXPECT_EQ(g->positions[1], glm::vec3(-1, 0, 10));
    EXPECT_NEAR(g->scales[0].x, 1.0f, 1e-7);
    EXPECT_NEAR(g->scales[0].y, std::exp(-2.0f), 1e-7);
    EXPECT_EQ(g->opacities[0], 1.0f);
    EXPECT_EQ(g->opacities[1], 0.0f);
    EXPECT_NEAR(g->sh[0], 0.5 / kShC0, 1e-6);
    EXPECT_NEAR(g->sh[1], -0.5 / kShC0, 1e-6);
    const double half = (512.0 / 1023.0 - 0.5) * std::sqrt(2.0);  // the nearest code to 0
    EXPECT_NEAR(g->rotations[0].w, std::sqrt(1 - 3 * half * half), 1e-6);
    EXPECT_NEAR(g->rotations[0].x, half, 1e-6);
    EXPECT_NEAR(g->rotations[1].w, std::sqrt(0.5), 1e-3);
    EXPECT_NEAR(g->rotations[1].z, std::sqrt(0.5), 1e-3);
    for (int k = 3; k < 12; ++k)
        EXPECT_EQ(g->sh[std::size_t(k)], 4.0f) << k;  // byte 255 is exactly (1 − 0.5)·8
    EXPECT_FALSE(capture.contains("infinite values"));
}

TEST(CompressedPly, OurWriterRoundTripsWithinTheStatedQuantisation) {
    for (int degree : {0, 3}) {
        const GaussianCloud g = cloud(700, degree, 11);  // three chunks, the last partly filled
        const fs::path p = temp("ours_" + std::to_string(degree) + ".compressed.ply");
        ASSERT_TRUE(write_compressed_ply(p, g));
        auto back = read_gaussians(p);
        ASSERT_TRUE(back) << back.message();
        ASSERT_EQ(back->size(), g.size());
        ASSERT_EQ(back->sh_degree, degree);
        const int K = sh_coeffs(degree);
        for (std::size_t i = 0; i < g.size(); ++i) {
            // Positions span 2 per axis per chunk: half a step is 2/2047/2 (x, z) and 2/1023/2 (y).
            const glm::vec3 d = glm::abs(back->positions[i] - g.positions[i]);
            EXPECT_LE(d.x, 2.0f / 4094 * 1.01f) << i;
            EXPECT_LE(d.y, 2.0f / 2046 * 1.01f) << i;
            EXPECT_LE(d.z, 2.0f / 4094 * 1.01f) << i;
            EXPECT_NEAR(back->opacities[i], g.opacities[i], 0.5 / 255 + 1e-6) << i;
            EXPECT_GT(std::abs(glm::dot(back->rotations[i], g.rotations[i])), 0.999f) << i;
            for (int c = 0; c < 3; ++c) {
                EXPECT_NEAR(std::log(back->scales[i][c]), std::log(g.scales[i][c]), 0.01) << i;
                EXPECT_NEAR(back->sh[i * std::size_t(K) * 3 + std::size_t(c)],
                            g.sh[i * std::size_t(K) * 3 + std::size_t(c)], 1.0 / 510 / kShC0 + 1e-5);
            }
            for (int k = 3; k < K * 3; ++k)
                EXPECT_NEAR(back->sh[i * std::size_t(K) * 3 + std::size_t(k)],
                            g.sh[i * std::size_t(K) * 3 + std::size_t(k)], 1.0 / 64 + 1e-6);
        }
    }
}

TEST(CompressedPly, BadFilesNameTheFileAndTheProblem) {
    auto expect = [](const fs::path& p, const std::string& fragment) {
        auto g = read_gaussians(p);
        ASSERT_FALSE(g);
        EXPECT_EQ(g.message().rfind(p.string() + ": ", 0), 0u) << g.message();
        EXPECT_NE(g.message().find(fragment), std::string::npos) << g.message();
    };
    const std::vector<double> b = {-1, 0, 10, 1, 2, 12, -2, -2, -2, 0, 0, 0, 0, 0, 0, 1, 1, 1};
    std::vector<std::array<double, 4>> rows(300, {0, 0, 0, 0});
    expect(compressed("one_chunk_300.ply", 300, {b}, rows), "1 chunks for 300 splats (expected 2");
    expect(compressed("sh7.ply", 2, {b}, {{0, 0, 0, 0}, {0, 0, 0, 0}}, 7),
           "7 properties: expected 9, 24 or 45");
    std::vector<double> nan_bounds = b;
    nan_bounds[1] = NAN;
    expect(compressed("nan.ply", 1, {nan_bounds}, {{0, 0, 0, 0}}), "chunk 0: non-finite 'min_y'");
    // A declared count the file cannot hold is refused before anything is allocated (ply::Reader).
    expect(compressed("huge.ply", 4000000000ull, {b}, {{0, 0, 0, 0}}, 0, 0, 15625000), "");
}

TEST(CompressedPly, MinusInfiniteLogScaleBoundReadsAsFlatAndIsCounted) {
    std::vector<double> b = {-1, 0, 10, 1, 2, 12, -INFINITY, -2, -2, 0, 0, 0, 0, 0, 0, 1, 1, 1};
    const fs::path p =
        compressed("flat.compressed.ply", 2, {b}, {{0, 0, 0, 255}, {0, 0, double(2047u << 21), 255}});
    log::ScopedLogCapture capture;
    auto g = read_gaussians(p);
    ASSERT_TRUE(g) << g.message();
    EXPECT_EQ(g->scales[0].x, 0.0f);  // at the -inf end
    EXPECT_EQ(g->scales[1].x, 1.0f);  // at the finite end, not inf·0
    EXPECT_TRUE(capture.contains("read 1 infinite values as limits"));
}

// .ksplat bytes: little-endian helpers over a growing buffer.
struct Bytes {
    std::string b;
    void at(std::size_t offset, const void* p, std::size_t n) {
        if (b.size() < offset + n) b.resize(offset + n, '\0');
        std::memcpy(&b[offset], p, n);
    }
    void u8(std::size_t o, unsigned v) {
        const unsigned char c = static_cast<unsigned char>(v);
        at(o, &c, 1);
    }
    void u16(std::size_t o, unsigned v) {
        const std::uint16_t x = static_cast<std::uint16_t>(v);
        at(o, &x, 2);
    }
    void u32(std::size_t o, std::uint32_t v) { at(o, &v, 4); }
    void f32(std::size_t o, float v) { at(o, &v, 4); }
};

// Mode 1 (positions u16 in buckets, f16 scale/rotation/SH): one section, three splats of degree 1 in a
// full bucket of two and a partial bucket of one.
Bytes ksplat_mode1(std::uint32_t declared = 3) {
    Bytes k;
    k.u8(0, 0), k.u8(1, 1), k.u32(4, 1), k.u32(16, declared), k.u16(20, 1);
    const std::size_t s = 4096;
    k.u32(s + 0, 3), k.u32(s + 4, 3), k.u32(s + 8, 2), k.u32(s + 12, 2), k.f32(s + 16, 2.0f),
        k.u16(s + 20, 12);
    k.u32(s + 24, 1000), k.u32(s + 32, 1), k.u32(s + 36, 1), k.u16(s + 40, 1);
    std::size_t d = 4096 + 1024;
    k.u32(d, 1);                                            // partial bucket size
    k.f32(d + 4, 10), k.f32(d + 8, 20), k.f32(d + 12, 30);  // bucket 0 centre
    k.f32(d + 16, -5), k.f32(d + 20, 0), k.f32(d + 24, 5);  // bucket 1 centre
    std::size_t r = d + 4 + 24;                             // 2 buckets x 12 bytes + 4
    const std::size_t record = 6 + 6 + 8 + 4 + 9 * 2;
    const unsigned half_one = 0x3c00, half_half = 0x3800, half_minus_quarter = 0xb400;
    for (int j = 0; j < 3; ++j, r += record) {
        k.u16(r, 1000 + 500), k.u16(r + 2, 1000), k.u16(r + 4, 1000 - 1000);  // (+0.5 block/2, 0, -block/2)
        k.u16(r + 6, half_half), k.u16(r + 8, half_one), k.u16(r + 10, 0);    // scales 0.5, 1, 0 (flat)
        k.u16(r + 12, half_one), k.u16(r + 14, 0), k.u16(r + 16, 0), k.u16(r + 18, 0);
        k.u8(r + 20, 255), k.u8(r + 21, 0), k.u8(r + 22, 128), k.u8(r + 23, 51);
        for (int c = 0; c < 9; ++c)
            k.u16(r + 24 + 2 * std::size_t(c), c < 3 ? half_minus_quarter : 0);  // R band 1 = -0.25
    }
    return k;
}

TEST(Ksplat, HandBuiltMode1WithBucketsAndKnownValues) {
    const fs::path p = temp("m1.ksplat");
    std::ofstream(p, std::ios::binary) << ksplat_mode1().b;
    auto g = read_gaussians(p);
    ASSERT_TRUE(g) << g.message();
    ASSERT_EQ(g->size(), 3u);
    EXPECT_EQ(g->sh_degree, 1);
    // Position = (u - range) * block / 2 / range + centre: (0.5, 0, -1) from each splat's bucket centre.
    EXPECT_EQ(g->positions[0], glm::vec3(10.5f, 20.0f, 29.0f));
    EXPECT_EQ(g->positions[1], glm::vec3(10.5f, 20.0f, 29.0f));
    EXPECT_EQ(g->positions[2], glm::vec3(-4.5f, 0.0f, 4.0f));  // the partial bucket
    EXPECT_EQ(g->scales[0], glm::vec3(0.5f, 1.0f, 0.0f));
    EXPECT_EQ(g->rotations[0], glm::quat(1, 0, 0, 0));
    EXPECT_NEAR(g->opacities[0], 0.2f, 1e-7);
    EXPECT_NEAR(g->sh[0], 0.5 / kShC0, 1e-6);
    EXPECT_NEAR(g->sh[1], -0.5 / kShC0, 1e-6);
    for (int k = 1; k < 4; ++k) {
        EXPECT_EQ(g->sh[std::size_t(k) * 3 + 0], -0.25f) << k;  // red, coefficients 1..3
        EXPECT_EQ(g->sh[std::size_t(k) * 3 + 1], 0.0f) << k;
    }
    EXPECT_TRUE(validate(*g, "read"));
}

TEST(Ksplat, BadFilesNameTheFileAndTheProblem) {
    auto expect = [](const std::string& name, const std::string& bytes, const std::string& fragment) {
        const fs::path p = temp(name);
        std::ofstream(p, std::ios::binary) << bytes;
        auto g = read_ksplat(p);
        ASSERT_FALSE(g);
        EXPECT_EQ(g.message().rfind(p.string() + ": ", 0), 0u) << g.message();
        EXPECT_NE(g.message().find(fragment), std::string::npos) << g.message();
    };
    expect("small.ksplat", std::string(100, '\0'), "too small");
    expect("count.ksplat", ksplat_mode1(4).b, "declares 4 splats, the sections hold 3");
    Bytes mode = ksplat_mode1();
    mode.u16(20, 3);
    expect("mode.ksplat", mode.b, "compression mode 3");
    const std::string whole = ksplat_mode1().b;
    expect("trunc.ksplat", whole.substr(0, whole.size() - 10), "run past the end of the file");
    Bytes sections = ksplat_mode1();
    sections.u32(4, 4000000000u);
    expect("sections.ksplat", sections.b, "section headers do not fit");
    Bytes scale = ksplat_mode1();
    scale.u16(4096 + 1024 + 28 + 6, 0xbc00);  // scale x = -1
    expect("scale.ksplat", scale.b, "splat 0: scale negative");
}

TEST(SpzWrite, RoundTripsWithinSpzQuantisationAndKeepsTheFrame) {
    const GaussianCloud g = cloud(400, 3, 21);
    const fs::path p = temp("ours.spz");
    ASSERT_TRUE(write_spz(p, g));
    auto back = read_gaussians(p);
    ASSERT_TRUE(back) << back.message();
    ASSERT_EQ(back->size(), g.size());
    ASSERT_EQ(back->sh_degree, 3);
    for (std::size_t i = 0; i < g.size(); ++i) {
        // 12 fractional bits; log scales in steps of 1/16; opacity 1/255; rotation 9-bit smallest three.
        EXPECT_LT(glm::length(back->positions[i] - g.positions[i]), 2.5e-4f) << i;  // √3 half steps
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(std::log(back->scales[i][c]), std::log(g.scales[i][c]), 1.0 / 32 + 1e-6) << i;
        EXPECT_NEAR(back->opacities[i], g.opacities[i], 0.5 / 255 + 1e-6) << i;
        EXPECT_GT(std::abs(glm::dot(back->rotations[i], g.rotations[i])), 0.999f) << i;
        for (int k = 0; k < 48; ++k)  // DC in steps of 1/(255·0.15), SH in steps of 1/128
            EXPECT_NEAR(back->sh[i * 48 + std::size_t(k)], g.sh[i * 48 + std::size_t(k)],
                        k < 3 ? 0.5 / (255 * 0.15) + 1e-5 : 0.5 / 128 + 1e-6)
                << i << " " << k;
    }
}

// A payload of several compression segments (the writer deflates 4 MB segments on every core and joins
// them): the file is one gzip stream whose content, length and CRC are the payload's, byte for byte.
TEST(SpzWrite, ALargeFileIsOneGzipStreamOfItsPayload) {
    const GaussianCloud g = cloud(100000, 3, 5);  // 6.5 MB of payload, 45 bytes of SH rest each
    const fs::path p = temp("large.spz");
    ASSERT_TRUE(write_spz(p, g));
    GaussianCloud rub = g;
    turn_axes(rub, AxisTurn::x180);
    auto e = spz_detail::encode(rub);
    ASSERT_TRUE(e) << e.message();
    std::string want;
    for (std::uint32_t v : {0x5053474eu, 3u, e->n})
        for (int b = 0; b < 4; ++b) want += char((v >> (8 * b)) & 0xff);
    want += char(e->degree), want += char(e->frac), want += char(0), want += char(0);
    for (const std::string& a : e->arrays) want += a;
    ASSERT_GT(want.size(), std::size_t(6) << 20);
    std::string got(want.size() + 1, '\0');
    gzFile f = gzopen(p.c_str(), "rb");
    ASSERT_NE(f, nullptr);
    gzbuffer(f, 1 << 20);
    std::size_t at = 0;
    int n = 0;
    while ((n = gzread(f, got.data() + at, unsigned(got.size() - at))) > 0) at += std::size_t(n);
    int err = Z_OK;
    const std::string why = n < 0 ? gzerror(f, &err) : "";
    gzclose(f);
    ASSERT_EQ(n, 0) << why;  // gzread checks the trailer's CRC and length
    got.resize(at);
    EXPECT_TRUE(got == want) << got.size() << " vs " << want.size() << " bytes";
}

TEST(SpzWrite, StoresRubOnDisk) {
    // One splat at (1, 2, 3) in the PLY frame is (1, -2, -3) in the file (fixed point, 12 bits).
    GaussianCloud g = cloud(1, 0);
    g.positions[0] = {1, 2, 3};
    const fs::path p = temp("rub.spz");
    ASSERT_TRUE(write_spz(p, g));
    gzFile f = gzopen(p.c_str(), "rb");
    ASSERT_NE(f, nullptr);
    unsigned char b[25];
    ASSERT_EQ(gzread(f, b, sizeof b), int(sizeof b));
    gzclose(f);
    EXPECT_EQ(b[13], 12);
    auto coord = [&](int c) {
        std::int32_t v = std::int32_t(b[16 + 3 * c] | b[17 + 3 * c] << 8 | b[18 + 3 * c] << 16);
        if (v & 0x800000) v -= 0x1000000;
        return v / 4096.0;
    };
    EXPECT_EQ(coord(0), 1.0);
    EXPECT_EQ(coord(1), -2.0);
    EXPECT_EQ(coord(2), -3.0);
}

}  // namespace
