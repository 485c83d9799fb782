// `splatffd deform` on 3DGS PLY files: same result as the library, --bench JSON, refusals.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "runtime/assets/formats/surface/ply.h"
#include "systems/ffd/lattice.h"
#include "systems/ffd/lattice_io.h"
#include "runtime/assets/builtin_scenes.h"
#include "systems/ffd/operations.h"
#include "systems/gaussian/from_splats.h"
#include "runtime/assets/formats/gaussian/gaussian_gltf.h"
#include "systems/gaussian/gaussian_read.h"
#include "runtime/assets/formats/gaussian/gaussian_axes.h"
#include "systems/gaussian/gaussian_deform.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "systems/gaussian/gaussian_math.h"
#include "systems/splat_render/image_io.h"
#include "tests/systems/gaussian/test_math.h"
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
    const fs::path d = fs::temp_directory_path() / ("sffd_gauss_cmd_" + std::to_string(getpid()));
    fs::create_directories(d);
    return d / name;
}

RunResult run(const std::string& args, const std::string& command = "deform") {
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

GaussianCloud cloud(std::size_t n) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-1, 1);
    GaussianCloud g;
    g.sh_degree = 3;
    for (std::size_t i = 0; i < n; ++i) {
        g.positions.emplace_back(u(rng), u(rng), u(rng));
        g.scales.emplace_back(0.02f + 0.01f * u(rng), 0.03f, 0.005f);
        g.rotations.push_back(glm::normalize(glm::quat(1.0f + u(rng), u(rng), u(rng), u(rng))));
        g.opacities.push_back(0.6f);
        for (int k = 0; k < 48; ++k) g.sh.push_back(0.3f * u(rng));
    }
    return g;
}

// A 4³ lattice around cloud(n), twisted by up to 0.5 rad about +y, saved to `path`.
Lattice save_twisted_lattice(const fs::path& path) {
    Lattice l = ffd::make_lattice(
        {-1.2, -1.2, -1.2}, {glm::dvec3(2.4, 0, 0), glm::dvec3(0, 2.4, 0), glm::dvec3(0, 0, 2.4)}, {4, 4, 4});
    ffd::twist_graded(l, ffd::all_control_points(l), {0, 1, 0}, 0.5, glm::dvec3(0.0));
    EXPECT_TRUE(ffd::save_lattice(path, l));
    return l;
}

// What the command wrote (`got`), its input as read back (`src`) and the library's CPU deformation of
// that input through `l` (`expect`), the reference the command must match.
struct Deformed {
    GaussianCloud got, src, expect;
};
Result<Deformed> read_and_deform(const fs::path& in, const fs::path& out, const Lattice& l) {
    Deformed d;
    auto got = gaussian::read_ply(out);
    if (!got) return got.error();
    auto src = gaussian::read_ply(in);
    if (!src) return src.error();
    if (auto s = gaussian::deform(l, *src, d.expect); !s) return s.error();
    d.got = std::move(*got), d.src = std::move(*src);
    return d;
}

TEST(GaussianDeformCommand, MatchesTheLibraryAndPrintsBenchJson) {
    const GaussianCloud g = cloud(70000);  // more than one 65,536-row chunk
    const fs::path in = temp("in.ply"), out = temp("out.ply"), lat = temp("lat.json");
    ASSERT_TRUE(gaussian::write_ply(in, g));
    const Lattice l = save_twisted_lattice(lat);
    const RunResult r = run(in.string() + " " + out.string() + " --lattice " + lat.string() + " --bench 2");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("{\"gaussians\":70000,\"sh_degree\":3,\"backend\":\"cpu\",\"median_ms\":"),
              std::string::npos)
        << r.out;
    EXPECT_NE(r.out.find("\"gaussians_per_s\":"), std::string::npos);
    auto d = read_and_deform(in, out, l);
    ASSERT_TRUE(d) << d.message();
    const GaussianCloud &got = d->got, &src = d->src, &expect = d->expect;
    ASSERT_EQ(got.size(), expect.size());
    for (std::size_t i = 0; i < got.size(); ++i) {
        EXPECT_EQ(got.positions[i], expect.positions[i]);
        EXPECT_LT(glm::length(got.scales[i] - expect.scales[i]), 1e-6f * glm::length(expect.scales[i]));
        EXPECT_LT(std::abs(std::abs(glm::dot(got.rotations[i], expect.rotations[i])) - 1.0f), 1e-6f);
        EXPECT_EQ(got.opacities[i], src.opacities[i]);
    }
    EXPECT_EQ(got.sh, expect.sh);
}

