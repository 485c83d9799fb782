// The level-of-detail hierarchy through the built binary: `convert IN DIR/lod-meta.json` (3DGS PLY,
// another Gaussian format, synthetic-gaussians:N) with its --lod-* options and progress, `info` on it,
// refused options, a lod-meta.json read back by convert, and `render`/`profile` of a lod-meta.json at full
// detail: the render equals the plain render of the same Gaussians (its finest level written as a 3DGS PLY),
// PSNR >= 40 dB, alone and deformed by a lattice from a scene that refers to the lod-meta.json.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <random>
#include <string>

#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "runtime/assets/formats/lod/streamed_sog.h"
#include "runtime/assets/scene.h"
#include "runtime/scene/lattice.h"
#include "systems/gaussian/gaussian_deform.h"
#include "systems/ffd/lattice_io.h"
#include "systems/ffd/deform.h"
#include "runtime/assets/formats/surface/potree2.h"
#include "systems/engine/engine_frame.h"
#include "systems/ffd/operations.h"
#include "systems/gaussian/gaussian_read.h"
#include "systems/splat_render/image_compare.h"
#include "systems/splat_render/image_io.h"
#include "tests/test_util/run_tool.h"

namespace fs = std::filesystem;
using namespace sffd;

namespace {

using sffd::test::CliRun;
CliRun tool(const std::string& args) { return sffd::test::run_headless(args); }

fs::path temp(const std::string& name) {
    const fs::path d = fs::temp_directory_path() / ("sffd_lod_cmd_" + std::to_string(::getpid()));
    fs::create_directories(d);
    return d / name;
}

// A shell of Gaussians with colours and some view dependence, in the 3DGS frame (y down).
GaussianCloud shell(std::size_t n) {
    std::mt19937 rng(4);
    std::normal_distribution<float> nd;
    std::uniform_real_distribution<float> u(0, 1);
    GaussianCloud g;
    g.sh_degree = 1;
    for (std::size_t i = 0; i < n; ++i) {
        const glm::vec3 d = glm::normalize(glm::vec3(nd(rng), nd(rng), nd(rng)));
        g.positions.push_back(d * (1.0f + 0.05f * u(rng)));
        g.scales.emplace_back(0.05f + 0.02f * u(rng), 0.05f + 0.02f * u(rng), 0.01f);
        g.rotations.push_back(glm::normalize(glm::quat(nd(rng), nd(rng), nd(rng), nd(rng))));
        g.opacities.push_back(0.5f + 0.45f * u(rng));
        for (int c = 0; c < 3; ++c) g.sh.push_back(1.5f * d[c]);
        for (int k = 0; k < 9; ++k) g.sh.push_back(0.1f * nd(rng));
    }
    return g;
}

render::FrameImage render_exr(const std::string& scene, const std::string& name) {
    const fs::path out = temp(name);
    const CliRun r = tool("render " + scene + " --out " + out.string() +
                          " --size 320x240 --format exr --camera 0.4,-0.6,3.6,0,0,0,0,1,0,40");
    EXPECT_EQ(r.code, 0) << r.out;
    auto img = render::read_exr(out / "frame_0000.exr");
    EXPECT_TRUE(img) << img.message();
    return img ? std::move(*img) : render::FrameImage{};
}

double psnr(const render::FrameImage& a, const render::FrameImage& b) {
    auto c = render::compare_images(a, b);
    EXPECT_TRUE(c) << c.message();
    EXPECT_GT(c ? c->pixels : 0u, 2000u);
    return c ? c->psnr : 0.0;
}

TEST(LodCommand, ConvertsSyntheticGaussiansWithProgressAndInfoDescribesIt) {
    const fs::path meta = temp("syn") / "lod-meta.json";
    const CliRun r = tool("convert synthetic-gaussians:30k " + meta.string() +
                          " --lod-levels 3 --lod-ratio 4 --lod-chunk-count 4 --lod-memory 64 --progress");
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_NE(r.out.find("convert: building"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("wrote " + meta.string() + ": "), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("in 3 levels (30000, "), std::string::npos) << r.out;
    auto s = lod::open_streamed_sog(meta);
    ASSERT_TRUE(s) << s.message();
    EXPECT_EQ(s->counts[0], 30000u);
    // Built again into the same folder with fewer units: the old units it no longer names are removed.
    const CliRun again = tool("convert synthetic-gaussians:30k " + meta.string() + " --lod-levels 2");
    ASSERT_EQ(again.code, 0) << again.out;
    EXPECT_NE(again.out.find("removed "), std::string::npos) << again.out;
    EXPECT_FALSE(fs::exists(meta.parent_path() / "2_0"));
    EXPECT_FALSE(fs::exists(meta.parent_path() / "0_1"));
    auto s2 = lod::open_streamed_sog(meta);
    ASSERT_TRUE(s2) << s2.message();
    EXPECT_TRUE(lod::read_level(*s2, 1));
    ASSERT_EQ(tool("convert synthetic-gaussians:30k " + meta.string() +
                   " --lod-levels 3 --lod-ratio 4 --lod-chunk-count 4 --lod-memory 64")
                  .code,
              0);
    const CliRun info = tool("info " + meta.string());
    ASSERT_EQ(info.code, 0) << info.out;
    for (const char* line : {"streamed SOG (lod-meta.json version 1, written by splatffd)", "levels: 3",
                             "level 0: 30000 Gaussians in", "tree: ", "bounds: ["})
        EXPECT_NE(info.out.find(line), std::string::npos) << line << "\n" << info.out;
}

// splat-transform's split rule: past the extent, a node splits only while it holds more than the chunk
// minimum (default 8K), so 20,000 Gaussians wider than 1 everywhere make 4 leaves of 5,000, and 128 of
// 156 or 157 (down to the 256-Gaussian buckets) with a minimum of 0.
TEST(LodCommand, ChunkExtentSplitsDownToTheChunkMinimum) {
    const auto chunks = [](const std::string& options) -> long {
        const CliRun r = tool("convert synthetic-gaussians:20k " + (temp("min") / "lod-meta.json").string() +
                              " " + options);
        EXPECT_EQ(r.code, 0) << r.out;
        const auto at = r.out.find(" chunks,");
        if (at == std::string::npos) return -1;
        const auto from = r.out.rfind(' ', at - 1) + 1;
        return std::stol(r.out.substr(from, at - from));
    };
    EXPECT_EQ(chunks("--lod-chunk-extent 1"), 4);
    EXPECT_EQ(chunks("--lod-chunk-extent 1 --lod-chunk-min 0"), 128);
    EXPECT_EQ(chunks("--lod-chunk-extent 100 --lod-chunk-min 0"), 1);
}

TEST(LodCommand, ConvertsGaussianFilesAndReadsTheHierarchyBack) {
    const GaussianCloud g = shell(4000);
    const fs::path ply = temp("s.ply"), spz = temp("s.spz");
    ASSERT_TRUE(gaussian::write_ply(ply, g));
    ASSERT_EQ(tool("convert " + ply.string() + " " + spz.string()).code, 0);
    for (const fs::path& in : {ply, spz}) {
        const fs::path meta = temp("from_" + in.extension().string().substr(1)) / "lod-meta.json";
        const CliRun r = tool("convert " + in.string() + " " + meta.string() + " --lod-chunk-count 1");
        ASSERT_EQ(r.code, 0) << r.out;
        // convert reads a lod-meta.json as its finest level.
        const fs::path back = temp("back_" + in.extension().string().substr(1) + ".ply");
        const CliRun b = tool("convert " + meta.string() + " " + back.string());
        ASSERT_EQ(b.code, 0) << b.out;
        auto cloud = gaussian::read_gaussians(back);
        ASSERT_TRUE(cloud) << cloud.message();
        EXPECT_EQ(cloud->size(), g.size());
        EXPECT_EQ(cloud->sh_degree, 1);
    }
    // Refusals: options of other outputs, bad values, a surface input.
    CliRun r =
        tool("convert " + ply.string() + " " + (temp("x") / "lod-meta.json").string() + " --lattice fit");
    EXPECT_EQ(r.code, 2) << r.out;
    EXPECT_NE(r.out.find("'--lattice' does not apply to a lod-meta.json output"), std::string::npos) << r.out;
    r = tool("convert " + ply.string() + " " + (temp("x") / "lod-meta.json").string() + " --lod-levels 40");
    EXPECT_EQ(r.code, 2) << r.out;
    EXPECT_NE(r.out.find("--lod-levels"), std::string::npos) << r.out;
    r = tool("convert sphere " + (temp("x") / "lod-meta.json").string());
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_NE(r.out.find("not a Gaussian file"), std::string::npos) << r.out;
    r = tool("convert " + ply.string() + " " + temp("lod-meta.json").string() + " --help");
    EXPECT_EQ(r.code, 0);
    EXPECT_NE(r.out.find("--lod-chunk-count"), std::string::npos) << r.out;
}

TEST(LodCommand, FullDetailRendersLikeThePlainCloud) {
    const GaussianCloud g = shell(6000);
    const fs::path ply = temp("r.ply"), meta = temp("r") / "lod-meta.json", level0 = temp("r_level0.ply");
    ASSERT_TRUE(gaussian::write_ply(ply, g));
    ASSERT_EQ(tool("convert " + ply.string() + " " + meta.string() + " --lod-chunk-count 2").code, 0);
    auto s = lod::open_streamed_sog(meta);
    ASSERT_TRUE(s) << s.message();
    EXPECT_GT(s->units.size(), 2u);
    auto finest = lod::read_level(*s, 0);
    ASSERT_TRUE(finest) << finest.message();
    ASSERT_TRUE(gaussian::write_ply(level0, *finest));
    const auto lod_image = render_exr(meta.string(), "img_lod");
    const auto plain = render_exr(level0.string(), "img_level0");
    const auto original = render_exr(ply.string(), "img_original");
    const double same = psnr(lod_image, plain), quantised = psnr(lod_image, original);
    std::printf(
        "  full-detail render vs its finest level as a PLY: %.1f dB; vs the unquantised input: %.1f dB\n",
        same, quantised);
    EXPECT_GE(same, 40.0);
    EXPECT_GE(quantised, 30.0);

    // The same under a twisted lattice, from scenes that refer to each file.
    const auto scene_of = [&](const fs::path& file, const fs::path& scene) {
        ecs::Registry r;
        sffd::use_engine_scene_hooks(r);
        ASSERT_TRUE(load_scene(r, file.string()));
        ecs::Entity cloud{};
        r.each_entity([&](ecs::Entity e) {
            if (r.has<GaussianCloud>(e)) cloud = e;
        });
        const GaussianCloud& c = r.get<GaussianCloud>(cloud);
        auto l = ffd::fit_lattice(c.positions, c.origin, ffd::FitOptions{glm::ivec3(3, 3, 3)});
        ASSERT_TRUE(l) << l.message();
        ffd::twist_graded(*l, ffd::all_control_points(*l), glm::dvec3(0, 1, 0), 1.2);
        const ecs::Entity le = r.create();
        r.emplace<Transform>(le, r.get<Transform>(cloud));
        r.emplace<Lattice>(le, std::move(*l));
        r.emplace<Deformers>(cloud, Deformers{{le}});
        ASSERT_TRUE(save_scene(r, scene));
    };
    const fs::path scene_lod = temp("lod_scene.glb"), scene_plain = temp("plain_scene.glb");
    scene_of(meta, scene_lod);
    scene_of(level0, scene_plain);
    // The scene refers to the hierarchy rather than embedding its Gaussians (6,000 would be ~400 KB).
    EXPECT_LT(fs::file_size(scene_lod), 100000u);
    const double twisted = psnr(render_exr(scene_lod.string(), "img_lod_twist"),
                                render_exr(scene_plain.string(), "img_plain_twist"));
    std::printf("  twisted by a scene's lattice: %.1f dB\n", twisted);
    EXPECT_GE(twisted, 40.0);

    const CliRun p = tool("profile " + meta.string() + " --frames 2 --warmup 1 --sync");
    EXPECT_EQ(p.code, 0) << p.out;
}

// `deform IN/lod-meta.json OUT/lod-meta.json` and `deform IN/metadata.json OUT/metadata.json`: the finest
// detail deformed piece by piece and the levels built again. OUT's finest detail is IN's deformed by the
// same lattice in this process (Gaussians within SOG's quantisation, splats within the octree's position
// scale), and its coarse levels are those of the deformed shape (their box is the deformed one).
TEST(LodCommand, DeformWritesTheDeformedHierarchy) {
    const fs::path lattice_file = temp("twist.json");
    {
        Lattice l = make_lattice(glm::dvec3(-11.0),
                                 {glm::dvec3(22, 0, 0), glm::dvec3(0, 22, 0), glm::dvec3(0, 0, 22)},
                                 glm::ivec3(4), LatticeBasis::bernstein);
        ffd::twist_graded(l, ffd::all_control_points(l), glm::dvec3(0, 1, 0), 0.08);
        ffd::stretch(l, ffd::select_range(l, glm::ivec3(4, 0, 0), glm::ivec3(4)), glm::dvec3(6.0, 0, 0));
        ASSERT_TRUE(ffd::save_lattice(lattice_file, l));
    }
    auto lattice = ffd::load_lattice(lattice_file);
    ASSERT_TRUE(lattice) << lattice.message();
    // Gaussians.
    const fs::path in = temp("dg_in") / "lod-meta.json", out = temp("dg_out") / "lod-meta.json";
    ASSERT_EQ(tool("convert synthetic-gaussians:30k " + in.string() + " --lod-chunk-count 8").code, 0);
    const CliRun d =
        tool("deform " + in.string() + " " + out.string() + " --lattice " + lattice_file.string());
    ASSERT_EQ(d.code, 0) << d.out;
    EXPECT_NE(d.out.find("30000 Gaussians deformed by 1 lattice"), std::string::npos) << d.out;
    auto sin = lod::open_streamed_sog(in), sout = lod::open_streamed_sog(out);
    ASSERT_TRUE(sin) << sin.message();
    ASSERT_TRUE(sout) << sout.message();
    EXPECT_EQ(sout->levels, sin->levels);
    auto fine = lod::read_level(*sin, 0), got = lod::read_level(*sout, 0);
    ASSERT_TRUE(fine && got);
    ASSERT_EQ(got->size(), fine->size());
    GaussianCloud want = *fine;
    ASSERT_TRUE(gaussian::deform(*lattice, want, want, {}));
    const auto box = [](const GaussianCloud& g) {
        glm::dvec3 lo(1e30), hi(-1e30);
        for (const auto& p : g.positions)
            lo = glm::min(lo, g.origin + glm::dvec3(p)), hi = glm::max(hi, g.origin + glm::dvec3(p));
        return std::pair{lo, hi};
    };
    const auto [wlo, whi] = box(want);
    const auto [glo, ghi] = box(*got);
    EXPECT_LT(glm::length(wlo - glo), 0.05);
    EXPECT_LT(glm::length(whi - ghi), 0.05);
    EXPECT_GT(whi.x - wlo.x, 22.0);  // stretched along x: the sphere of radius 10 is now wider
    // Nearest-centre agreement on a sample (SOG quantises positions to 16 bits per axis).
    std::size_t far = 0;
    for (std::size_t i = 0; i < want.size(); i += 97) {
        const glm::dvec3 w = want.origin + glm::dvec3(want.positions[i]);
        double best = 1e30;
        for (const auto& p : got->positions)
            best = std::min(best, glm::length(got->origin + glm::dvec3(p) - w));
        if (best > 0.01) ++far;
    }
    EXPECT_EQ(far, 0u);
    // The coarsest level follows the deformed shape.
    auto coarse = lod::read_level(*sout, sout->levels - 1);
    ASSERT_TRUE(coarse);
    const auto [clo, chi] = box(*coarse);
    EXPECT_GT(chi.x - clo.x, 0.9 * (whi.x - wlo.x));

    // Splats.
    const fs::path pin = temp("dp_in") / "metadata.json", pout = temp("dp_out") / "metadata.json";
    ASSERT_EQ(tool("convert synthetic:50k " + pin.string()).code, 0);
    Lattice small =
        make_lattice(glm::dvec3(-1.1), {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)},
                     glm::ivec3(3), LatticeBasis::bernstein);
    ffd::twist_graded(small, ffd::all_control_points(small), glm::dvec3(0, 1, 0), 0.7);
    const fs::path small_file = temp("twist_small.json");
    ASSERT_TRUE(ffd::save_lattice(small_file, small));
    const CliRun dp =
        tool("deform " + pin.string() + " " + pout.string() + " --lattice " + small_file.string());
    ASSERT_EQ(dp.code, 0) << dp.out;
    auto oin = assets::open_potree2(pin), oout = assets::open_potree2(pout);
    ASSERT_TRUE(oin && oout);
    auto a = assets::read_potree2(*oin), b = assets::read_potree2(*oout);
    ASSERT_TRUE(a && b);
    ASSERT_EQ(a->size(), b->size());
    ffd::PointsIn pi{a->positions.data(), a->normals.data(), a->axis_u.data(),
                     a->axis_v.data(),    a->size(),         a->origin};
    ffd::PointsOut po{a->positions.data(), a->normals.data(), a->axis_u.data(), a->axis_v.data()};
    ASSERT_TRUE(ffd::deform(small, pi, po));
    const auto sorted = [](const SplatCloud& c) {
        std::vector<std::array<double, 3>> v;
        for (const auto& p : c.positions) {
            const glm::dvec3 w = c.origin + glm::dvec3(p);
            v.push_back({w.x, w.y, w.z});
        }
        std::sort(v.begin(), v.end());
        return v;
    };
    const auto wa = sorted(*a), wb = sorted(*b);
    const double tol = 2.0 * oout->scale.x;
    std::size_t off = 0;
    for (std::size_t i = 0; i < wa.size(); ++i)
        for (int c = 0; c < 3; ++c)
            if (std::abs(wa[i][std::size_t(c)] - wb[i][std::size_t(c)]) > tol) ++off;
    EXPECT_LT(off, wa.size() / 1000) << "of " << wa.size() << " splats, tolerance " << tol;
    // Another kind or the same folder is refused by name.
    const CliRun bad = tool("deform " + pin.string() + " " + (temp("dp_x") / "lod-meta.json").string() +
                            " --lattice " + small_file.string());
    EXPECT_EQ(bad.code, 1);
    EXPECT_NE(bad.out.find("lod-meta.json"), std::string::npos) << bad.out;
}

}  // namespace
