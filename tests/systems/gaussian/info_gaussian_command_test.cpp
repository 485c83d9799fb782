// `splatffd info` on every Gaussian format the other commands read, run as a user would (the built
// binary): the "N Gaussians, SH degree D" line, the infinity log line, and the list of expected types.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <cstring>
#include <sstream>

#include <zlib.h>

#include "runtime/assets/formats/gaussian/gaussian_compressed_ply.h"
#include "systems/gaussian/gaussian_read.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"

namespace {

namespace fs = std::filesystem;
using namespace sffd;

const std::string kTool = SFFD_BINARY_DIR "/tools/splatffd";

struct RunResult {
    int code = -1;
    std::string out, err;
};

fs::path temp(const std::string& name) {
    const fs::path d = fs::temp_directory_path() / ("sffd_info_gauss_" + std::to_string(getpid()));
    fs::create_directories(d);
    return d / name;
}

RunResult info(const fs::path& file) {
    const std::string o = temp("stdout.txt").string(), e = temp("stderr.txt").string();
    const int status = std::system((kTool + " info '" + file.string() + "' >" + o + " 2>" + e).c_str());
    RunResult r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    std::stringstream so, se;
    so << std::ifstream(o).rdbuf();
    se << std::ifstream(e).rdbuf();
    r.out = so.str(), r.err = se.str();
    return r;
}

GaussianCloud cloud(std::size_t n, int degree) {
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> u(-1, 1);
    GaussianCloud g;
    g.sh_degree = degree;
    for (std::size_t i = 0; i < n; ++i) {
        g.positions.emplace_back(u(rng), u(rng), u(rng));
        g.scales.emplace_back(0.05f, 0.04f, 0.03f);
        g.rotations.push_back(glm::normalize(glm::quat(u(rng), u(rng), u(rng), u(rng))));
        g.opacities.push_back(0.5f);
        for (int k = 0; k < sh_coeffs(degree) * 3; ++k) g.sh.push_back(0.3f * u(rng));
    }
    return g;
}

TEST(InfoGaussians, PlyAndCompressedPlySummaries) {
    const fs::path ply = temp("g.ply"), comp = temp("g.compressed.ply");
    ASSERT_TRUE(gaussian::write_ply(ply, cloud(123, 2)));
    ASSERT_TRUE(gaussian::write_compressed_ply(comp, cloud(300, 1)));
    RunResult r = info(ply);
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("123 Gaussians, SH degree 2"), std::string::npos) << r.out;
    r = info(comp);
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("compressed PLY"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("300 Gaussians, SH degree 1"), std::string::npos) << r.out;
}

TEST(InfoGaussians, SplatAndSpzAreRead) {
    // .splat: two rows of 32 bytes.
    std::string bytes;
    for (int i = 0; i < 2; ++i) {
        const float f[6] = {float(i), 0, 0, 0.1f, 0.1f, 0.1f};
        bytes.append(reinterpret_cast<const char*>(f), sizeof f);
        const unsigned char c[8] = {200, 100, 50, 255, 255, 128, 128, 128};
        bytes.append(reinterpret_cast<const char*>(c), sizeof c);
    }
    const fs::path splat = temp("g.splat");
    std::ofstream(splat, std::ios::binary) << bytes;
    RunResult r = info(splat);
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("2 Gaussians, SH degree 0"), std::string::npos) << r.out;
    // SPZ v2, one splat of degree 0 (header, position, alpha, colour, scale, rotation).
    std::string b;
    auto put32 = [&](std::uint32_t v) {
        for (int i = 0; i < 4; ++i) b.push_back(char((v >> (8 * i)) & 0xff));
    };
    put32(0x5053474e), put32(2), put32(1);
    b += char(0), b += char(12), b += char(0), b += char(0);
    b += std::string(9, '\0') + std::string(1, char(255)) + std::string(3, char(128)) +
         std::string(3, char(160)) + std::string(3, char(128));
    const fs::path spz = temp("g.spz");
    gzFile f = gzopen(spz.c_str(), "wb");
    ASSERT_NE(f, nullptr);
    gzwrite(f, b.data(), unsigned(b.size()));
    gzclose(f);
    r = info(spz);
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("1 Gaussians, SH degree 0"), std::string::npos) << r.out;
}

TEST(InfoGaussians, InfinitiesAreCountedAndUnknownTypesListEveryFormat) {
    const fs::path ply = temp("inf.ply");
    GaussianCloud g = cloud(4, 0);
    ASSERT_TRUE(gaussian::write_ply(ply, g));
    // Rewrite the opacity column of row 0 to +inf the way splat-transform does (float bits 0x7f800000).
    std::string text;
    {
        std::stringstream s;
        s << std::ifstream(ply, std::ios::binary).rdbuf();
        text = s.str();
    }
    const std::size_t data = text.find("end_header\n") + 11;
    const int opacity_column = 9;  // x y z nx ny nz f_dc_0..2 opacity ...
    const float inf = INFINITY;
    std::memcpy(&text[data + std::size_t(opacity_column) * 4], &inf, 4);
    std::ofstream(ply, std::ios::binary) << text;
    // info lists the header; render/convert read the file and log the mapped count.
    const std::string o = temp("convert.txt").string();
    const int status = std::system((kTool + " convert '" + ply.string() + "' '" + temp("out.ply").string() +
                                    "' --gaussians >" + o + " 2>&1")
                                       .c_str());
    EXPECT_EQ(WEXITSTATUS(status), 0);
    std::stringstream so;
    so << std::ifstream(o).rdbuf();
    EXPECT_NE(so.str().find("read 1 infinite values as limits (1 logit opacities"), std::string::npos)
        << so.str();

    const fs::path odd = temp("g.xyz");
    std::ofstream(odd) << "1 2 3\n";
    RunResult r = info(odd);
    EXPECT_NE(r.code, 0);
    EXPECT_NE(r.err.find(odd.string() + ": unknown file type '.xyz' (expected .ply, .obj, .off, .gltf, .glb, "
                                        ".spz, .splat, .ksplat, .sog or a "
                                        "SOG folder's meta.json)"),
              std::string::npos)
        << r.err;
}

TEST(InfoGaussians, CompressedPlyConvertsToGaussiansWithoutAsking) {
    // A Gaussian input stays Gaussian (read as a point cloud it would lose colour, opacity and SH): the
    // compressed PLY is expanded to a 3DGS PLY without --gaussians.
    const fs::path comp = temp("p.compressed.ply");
    ASSERT_TRUE(gaussian::write_compressed_ply(comp, cloud(10, 0)));
    const std::string o = temp("pc.txt").string();
    const int status = std::system(
        (kTool + " convert '" + comp.string() + "' '" + temp("pc.ply").string() + "' >" + o + " 2>&1")
            .c_str());
    EXPECT_EQ(WEXITSTATUS(status), 0);
    std::stringstream so;
    so << std::ifstream(o).rdbuf();
    EXPECT_NE(so.str().find(": 10 Gaussians"), std::string::npos) << so.str();
    auto back = gaussian::read_gaussians(temp("pc.ply"));
    ASSERT_TRUE(back) << back.message();
    EXPECT_EQ(back->size(), 10u);
}

}  // namespace
