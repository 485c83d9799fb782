// Every command reads every Gaussian format (run as a user would: the built binary). `deform` of a
// compressed PLY, SPZ, SOG, ... equals `deform` of the same cloud as a 3DGS PLY; then a table runs info,
// render, convert, pick, profile and deform on a file of each format.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "systems/ffd/lattice.h"
#include "systems/ffd/lattice_io.h"
#include "systems/ffd/operations.h"
#include "systems/gaussian/gaussian_compressed_ply.h"
#include "systems/gaussian/gaussian_deform.h"
#include "systems/gaussian/gaussian_gltf.h"
#include "systems/gaussian/gaussian_io.h"
#include "systems/gaussian/gaussian_math.h"
#include "systems/gaussian/sh.h"
#include "systems/gaussian/gaussian_sog.h"
#include "systems/gaussian/gaussian_spz.h"
#include "systems/splat_render/image_io.h"
#include "tests/test_util/gl_required.h"

namespace {

namespace fs = std::filesystem;
using namespace sffd;

const std::string kTool = SFFD_BINARY_DIR "/tools/splatffd";

struct RunResult {
    int code = -1;
    std::string out, err;
};

fs::path temp(const std::string& name) {
    const fs::path d = fs::temp_directory_path() / ("sffd_format_cmd_" + std::to_string(getpid()));
    fs::create_directories(d);
    return d / name;
}

RunResult run(const std::string& command, const std::string& args) {
    const std::string o = temp("stdout.txt").string(), e = temp("stderr.txt").string();
    const int status = std::system((kTool + " " + command + " " + args + " >" + o + " 2>" + e).c_str());
    RunResult r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    std::stringstream so, se;
    so << std::ifstream(o).rdbuf();
    se << std::ifstream(e).rdbuf();
    r.out = so.str(), r.err = se.str();
    return r;
}

// A shell of Gaussians of degree 1 around the origin (radius 0.8), so a picked pixel at the image centre
// lands on one and every format's bounds are the same.
GaussianCloud shell(std::size_t n) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(-1, 1);
    GaussianCloud g;
    g.sh_degree = 1;
    while (g.size() < n) {
        const glm::vec3 p(u(rng), u(rng), u(rng));
        if (glm::length(p) < 0.1f || glm::length(p) > 1.0f) continue;
        g.positions.push_back(0.8f * glm::normalize(p));
        g.scales.emplace_back(0.06f, 0.05f, 0.02f);
        g.rotations.push_back(glm::normalize(glm::quat(1.0f + u(rng), u(rng), u(rng), u(rng))));
        g.opacities.push_back(0.8f);
        for (int k = 0; k < 12; ++k) g.sh.push_back(k < 3 ? 0.5f + 0.3f * u(rng) : 0.2f * u(rng));
    }
    return g;
}

// .splat (antimatter15): 32 bytes a Gaussian, no SH beyond the colour.
void write_splat(const fs::path& p, const GaussianCloud& g) {
    std::string bytes;
    for (std::size_t i = 0; i < g.size(); ++i) {
        const float f[6] = {g.positions[i].x, g.positions[i].y, g.positions[i].z,
                            g.scales[i].x,    g.scales[i].y,    g.scales[i].z};
        bytes.append(reinterpret_cast<const char*>(f), sizeof f);
        unsigned char c[8];
        for (int k = 0; k < 3; ++k)
            c[k] = static_cast<unsigned char>(std::clamp(
                std::lround((0.5 + gaussian::kShC0 * g.sh[i * 12 + std::size_t(k)]) * 255.0), 0l, 255l));
        c[3] = static_cast<unsigned char>(std::lround(g.opacities[i] * 255.0f));
        const glm::quat q = g.rotations[i];
        const float wxyz[4] = {q.w, q.x, q.y, q.z};
        for (int k = 0; k < 4; ++k)
            c[4 + k] =
                static_cast<unsigned char>(std::clamp(std::lround(wxyz[k] * 128.0f + 128.0f), 0l, 255l));
        bytes.append(reinterpret_cast<const char*>(c), sizeof c);
    }
    std::ofstream(p, std::ios::binary) << bytes;
}

