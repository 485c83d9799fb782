// 3DGS PLY and .splat import/export: hand-written files with known values, round trips, bad files.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <vector>

#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "systems/gaussian/gaussian_read.h"
#include "systems/gaussian/sh.h"

namespace {

namespace fs = std::filesystem;
using namespace sffd;
using namespace sffd::gaussian;

fs::path temp_path(const std::string& name) {
    const fs::path dir = fs::temp_directory_path() / ("sffd_gaussian_io_" + std::to_string(getpid()));
    fs::create_directories(dir);
    return dir / name;
}

void write_text(const fs::path& p, const std::string& s) { std::ofstream(p, std::ios::binary) << s; }

std::string ascii_header(int n_rest, std::uint64_t count) {
    std::string h =
        "ply\nformat ascii 1.0\nelement vertex " + std::to_string(count) +
        "\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\n"
        "property float nz\nproperty float f_dc_0\nproperty float f_dc_1\nproperty float f_dc_2\n";
    for (int i = 0; i < n_rest; ++i) h += "property float f_rest_" + std::to_string(i) + "\n";
    h += "property float opacity\nproperty float scale_0\nproperty float scale_1\nproperty float scale_2\n"
         "property float rot_0\nproperty float rot_1\nproperty float rot_2\nproperty float "
         "rot_3\nend_header\n";
    return h;
}

TEST(GaussianIo, HandWrittenDegreeOnePly) {
    // Degree 1: 9 f_rest values per channel block R(k=1..3), G(k=1..3), B(k=1..3) = 10..18.
    const fs::path p = temp_path("tiny.ply");
    write_text(
        p,
        ascii_header(9, 2) +
            "1 2 3 0 0 0 0.1 0.2 0.3 10 11 12 13 14 15 16 17 18 0 -1 0 0.6931471805599453 2 0 0 0\n"
            "-1 0.5 4 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 2.1972245773362196 -2.302585092994046 -2.302585092994046 "
            "-2.302585092994046 0 0 1 1\n");
    auto g = read_ply(p);
    ASSERT_TRUE(g) << g.message();
    ASSERT_EQ(g->size(), 2u);
    EXPECT_EQ(g->sh_degree, 1);
    EXPECT_EQ(g->positions[0], glm::vec3(1, 2, 3));
    EXPECT_EQ(g->positions[1], glm::vec3(-1, 0.5f, 4));
    EXPECT_NEAR(g->scales[0].x, 1.0f / std::exp(1.0f), 1e-7);  // exp(-1)
    EXPECT_NEAR(g->scales[0].y, 1.0f, 1e-7);
    EXPECT_NEAR(g->scales[0].z, 2.0f, 1e-6);
    EXPECT_NEAR(g->scales[1].x, 0.1f, 1e-7);
    EXPECT_NEAR(g->opacities[0], 0.5f, 1e-7);  // sigmoid(0)
    EXPECT_NEAR(g->opacities[1], 0.9f, 1e-6);  // sigmoid(logit 0.9)
    // rot_0..3 = w, x, y, z = (2, 0, 0, 0) -> identity; (0, 0, 1, 1) -> normalised, 180° about (y+z)/√2.
    EXPECT_EQ(g->rotations[0], glm::quat(1, 0, 0, 0));
    EXPECT_NEAR(g->rotations[1].w, 0.0f, 1e-7);
    EXPECT_NEAR(g->rotations[1].x, 0.0f, 1e-7);
    EXPECT_NEAR(g->rotations[1].y, float(std::sqrt(0.5)), 1e-7);
    EXPECT_NEAR(g->rotations[1].z, float(std::sqrt(0.5)), 1e-7);
    // sh[(i*K + k)*3 + c], K = 4.
    EXPECT_FLOAT_EQ(g->sh[0 * 3 + 0], 0.1f);
    EXPECT_FLOAT_EQ(g->sh[0 * 3 + 2], 0.3f);
    for (int c = 0; c < 3; ++c)
        for (int k = 1; k < 4; ++k)
            EXPECT_EQ(g->sh[std::size_t(k * 3 + c)], float(10 + c * 3 + (k - 1))) << c << k;
}

GaussianCloud random_cloud(int degree, std::size_t n, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1, 1);
    std::normal_distribution<float> nd;
    GaussianCloud g;
    g.sh_degree = degree;
    for (std::size_t i = 0; i < n; ++i) {
        g.positions.emplace_back(u(rng) * 10, u(rng), u(rng) + 5);
        g.scales.emplace_back(std::exp(u(rng) * 4), std::exp(u(rng) * 4), std::exp(u(rng) * 4));
        g.rotations.push_back(glm::normalize(glm::quat(nd(rng), nd(rng), nd(rng), nd(rng))));
        g.opacities.push_back(0.5f + 0.49f * u(rng));
        for (int k = 0; k < sh_coeffs(degree) * 3; ++k) g.sh.push_back(u(rng));
    }
    return g;
}