// Streaming over three chunks (140,000 rows > 2 x 65,536) of an ASCII 3DGS PLY that carries a property
// and an element the Gaussian layout does not know: the output equals the in-memory deformation of the
// whole file, and the unknown property and element come through unchanged.
TEST(GaussianDeformCommand, StreamsThreeChunksIdenticallyAndKeepsOtherData) {
    constexpr std::size_t n = 140000;
    const fs::path in = temp("stream_in.ply"), out = temp("stream_out.ply"), lat = temp("stream_lat.json");
    {
        std::ofstream f(in);
        f << "ply\nformat ascii 1.0\nelement vertex " << n
          << "\nproperty float x\nproperty float y\nproperty float z\n"
          << "property float confidence\nproperty float f_dc_0\nproperty float f_dc_1\nproperty float "
             "f_dc_2\n"
          << "property float opacity\nproperty float scale_0\nproperty float scale_1\nproperty float "
             "scale_2\n"
          << "property float rot_0\nproperty float rot_1\nproperty float rot_2\nproperty float rot_3\n"
          << "element camera 1\nproperty float fx\nend_header\n";
        for (std::size_t i = 0; i < n; ++i) {
            const double t = double(i);
            f << 0.9 * std::sin(t) << ' ' << 0.9 * std::cos(1.3 * t) << ' ' << 0.9 * std::sin(0.7 * t + 1)
              << ' ' << i % 1000 << " 0.1 -0.2 0.3 " << (i % 7) - 3.0 << ' ' << -4.0 - double(i % 3)
              << " -4.5 -5 " << 1.0 + 0.1 * std::sin(t) << ' ' << 0.2 * std::cos(t) << " 0.3 -0.1\n";
        }
        f << "1234.5\n";
    }
    Lattice l = ffd::make_lattice({-1, -1, -1},
                                  {glm::dvec3(2, 0, 0), glm::dvec3(0, 2, 0), glm::dvec3(0, 0, 2)}, {3, 3, 3});
    ffd::twist_graded(l, ffd::all_control_points(l), {0, 1, 0}, 0.7, glm::dvec3(0.0));
    ASSERT_TRUE(ffd::save_lattice(lat, l));
    const RunResult r = run(in.string() + " " + out.string() + " --lattice " + lat.string());
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.err.find("140000 Gaussians"), std::string::npos) << r.err;

    auto d = read_and_deform(in, out, l);
    ASSERT_TRUE(d) << d.message();
    const GaussianCloud &got = d->got, &src = d->src, &expect = d->expect;
    ASSERT_EQ(got.size(), n);
    std::size_t bad = 0;
    for (std::size_t i = 0; i < n; ++i) {
        bad += got.positions[i] != expect.positions[i];
        bad += !(glm::length(got.scales[i] - expect.scales[i]) <= 1e-6f * glm::length(expect.scales[i]));
        bad += !(std::abs(std::abs(glm::dot(got.rotations[i], expect.rotations[i])) - 1.0f) <= 1e-6f);
        bad += got.opacities[i] != src.opacities[i];
    }
    EXPECT_EQ(bad, 0u);
    EXPECT_EQ(got.sh, expect.sh);

    auto reader = ply::Reader::open(out);
    ASSERT_TRUE(reader) << reader.message();
    ASSERT_TRUE(reader->seek_element("vertex"));
    ply::Chunk chunk;
    std::size_t row = 0, wrong = 0;
    while (true) {
        auto rows = reader->read_rows(50000, chunk);
        ASSERT_TRUE(rows) << rows.message();
        if (*rows == 0) break;
        const int c = chunk.find("confidence");
        ASSERT_GE(c, 0);
        for (std::size_t k = 0; k < *rows; ++k, ++row)
            wrong += chunk.columns[std::size_t(c)].values[k] != double(row % 1000);
    }
    EXPECT_EQ(row, n);
    EXPECT_EQ(wrong, 0u);
    ASSERT_TRUE(reader->seek_element("camera"));
    auto rows = reader->read_rows(10, chunk);
    ASSERT_TRUE(rows);
    ASSERT_EQ(*rows, 1u);
    EXPECT_EQ(chunk.columns[std::size_t(chunk.find("fx"))].values[0], 1234.5);
}

using sffd::test::max_abs;

TEST(GaussianDeformCommand, GpuBackendMatchesTheLibrary) {
    // --backend gpu: the GPU deformation (coefficients rotated on the GPU) on a headless context, chunk by
    // chunk; the file matches the CPU library within the GPU tests' tolerances (float vs double).
    const GaussianCloud g = cloud(70000);  // two chunks
    const fs::path in = temp("gin.ply"), out = temp("gout.ply"), lat = temp("glat.json");
    ASSERT_TRUE(gaussian::write_ply(in, g));
    const Lattice l = save_twisted_lattice(lat);
    const RunResult r =
        run(in.string() + " " + out.string() + " --lattice " + lat.string() + " --backend gpu");
    if (r.code != 0 && r.err.find("--backend gpu: ") != std::string::npos)
        SFFD_GL_UNAVAILABLE("no GL context: " << r.err);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.err.find("0 not finite"), std::string::npos) << r.err;
    auto d = read_and_deform(in, out, l);
    ASSERT_TRUE(d) << d.message();
    const GaussianCloud &got = d->got, &src = d->src, &expect = d->expect;
    ASSERT_EQ(got.size(), expect.size());
    double ec = 0, es = 0, esh = 0;
    for (std::size_t i = 0; i < got.size(); ++i) {
        ec = std::max(ec, double(glm::length(got.positions[i] - expect.positions[i])));
        const glm::dmat3 s =
            gaussian::covariance(glm::dvec3(expect.scales[i]), glm::dquat(expect.rotations[i]));
        es = std::max(
            es, max_abs(gaussian::covariance(glm::dvec3(got.scales[i]), glm::dquat(got.rotations[i])) - s) /
                    max_abs(s));
        EXPECT_EQ(got.opacities[i], src.opacities[i]);
    }
    for (std::size_t k = 0; k < got.sh.size(); ++k)
        esh = std::max(esh, double(std::abs(got.sh[k] - expect.sh[k])));
    std::printf("deform --backend gpu: max centre error %.2e, relative Σ %.2e, SH %.2e\n", ec, es, esh);
    EXPECT_LT(ec, 5e-6);
    EXPECT_LT(es, 3e-5);  // the file's log scales and normalised quaternions add rounding of their own
    EXPECT_LT(esh, 5e-5);
}