// .ksplat mode 0 is not written by us: a hand-built mode-1 file (GaussianSplats3D's layout, as
// gaussian_formats_test.cpp builds it) of three Gaussians near the origin.
void write_ksplat(const fs::path& p) {
    std::string b;
    auto at = [&](std::size_t o, const void* v, std::size_t n) {
        if (b.size() < o + n) b.resize(o + n, '\0');
        std::memcpy(&b[o], v, n);
    };
    auto u8 = [&](std::size_t o, unsigned v) {
        const auto c = static_cast<unsigned char>(v);
        at(o, &c, 1);
    };
    auto u16 = [&](std::size_t o, unsigned v) {
        const auto x = static_cast<std::uint16_t>(v);
        at(o, &x, 2);
    };
    auto u32 = [&](std::size_t o, std::uint32_t v) { at(o, &v, 4); };
    auto f32 = [&](std::size_t o, float v) { at(o, &v, 4); };
    u8(0, 0), u8(1, 1), u32(4, 1), u32(16, 3), u16(20, 1);
    const std::size_t s = 4096;
    u32(s + 0, 3), u32(s + 4, 3), u32(s + 8, 2), u32(s + 12, 2), f32(s + 16, 2.0f), u16(s + 20, 12);
    u32(s + 24, 1000), u32(s + 32, 1), u32(s + 36, 1), u16(s + 40, 1);
    const std::size_t d = 4096 + 1024;
    u32(d, 1);
    f32(d + 4, 0.2f), f32(d + 8, 0), f32(d + 12, 0);
    f32(d + 16, -0.2f), f32(d + 20, 0), f32(d + 24, 0);
    std::size_t r = d + 4 + 24;
    for (int j = 0; j < 3; ++j, r += 6 + 6 + 8 + 4 + 18) {
        u16(r, 1000), u16(r + 2, 1000), u16(r + 4, 1000);
        u16(r + 6, 0x3400), u16(r + 8, 0x3400), u16(r + 10, 0x3000);  // scales 0.25, 0.25, 0.125
        u16(r + 12, 0x3c00), u16(r + 14, 0), u16(r + 16, 0), u16(r + 18, 0);
        u8(r + 20, 255), u8(r + 21, 128), u8(r + 22, 0), u8(r + 23, 220);
        for (int c = 0; c < 9; ++c) u16(r + 24 + 2 * std::size_t(c), 0);  // band 1: zero
    }
    std::ofstream(p, std::ios::binary) << b;
}

// One file of each format the commands read, written by our writers from shell(n) (or built by hand).
struct FormatFile {
    std::string format;
    fs::path path;
};
std::vector<FormatFile> write_every_format(const GaussianCloud& g) {
    std::vector<FormatFile> f = {{"3DGS PLY", temp("g.ply")},
                                 {"compressed PLY", temp("g.compressed.ply")},
                                 {"SPZ v3", temp("g.spz")},
                                 {"SPZ v4", temp("g4.spz")},
                                 {"SOG", temp("g.sog")},
                                 {"SOG folder", temp("sog_dir")},
                                 {"SOG meta.json", temp("sog_dir") / "meta.json"},
                                 {"KHR glb", temp("g.glb")},
                                 {".splat", temp("g.splat")},
                                 {".ksplat", temp("g.ksplat")}};
    EXPECT_TRUE(gaussian::write_ply(f[0].path, g));
    EXPECT_TRUE(gaussian::write_compressed_ply(f[1].path, g));
    EXPECT_TRUE(gaussian::write_spz(f[2].path, g, 3));
    EXPECT_TRUE(gaussian::write_spz(f[3].path, g, 4));
    EXPECT_TRUE(gaussian::write_sog(f[4].path, g));
    fs::create_directories(f[5].path);
    EXPECT_TRUE(gaussian::write_sog(f[6].path, g));
    EXPECT_TRUE(gaussian::write_glb(f[7].path, g));
    write_splat(f[8].path, g);
    write_ksplat(f[9].path);
    return f;
}

// A 3³ lattice around the shell, bent (top raised and sheared) and twisted, saved to `path`.
Lattice save_bent_lattice(const fs::path& path) {
    Lattice l = ffd::make_lattice(
        {-1.1, -1.1, -1.1}, {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)}, {3, 3, 3});
    ffd::twist_graded(l, ffd::all_control_points(l), {0, 1, 0}, 0.4, glm::dvec3(0.0));
    for (glm::dvec3& p : l.current)
        if (p.y > 0) p += glm::dvec3(0.3 * p.y, 0.4 * p.y, 0.0);
    EXPECT_TRUE(ffd::save_lattice(path, l));
    return l;
}

double quat_distance(const glm::quat& a, const glm::quat& b) {
    return 1.0 - std::abs(double(glm::dot(a, b)));
}