void expect_same(const GaussianCloud& a, const GaussianCloud& b) {
    ASSERT_EQ(a.size(), b.size());
    ASSERT_EQ(a.sh_degree, b.sh_degree);
    for (std::size_t i = 0; i < a.size(); ++i) {
        EXPECT_EQ(a.positions[i], b.positions[i]);
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(a.scales[i][c], b.scales[i][c], 2e-7 * double(a.scales[i][c]));
        EXPECT_NEAR(a.opacities[i], b.opacities[i], 2e-7);
        for (int c = 0; c < 4; ++c) EXPECT_NEAR(a.rotations[i][c], b.rotations[i][c], 2e-7);
    }
    EXPECT_EQ(a.sh, b.sh);
}

TEST(GaussianIo, PlyRoundTripsEveryDegreeBinaryAndAscii) {
    for (int degree = 0; degree <= 3; ++degree)
        for (ply::Format f : {ply::Format::binary_little_endian, ply::Format::ascii}) {
            const GaussianCloud g = random_cloud(degree, 300, unsigned(degree + 10));
            const fs::path p = temp_path("rt.ply");
            ASSERT_TRUE(write_ply(p, g, f));
            auto back = read_ply(p);
            ASSERT_TRUE(back) << back.message();
            expect_same(g, *back);
            // The header has the 3DGS property count: 17 + 3 * (K - 1) (x y z, normals, f_dc, opacity, scale,
            // rot).
            auto reader = ply::Reader::open(p);
            ASSERT_TRUE(reader);
            EXPECT_EQ(reader->header().elements[0].properties.size(),
                      std::size_t(17 + 3 * (sh_coeffs(degree) - 1)));
        }
}

TEST(GaussianIo, LogitAndLogConversions) {
    for (double p : {1e-6, 0.01, 0.3, 0.5, 0.77, 0.999}) EXPECT_NEAR(sigmoid(logit(p)), p, 1e-7 * (1 + p));
    EXPECT_NEAR(logit(0.5), 0.0, 1e-15);
    EXPECT_NEAR(logit(0.9), std::log(9.0), 1e-12);
    // Saturation keeps written files finite: p = 0 and 1 map to ∓ logit(1 − 2⁻²⁴).
    EXPECT_NEAR(kMaxLogit, std::log(16777215.0), 1e-12);
    EXPECT_EQ(logit(1.0), kMaxLogit);
    EXPECT_EQ(logit(0.0), -kMaxLogit);
    EXPECT_EQ(sigmoid(kMaxLogit), float(1.0 - 1.0 / 16777216.0));
    // Opacity 1 and scale 0 survive a write as 1 − 2⁻²⁴ and a tiny positive scale.
    GaussianCloud g = random_cloud(0, 1, 3);
    g.opacities[0] = 1.0f;
    g.scales[0] = glm::vec3(0.0f, 1.0f, 2.0f);
    const fs::path p = temp_path("sat.ply");
    ASSERT_TRUE(write_ply(p, g));
    auto back = read_ply(p);
    ASSERT_TRUE(back) << back.message();
    EXPECT_EQ(back->opacities[0], float(1.0 - 1.0 / 16777216.0));
    EXPECT_GT(back->scales[0].x, 0.0f);
    EXPECT_LT(back->scales[0].x, 1e-29f);
}

