// What the format command tests share (format_commands_test.cpp, format_table_test.cpp): the built
// `splatffd`, a scratch folder, a shell of Gaussians, a file of each Gaussian format the commands read and
// a bent lattice.
#pragma once

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
#include "runtime/assets/formats/gaussian/gaussian_compressed_ply.h"
#include "systems/gaussian/gaussian_read.h"
#include "systems/gaussian/gaussian_deform.h"
#include "runtime/assets/formats/gaussian/gaussian_gltf.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "systems/gaussian/gaussian_math.h"
#include "systems/gaussian/sh.h"
#include "runtime/assets/formats/gaussian/gaussian_sog.h"
#include "runtime/assets/formats/gaussian/gaussian_spz.h"
#include "systems/splat_render/image_io.h"
#include "tests/test_util/gl_required.h"

namespace sffd::test::formats {

namespace fs = std::filesystem;

inline const std::string kTool = SFFD_BINARY_DIR "/tools/splatffd";

struct RunResult {
    int code = -1;
    std::string out, err;
};

inline fs::path temp(const std::string& name) {
    const fs::path d = fs::temp_directory_path() / ("sffd_format_cmd_" + std::to_string(getpid()));
    fs::create_directories(d);
    return d / name;
}

inline RunResult run(const std::string& command, const std::string& args) {
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
inline GaussianCloud shell(std::size_t n) {
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
inline void write_splat(const fs::path& p, const GaussianCloud& g) {
    std::string bytes;
    for (std::size_t i = 0; i < g.size(); ++i) {
        const float f[6] = {g.positions[i].x, g.positions[i].y, g.positions[i].z,
                            g.scales[i].x,    g.scales[i].y,    g.scales[i].z};
        bytes.append(reinterpret_cast<const char*>(f), sizeof f);
        unsigned char c[8];
        for (int k = 0; k < 3; ++k)
            c[k] = static_cast<unsigned char>(std::clamp(
                std::lround((0.5 + gaussian::kShC0 * double(g.sh[i * 12 + std::size_t(k)])) * 255.0), 0l,
                255l));
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
inline void write_ksplat(const fs::path& p) {
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
inline std::vector<FormatFile> write_every_format(const GaussianCloud& g) {
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
inline Lattice save_bent_lattice(const fs::path& path) {
    Lattice l = ffd::make_lattice(
        {-1.1, -1.1, -1.1}, {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)}, {3, 3, 3});
    ffd::twist_graded(l, ffd::all_control_points(l), {0, 1, 0}, 0.4, glm::dvec3(0.0));
    for (glm::dvec3& p : l.current)
        if (p.y > 0) p += glm::dvec3(0.3 * p.y, 0.4 * p.y, 0.0);
    EXPECT_TRUE(ffd::save_lattice(path, l));
    return l;
}

}  // namespace sffd::test::formats