// A Gaussian's covariance R S² Rᵀ: what rendering sees (a rotation and scales are one of its
// factorisations; two files may store different ones of the same ellipsoid).
glm::dmat3 covariance(const glm::quat& q, const glm::vec3& s) {
    const glm::dmat3 r = glm::mat3_cast(q);
    const glm::dmat3 s2(glm::dvec3(s.x * s.x, 0, 0), glm::dvec3(0, s.y * s.y, 0),
                        glm::dvec3(0, 0, s.z * s.z));
    return r * s2 * glm::transpose(r);
}
double relative_difference(const glm::dmat3& a, const glm::dmat3& b) {
    double d = 0, n = 0;
    for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r) d += (a[c][r] - b[c][r]) * (a[c][r] - b[c][r]), n += b[c][r] * b[c][r];
    return std::sqrt(d / n);
}

// deform IN (each lossy format) equals deform of the same cloud (IN as read back) written as a 3DGS PLY,
// which the command streams: the same Gaussians to float rounding. Against the cloud before the format
// quantised it, within that format's quantisation, moved by the lattice.
TEST(FormatCommands, DeformOfEachFormatEqualsDeformOfItsCloudAsPly) {
    const GaussianCloud g = shell(2000);
    const fs::path lat = temp("bent.json");
    const Lattice l = save_bent_lattice(lat);
    GaussianCloud exact;
    ASSERT_TRUE(gaussian::deform(l, g, exact));
    gaussian::bake_sh_frames(exact);
    struct Case {
        std::string name;
        double position, covariance;  // tolerances against the unquantised cloud, deformed
    };
    // Positions: compressed PLY 11/10-bit per 256-row chunk bounds, SPZ 2^-12, SOG 16-bit log-mapped;
    // scales are stored as logs (compressed PLY 10/11 bits, SPZ 1/16, SOG a 256-entry codebook) and
    // rotations in 8-10 bits a component: the covariance within a few per cent, about twice the scales'.
    const std::vector<Case> cases = {
        {"g.compressed.ply", 4e-3, 0.1}, {"g.spz", 1e-3, 0.15}, {"g.sog", 4e-3, 0.15}, {"g.glb", 1e-5, 1e-4}};
    write_every_format(g);
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        const fs::path in = temp(c.name), out = temp("deformed_" + c.name + ".ply");
        const fs::path as_ply = temp("as_ply_" + c.name + ".ply"), ply_out = temp("deformed_as_ply.ply");
        auto decoded = gaussian::read_gaussians(in);
        ASSERT_TRUE(decoded) << decoded.message();
        ASSERT_TRUE(gaussian::write_ply(as_ply, *decoded));
        RunResult r = run("deform", in.string() + " " + out.string() + " --lattice " + lat.string());
        ASSERT_EQ(r.code, 0) << r.err;
        r = run("deform", as_ply.string() + " " + ply_out.string() + " --lattice " + lat.string());
        ASSERT_EQ(r.code, 0) << r.err;
        auto got = gaussian::read_ply(out);
        auto want = gaussian::read_ply(ply_out);
        ASSERT_TRUE(got && want);
        ASSERT_EQ(got->size(), g.size());
        ASSERT_EQ(want->size(), g.size());
        double dp = 0, ds = 0, dq = 0, dq_exact = 0, dsh = 0;
        for (std::size_t i = 0; i < g.size(); ++i) {
            dp = std::max(dp, double(glm::length(got->positions[i] - want->positions[i])));
            ds = std::max(ds, double(glm::length(got->scales[i] - want->scales[i])) /
                                  double(glm::length(want->scales[i])));
            dq = std::max(dq, quat_distance(got->rotations[i], want->rotations[i]));
            EXPECT_NEAR(got->opacities[i], want->opacities[i], 1e-6f);
            const double pe = glm::length(got->positions[i] - exact.positions[i]);
            EXPECT_LT(pe, c.position) << "Gaussian " << i;
            dq_exact =
                std::max(dq_exact, relative_difference(covariance(got->rotations[i], got->scales[i]),
                                                       covariance(exact.rotations[i], exact.scales[i])));
        }
        for (std::size_t k = 0; k < got->sh.size() && k < want->sh.size(); ++k)
            dsh = std::max(dsh, double(std::abs(got->sh[k] - want->sh[k])));
        EXPECT_LT(dp, 1e-5) << "positions against the PLY path";
        EXPECT_LT(ds, 1e-5) << "scales against the PLY path";
        EXPECT_LT(dq, 1e-6) << "rotations against the PLY path";
        EXPECT_LT(dsh, 1e-5) << "SH against the PLY path";
        EXPECT_LT(dq_exact, c.covariance) << "covariances against the unquantised cloud";
    }
}