void expect_error(const fs::path& p, const std::string& fragment) {
    auto g = read_gaussians(p);
    ASSERT_FALSE(g) << p;
    EXPECT_NE(g.message().find(p.string()), std::string::npos) << g.message();
    EXPECT_NE(g.message().find(fragment), std::string::npos) << g.message();
}

TEST(GaussianIo, BadPlyFiles) {
    // Wrong f_rest count.
    const fs::path wrong = temp_path("wrong.ply");
    std::string zeros;
    for (int i = 0; i < 27; ++i) zeros += "0 ";
    write_text(wrong, ascii_header(10, 1) + zeros + "\n");
    expect_error(wrong, "10 f_rest properties: expected 0, 9, 24 or 45");
    // Missing property.
    const fs::path missing = temp_path("missing.ply");
    write_text(missing,
               "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float "
               "z\nend_header\n0 0 0\n");
    expect_error(missing, "not a 3DGS PLY");
    // NaN scale and zero quaternion.
    const fs::path nan = temp_path("nan.ply");
    write_text(nan, ascii_header(0, 1) + "0 0 0 0 0 0 0 0 0 0 nan 0 0 1 0 0 0\n");
    expect_error(nan, "vertex 0: non-finite 'scale_0'");
    const fs::path zero_q = temp_path("zq.ply");
    write_text(zero_q, ascii_header(0, 1) + "0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0\n");
    expect_error(zero_q, "zero-length rotation quaternion");
    // Truncated binary data.
    const GaussianCloud g = random_cloud(3, 50, 7);
    const fs::path full = temp_path("full.ply");
    ASSERT_TRUE(write_ply(full, g));
    const fs::path cut = temp_path("cut.ply");
    fs::copy_file(full, cut, fs::copy_options::overwrite_existing);
    fs::resize_file(cut, fs::file_size(full) - 100);
    expect_error(cut, "declares 50 rows");
    // A huge declared count is refused before allocating.
    const fs::path huge = temp_path("huge.ply");
    std::string h = ascii_header(45, 4000000000ull);
    h.replace(h.find("ascii"), 5, "binary_little_endian");
    write_text(huge, h + std::string(64, '\0'));
    expect_error(huge, "declares 4000000000 rows");
}

void put_splat(std::string& out, glm::vec3 p, glm::vec3 s, const unsigned char rgba[4],
               const unsigned char rot[4]) {
    char b[32];
    std::memcpy(b, &p, 12);
    std::memcpy(b + 12, &s, 12);
    std::memcpy(b + 24, rgba, 4);
    std::memcpy(b + 28, rot, 4);
    out.append(b, 32);
}