TEST(GaussianDeformCommand, RefusesBadFiles) {
    const fs::path in = temp("small.ply"), out = temp("o.ply"), lat = temp("l.json");
    ASSERT_TRUE(gaussian::write_ply(in, cloud(10)));
    ASSERT_TRUE(ffd::save_lattice(
        lat, ffd::make_lattice({-1, -1, -1}, {glm::dvec3(2, 0, 0), glm::dvec3(0, 2, 0), glm::dvec3(0, 0, 2)},
                               {2, 2, 2})));
    RunResult r;
    const fs::path bad = temp("bad.ply");
    std::ofstream(bad)
        << "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
           "property float f_dc_0\nproperty float f_dc_1\nproperty float f_dc_2\nproperty float opacity\n"
           "property float scale_0\nproperty float scale_1\nproperty float scale_2\nproperty float rot_0\n"
           "property float rot_1\nproperty float rot_2\nproperty float rot_3\nend_header\n"
           "0 0 0 0 0 0 0 0 0 nan 1 0 0 0\n";
    r = run(bad.string() + " " + out.string() + " --lattice " + lat.string());
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find(bad.string() + ": vertex 0: non-finite 'scale_2'"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));  // nothing half-written
}

TEST(GaussianConvertCommand, BuiltinSphereToGaussiansAndBetweenFormats) {
    const fs::path ply = temp("sphere.ply"), glb = temp("sphere.glb");
    RunResult r = run("sphere " + ply.string() + " --gaussians --splats 1000", "convert");
    ASSERT_EQ(r.code, 0) << r.err;
    auto g = gaussian::read_ply(ply);
    ASSERT_TRUE(g) << g.message();
    // Written as a capture is stored, y down (systems/gaussian/capture_up.h): the sphere turned about x.
    GaussianCloud expect = gaussian::gaussians_from_splats(assets::make_sphere_cloud(1000));
    gaussian::turn_axes(expect, gaussian::AxisTurn::x180);
    ASSERT_EQ(g->size(), 1000u);
    for (std::size_t i = 0; i < g->size(); ++i) EXPECT_EQ(g->positions[i], expect.positions[i]);
    EXPECT_EQ(g->sh, expect.sh);
    r = run(ply.string() + " " + glb.string() + " --gaussians", "convert");  // Gaussian file in, KHR glb out
    ASSERT_EQ(r.code, 0) << r.err;
    auto back = gaussian::read_gltf(glb);
    ASSERT_TRUE(back) << back.message();
    EXPECT_EQ(back->positions, g->positions);
    EXPECT_EQ(back->sh, g->sh);
    r = run("sphere " + temp("x.obj").string() + " --gaussians", "convert");
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(
        r.err.find(
            "Gaussians are written as .ply (3DGS), .compressed.ply (PlayCanvas), .spz (v3 or v4) or .glb"),
        std::string::npos)
        << r.err;
}

TEST(GaussianRenderCommand, RendersAGaussianFileToPng) {
    const fs::path ply = temp("r_sphere.ply"), dir = temp("render_out");
    ASSERT_EQ(run("sphere " + ply.string() + " --gaussians --splats 20000", "convert").code, 0);
    RunResult r =
        run(ply.string() + " --out " + dir.string() + " --size 160x120 --background 1,1,1", "render");
    if (r.code == 1 && r.err.find("EGL") != std::string::npos) SFFD_GL_UNAVAILABLE("no EGL: " << r.err);
    ASSERT_EQ(r.code, 0) << r.err;
    auto png = render::read_png(dir / "frame_0000.png");
    ASSERT_TRUE(png) << png.message();
    ASSERT_EQ(png->width, 160);
    // The sphere fills the middle (not white: its colours are dark or saturated), the corners are the
    // white background.
    const std::uint8_t* mid = png->at(80, 60);
    EXPECT_LT(int(mid[0]) + int(mid[1]) + int(mid[2]), 600);
    const std::uint8_t* corner = png->at(2, 2);
    EXPECT_EQ(corner[0], 255);
    EXPECT_EQ(corner[1], 255);
    EXPECT_EQ(corner[2], 255);
    EXPECT_EQ(corner[3], 255);
    r = run(temp("absent.splat").string() + " --out " + dir.string(), "render");
    EXPECT_NE(r.code, 0);
}

}  // namespace