TEST(FormatCommands, DeformWritesEveryGaussianFormat) {
    const GaussianCloud g = shell(500);
    const fs::path lat = temp("bent_out.json");
    const Lattice l = save_bent_lattice(lat);
    ASSERT_TRUE(gaussian::write_compressed_ply(temp("src.compressed.ply"), g));
    GaussianCloud want;
    ASSERT_TRUE(gaussian::deform(l, *gaussian::read_gaussians(temp("src.compressed.ply")), want));
    fs::create_directories(temp("out_sog"));
    for (const fs::path& out : {temp("o.ply"), temp("o.compressed.ply"), temp("o.spz"), temp("o.sog"),
                                temp("o.glb"), temp("out_sog") / "meta.json"}) {
        SCOPED_TRACE(out.string());
        const RunResult r = run("deform", temp("src.compressed.ply").string() + " " + out.string() +
                                              " --lattice " + lat.string());
        ASSERT_EQ(r.code, 0) << r.err;
        auto got = gaussian::read_gaussians(out);
        ASSERT_TRUE(got) << got.message();
        ASSERT_EQ(got->size(), want.size());
        for (std::size_t i = 0; i < want.size(); ++i)
            ASSERT_LT(glm::length(got->positions[i] - want.positions[i]), 5e-3) << i;
    }
    // The stream's own options are refused with the reason, not ignored.
    RunResult r = run("deform", temp("src.compressed.ply").string() + " " + temp("x.ply").string() +
                                    " --lattice " + lat.string() + " --backend gpu");
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("deformed on the CPU"), std::string::npos) << r.err;
    r = run("deform", temp("src.compressed.ply").string() + " " + temp("x.xyz").string() + " --lattice " +
                          lat.string());
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("Gaussians also .compressed.ply, .spz, .sog or meta.json"), std::string::npos)
        << r.err;
}

// The table: each command on each format. render draws the Gaussians (coverage), pick hits one, convert
// and deform write the file's count, profile runs its frames, info names the count.
TEST(FormatCommands, EveryCommandReadsEveryFormat) {
    const GaussianCloud g = shell(600);
    const fs::path lat = temp("table.json");
    save_bent_lattice(lat);
    for (const FormatFile& f : write_every_format(g)) {
        SCOPED_TRACE(f.format);
        const std::size_t n = f.format == ".ksplat" ? 3 : g.size();
        const std::string in = "'" + f.path.string() + "'";
        RunResult r = run("info", in);
        EXPECT_EQ(r.code, 0) << r.err;
        EXPECT_NE(r.out.find(std::to_string(n) + " Gaussians"), std::string::npos) << r.out;

        r = run("convert", in + " " + temp("converted.ply").string() + " --gaussians");
        EXPECT_EQ(r.code, 0) << r.err;
        auto c = gaussian::read_ply(temp("converted.ply"));
        EXPECT_TRUE(c && c->size() == n) << (c ? std::to_string(c->size()) : c.message());

        r = run("deform", in + " " + temp("deformed.ply").string() + " --lattice fit");
        EXPECT_EQ(r.code, 0) << r.err;
        auto d = gaussian::read_ply(temp("deformed.ply"));
        EXPECT_TRUE(d && d->size() == n) << (d ? std::to_string(d->size()) : d.message());

        const fs::path frames = temp("render_" + std::to_string(std::hash<std::string>{}(f.format)));
        r = run("render", in + " --size 96x72 --out " + frames.string());
        if (r.code != 0 && r.err.find("EGL") != std::string::npos) SFFD_GL_UNAVAILABLE(r.err);
        EXPECT_EQ(r.code, 0) << r.err;
        auto png = render::read_png(frames / "frame_0000.png");
        ASSERT_TRUE(png) << png.message();
        std::size_t covered = 0;
        for (std::size_t p = 0; p < png->pixels.size() / 4; ++p) covered += png->pixels[p * 4 + 3] > 128;
        EXPECT_GT(covered, png->pixels.size() / 4 / 50) << "pixels drawn";

        r = run("pick", in + " --at 48,36 --size 96x72");
        EXPECT_EQ(r.code, 0) << r.err;
        EXPECT_NE(r.out.find("\"kind\":\"gaussian\""), std::string::npos) << r.out;

        r = run("profile", in + " --frames 1");
        EXPECT_EQ(r.code, 0) << r.err;
    }
}

}  // namespace