TEST(GaussianIo, SplatFileKnownValues) {
    std::string bytes;
    const unsigned char c0[4] = {255, 128, 0, 204},
                        r0[4] = {128, 255, 128, 128};  // rot (w,x,y,z) ~ (0,1,0,0)
    const unsigned char c1[4] = {0, 0, 0, 255}, r1[4] = {255, 128, 128, 128};
    put_splat(bytes, {1, 2, 3}, {0.1f, 0.2f, 0.3f}, c0, r0);
    put_splat(bytes, {-4, 5, -6}, {1, 1, 1}, c1, r1);
    const fs::path p = temp_path("two.splat");
    write_text(p, bytes);
    auto g = read_gaussians(p);
    ASSERT_TRUE(g) << g.message();
    ASSERT_EQ(g->size(), 2u);
    EXPECT_EQ(g->sh_degree, 0);
    EXPECT_EQ(g->positions[0], glm::vec3(1, 2, 3));
    EXPECT_EQ(g->scales[0], glm::vec3(0.1f, 0.2f, 0.3f));
    EXPECT_NEAR(g->opacities[0], 0.8f, 1e-7);
    EXPECT_EQ(g->rotations[0], glm::quat(0, 1, 0, 0));
    EXPECT_EQ(g->rotations[1], glm::quat(1, 0, 0, 0));
    // The colour seen from any direction is the file's RGB.
    const glm::vec3 col = sh_color(0, &g->sh[0], {0, 0, 1});
    EXPECT_NEAR(col.x, 1.0f, 1e-6);
    EXPECT_NEAR(col.y, 128.0f / 255.0f, 1e-6);
    EXPECT_NEAR(col.z, 0.0f, 1e-6);

    const fs::path odd = temp_path("odd.splat");
    write_text(odd, bytes.substr(0, 40));
    expect_error(odd, "not a multiple of 32");
    const fs::path empty = temp_path("empty.splat");
    write_text(empty, "");
    expect_error(empty, "empty.splat: empty file");
    std::string bad = bytes;
    const float nan = std::nanf("");
    std::memcpy(bad.data() + 32 + 16, &nan, 4);
    const fs::path nanp = temp_path("nan.splat");
    write_text(nanp, bad);
    expect_error(nanp, "splat 1: non-finite scale");
    expect_error(temp_path("absent.splat"), "no such file");
}

// Binary float32 files are decoded in place from the mapped file, ASCII ones through ply::Reader's
// columns: the same rows must give the same cloud, bit for bit, every degree, with more rows than one
// parallel range and a property order that is not the writer's (extra columns between).
TEST(GaussianIo, MappedRowsMatchTheColumnPath) {
    for (int degree : {0, 1, 3}) {
        const GaussianCloud g = random_cloud(degree, 20000, unsigned(degree + 30));
        const fs::path bin = temp_path("mapped_" + std::to_string(degree) + ".ply");
        const fs::path text = temp_path("columns_" + std::to_string(degree) + ".ply");
        ASSERT_TRUE(write_ply(bin, g));
        ASSERT_TRUE(write_ply(text, g, ply::Format::ascii));
        auto a = read_gaussians(bin);
        auto b = read_gaussians(text);
        ASSERT_TRUE(a) << a.message();
        ASSERT_TRUE(b) << b.message();
        ASSERT_EQ(a->size(), g.size());
        EXPECT_EQ(a->sh_degree, degree);
        EXPECT_EQ(a->positions, b->positions);
        EXPECT_EQ(a->scales, b->scales);
        EXPECT_EQ(a->rotations, b->rotations);
        EXPECT_EQ(a->opacities, b->opacities);
        EXPECT_EQ(a->sh, b->sh);
    }
}

// One binary little-endian degree-1 row per vector (x y z, an int column, f_dc, f_rest, opacity, scale, rot),
// a list-free element before the vertices.
void write_binary_rows(const fs::path& p, const std::vector<std::vector<float>>& rows) {
    std::string h =
        "ply\nformat binary_little_endian 1.0\nelement camera 2\nproperty uchar id\n"
        "element vertex " +
        std::to_string(rows.size()) +
        "\nproperty float x\nproperty float y\nproperty float z\nproperty int tag\n"
        "property float f_dc_0\nproperty float f_dc_1\nproperty float f_dc_2\n";
    for (int i = 0; i < 9; ++i) h += "property float f_rest_" + std::to_string(i) + "\n";
    h += "property float opacity\nproperty float scale_0\nproperty float scale_1\nproperty float scale_2\n"
         "property float rot_0\nproperty float rot_1\nproperty float rot_2\nproperty float "
         "rot_3\nend_header\n";
    std::ofstream f(p, std::ios::binary);
    f << h << char(7) << char(9);  // the camera element's two rows
    for (const auto& r : rows) {
        f.write(reinterpret_cast<const char*>(r.data()), 3 * 4);
        const std::int32_t tag = -5;
        f.write(reinterpret_cast<const char*>(&tag), 4);
        f.write(reinterpret_cast<const char*>(r.data() + 3), std::streamsize((r.size() - 3) * 4));
    }
}

std::vector<float> good_row(float x) {
    // x y z, f_dc 0..2, f_rest 0..8, opacity, scale 0..2, rot 0..3
    std::vector<float> r = {x, 2, 3, 0.1f, 0.2f, 0.3f};
    for (int i = 0; i < 9; ++i) r.push_back(float(i) * 0.25f - 1.0f);
    for (float v : {0.0f, -1.0f, 0.0f, 0.5f, 2.0f, 0.0f, 0.0f, 0.0f}) r.push_back(v);
    return r;
}

TEST(GaussianIo, MappedRowsValues) {
    const fs::path p = temp_path("mapped_values.ply");
    write_binary_rows(p, {good_row(1), good_row(-4)});
    auto g = read_gaussians(p);
    ASSERT_TRUE(g) << g.message();
    ASSERT_EQ(g->size(), 2u);
    EXPECT_EQ(g->positions[1], glm::vec3(-4, 2, 3));
    EXPECT_EQ(g->sh_degree, 1);
    // Coefficient k of channel c comes from f_rest_{c*3 + k-1}: R, G, B blocks.
    EXPECT_EQ(g->sh[0], 0.1f);
    EXPECT_EQ(g->sh[3 * 1 + 0], -1.0f);   // k=1 R: f_rest_0
    EXPECT_EQ(g->sh[3 * 1 + 1], -0.25f);  // k=1 G: f_rest_3
    EXPECT_EQ(g->sh[3 * 3 + 2], 1.0f);    // k=3 B: f_rest_8
    EXPECT_FLOAT_EQ(g->scales[0].x, std::exp(-1.0f));
    EXPECT_EQ(g->rotations[0], glm::quat(1, 0, 0, 0));  // (2, 0, 0, 0) normalised
    EXPECT_EQ(g->opacities[0], 0.5f);
}

TEST(GaussianIo, MappedRowsBadValues) {
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    struct Case {
        int field;  // index into good_row
        float value;
        const char* message;
    };
    for (const Case& c :
         {Case{1, nan, "vertex 5000: non-finite 'y'"}, Case{6 + 4, inf, "vertex 5000: non-finite 'f_rest_4'"},
          Case{16, inf, "vertex 5000: scale overflows (log scale too large) in 'scale_0'"},
          Case{17, nan, "vertex 5000: non-finite 'scale_1'"},
          Case{15, nan, "vertex 5000: non-finite 'opacity'"}}) {
        std::vector<std::vector<float>> rows(9000, good_row(1));
        rows[5000][std::size_t(c.field)] = c.value;
        rows[7000][1] = nan;  // a later bad row in another range: the first in file order is reported
        const fs::path p = temp_path("mapped_bad.ply");
        write_binary_rows(p, rows);
        expect_error(p, c.message);
    }
    // A zero quaternion is refused, an opacity of -inf and a log scale of -inf are read as limits.
    std::vector<std::vector<float>> rows(3, good_row(1));
    rows[1][15] = -inf, rows[1][18] = -inf;
    const fs::path limits = temp_path("mapped_limits.ply");
    write_binary_rows(limits, rows);
    auto g = read_gaussians(limits);
    ASSERT_TRUE(g) << g.message();
    EXPECT_EQ(g->opacities[1], 0.0f);
    EXPECT_EQ(g->scales[1].z, 0.0f);
    for (int k = 19; k < 23; ++k) rows[2][std::size_t(k)] = 0.0f;
    const fs::path zero = temp_path("mapped_zero_rotation.ply");
    write_binary_rows(zero, rows);
    expect_error(zero, "vertex 2: zero-length rotation quaternion at 'rot_0'");
}

}  // namespace
