// Gaussian scenes and the commands that used to do nothing silently, through the built binary as a user
// meets them: a Gaussian file converted with --lattice stays Gaussian (colour kept) with its lattice, which
// render and deform then apply; outputs that cannot hold a lattice are refused; a lattice around none of
// the points, an obb fit that falls back to a box, `view --headless` without an end and
// `--window-screenshot` without a window are said, not silent; a clip keyed in the editor on a Gaussian
// file and saved plays when rendered.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "systems/ffd/lattice_io.h"
#include "systems/ffd/operations.h"
#include "tests/test_util/run_tool.h"

namespace fs = std::filesystem;
using sffd::test::CliRun;

namespace {

fs::path temp_dir(const std::string& name) {
    const fs::path d =
        fs::temp_directory_path() / ("sffd_gaussian_scene_" + std::to_string(::getpid())) / name;
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

CliRun tool(const std::string& args) { return sffd::test::run_headless(args); }

// A Gaussian 3DGS PLY made from the built-in sphere (colours from its texture).
fs::path gaussian_sphere(const fs::path& dir) {
    const fs::path g = dir / "g.ply";
    const CliRun r = tool("convert sphere " + g.string() + " --gaussians --splats 4000");
    EXPECT_EQ(r.code, 0) << r.out;
    return g;
}

const std::string kCamera = " --camera 0,0.6,3.2,0,0,0,0,1,0,40";

// Frame 0 of `scene` as EXR, rendered with a fixed camera (the same view for every scene).
fs::path render_exr(const std::string& scene, const fs::path& out) {
    const CliRun r = tool("render " + scene + " --out " + out.string() +
                          " --size 160x120 --quality preview --format exr" + kCamera);
    EXPECT_EQ(r.code, 0) << r.out;
    return out / "frame_0000.exr";
}

// psnr_db of `compare A B` (inf for identical images; NaN when compare failed).
double psnr(const fs::path& a, const fs::path& b) {
    const CliRun r = tool("compare " + a.string() + " " + b.string());
    const auto at = r.out.find("psnr_db=");
    if (r.code != 0 || at == std::string::npos) {
        ADD_FAILURE() << r.out;
        return std::nan("");
    }
    return std::strtod(r.out.c_str() + at + 8, nullptr);
}

bool has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

}  // namespace

TEST(GaussianScene, ConvertKeepsGaussiansAndTheirFittedLatticeWhichRenderAndDeformApply) {
    const fs::path dir = temp_dir("convert");
    const fs::path g = gaussian_sphere(dir);
    // The command `info` suggests, with and without --gaussians: the same Gaussian scene.
    for (const std::string& extra : {std::string(), std::string(" --gaussians")}) {
        const fs::path out = dir / ("scene" + std::to_string(extra.size()) + ".glb");
        const CliRun c = tool("convert " + g.string() + " " + out.string() + " --lattice fit" + extra);
        ASSERT_EQ(c.code, 0) << c.out;
        EXPECT_TRUE(has(c.out, "Gaussians")) << c.out;
        const CliRun info = tool("info " + out.string());
        ASSERT_EQ(info.code, 0) << info.out;
        EXPECT_TRUE(has(info.out, "gaussians 'g': 4000 Gaussians")) << info.out;
        EXPECT_TRUE(has(info.out, "deformed by")) << info.out;
        EXPECT_TRUE(has(info.out, "lattice  'g.lattice'")) << info.out;
        EXPECT_TRUE(has(info.out, "total    0 splats")) << info.out;  // no white surface cloud
    }
    // Colour kept: the scene at rest renders as the Gaussian file does.
    const fs::path plain = render_exr(g.string(), dir / "r_plain");
    const fs::path scene = render_exr((dir / "scene0.glb").string(), dir / "r_scene");
    EXPECT_GT(psnr(plain, scene), 40.0);

    // A twisted lattice bound by convert deforms the Gaussians in render, and deform writes them twisted.
    const fs::path json = dir / "lattice.json", twisted_json = dir / "twisted.json";
    const CliRun e = tool("convert " + (dir / "scene0.glb").string() + " " + json.string());
    ASSERT_EQ(e.code, 0) << e.out;
    auto lattice = sffd::ffd::load_lattice(json);
    ASSERT_TRUE(lattice) << lattice.message();
    sffd::ffd::twist_graded(*lattice, sffd::ffd::all_control_points(*lattice), glm::dvec3(0, 1, 0), 1.5);
    ASSERT_TRUE(sffd::ffd::save_lattice(twisted_json, *lattice));
    const fs::path twisted = dir / "twisted.glb";
    const CliRun t =
        tool("convert " + g.string() + " " + twisted.string() + " --lattice " + twisted_json.string());
    ASSERT_EQ(t.code, 0) << t.out;
    const fs::path twisted_frame = render_exr(twisted.string(), dir / "r_twisted");
    const double changed = psnr(plain, twisted_frame);
    EXPECT_TRUE(std::isfinite(changed)) << "the twist left the image unchanged";
    EXPECT_LT(changed, 30.0);

    const fs::path deformed = dir / "deformed.ply";
    const CliRun d = tool("deform " + twisted.string() + " " + deformed.string());
    ASSERT_EQ(d.code, 0) << d.out;
    const CliRun dinfo = tool("info " + deformed.string());
    EXPECT_TRUE(has(dinfo.out, "4000 Gaussians")) << dinfo.out;
    EXPECT_GT(psnr(twisted_frame, render_exr(deformed.string(), dir / "r_deformed")), 25.0);
}

TEST(GaussianScene, OutputsThatCannotHoldALatticeAreRefused) {
    const fs::path dir = temp_dir("refuse");
    const fs::path g = gaussian_sphere(dir);
    for (const char* name : {"out.ply", "out.spz"}) {
        const CliRun r = tool("convert " + g.string() + " " + (dir / name).string() + " --lattice fit");
        EXPECT_EQ(r.code, 2) << r.out;
        EXPECT_TRUE(has(r.out, "cannot hold a lattice; write a scene (.glb/.gltf)")) << r.out;
        EXPECT_FALSE(fs::exists(dir / name));
    }
}

TEST(NothingHappens, DeformWarnsWhenALatticeHoldsNoneOfThePoints) {
    const fs::path dir = temp_dir("empty_lattice");
    const fs::path surface = dir / "s.ply", far = dir / "far.json", near = dir / "near.json";
    ASSERT_EQ(tool("convert sphere " + surface.string() + " --splats 3000").code, 0);
    const fs::path g = gaussian_sphere(dir);
    const std::vector<glm::vec3> box{{0, 0, 0}, {3, 3, 3}};  // the sphere (radius 1) fits in it
    auto far_lattice = sffd::ffd::fit_lattice(box, glm::dvec3(100.0), glm::ivec3(2));
    auto near_lattice = sffd::ffd::fit_lattice(box, glm::dvec3(-1.5), glm::ivec3(2));
    ASSERT_TRUE(far_lattice && near_lattice);
    ASSERT_TRUE(sffd::ffd::save_lattice(far, *far_lattice));
    ASSERT_TRUE(sffd::ffd::save_lattice(near, *near_lattice));
    for (const fs::path& in : {surface, g}) {
        const CliRun r =
            tool("deform " + in.string() + " " + (dir / "o.ply").string() + " --lattice " + far.string());
        EXPECT_EQ(r.code, 0) << r.out;
        EXPECT_TRUE(has(r.out, "warning: lattice '")) << r.out;
        EXPECT_TRUE(has(r.out, "' contains none of the")) << r.out;
        const CliRun ok =
            tool("deform " + in.string() + " " + (dir / "o.ply").string() + " --lattice " + near.string());
        EXPECT_EQ(ok.code, 0) << ok.out;
        EXPECT_FALSE(has(ok.out, "contains none")) << ok.out;
    }
    // A scene's own lattice (in memory, named after the lattice), moved away from its cloud.
    const CliRun moved =
        tool("convert " + surface.string() + " " + (dir / "s.glb").string() + " --lattice " + far.string());
    ASSERT_EQ(moved.code, 0) << moved.out;
    const CliRun r = tool("deform " + (dir / "s.glb").string() + " " + (dir / "o.glb").string());
    EXPECT_EQ(r.code, 0) << r.out;
    EXPECT_TRUE(has(r.out, "warning: lattice 's.lattice' contains none of the 3000 points")) << r.out;
}

TEST(NothingHappens, AnObbFitThatFallsBackToABoxSaysSo) {
    const fs::path dir = temp_dir("obb");
    // The sphere has no principal axes: the oriented fit is the axis-aligned box, said once.
    const CliRun sphere = tool("convert sphere " + (dir / "s.glb").string() + " --lattice fit:4,4,4,obb");
    ASSERT_EQ(sphere.code, 0) << sphere.out;
    EXPECT_TRUE(has(sphere.out, "warning: obb:")) << sphere.out;
    EXPECT_TRUE(has(sphere.out, "so the lattice is axis-aligned")) << sphere.out;
    // A long, thin, tilted cloud gets its oriented box, without a warning.
    const fs::path rod = dir / "rod.ply";
    {
        std::ofstream f(rod);
        f << "ply\nformat ascii 1.0\nelement vertex 400\nproperty float x\nproperty float y\nproperty float "
             "z\nend_header\n";
        for (int i = 0; i < 400; ++i) {
            const double t = i / 399.0, w = 0.05 * std::sin(i * 1.7), h = 0.03 * std::cos(i * 2.3);
            f << t + w << " " << t - w << " " << h << "\n";
        }
    }
    const CliRun tilted =
        tool("convert " + rod.string() + " " + (dir / "rod.glb").string() + " --lattice fit:4,4,4,obb");
    ASSERT_EQ(tilted.code, 0) << tilted.out;
    EXPECT_FALSE(has(tilted.out, "warning: obb:")) << tilted.out;
}

TEST(NothingHappens, ViewHeadlessNeedsAnEndAndHasNoWindowToCapture) {
    const fs::path dir = temp_dir("view");
    const CliRun forever = tool("view sphere --headless");
    EXPECT_EQ(forever.code, 2) << forever.out;
    EXPECT_TRUE(has(forever.out, "--headless needs --frames N or --replay FILE")) << forever.out;
    const fs::path shot = dir / "window.png";
    const CliRun capture = tool("view sphere --headless --frames 1 --window-screenshot " + shot.string());
    EXPECT_EQ(capture.code, 2) << capture.out;
    EXPECT_TRUE(has(capture.out, "--window-screenshot captures the window, and --headless has none"))
        << capture.out;
    EXPECT_FALSE(fs::exists(shot));
}

// A clip keyed in the editor on a Gaussian file (add a lattice, auto-key, a stretch at 0 s and 1 s), saved
// with ctrl+s, animates when rendered: frame 0 and frame 12 (0.5 s at 24 fps, half way) differ. (Frame 24
// is 1 s, where the 1 s clip loops back to frame 0's pose.)
TEST(GaussianClip, KeyedInTheEditorAndSavedItPlaysWhenRendered) {
    const fs::path dir = temp_dir("clip");
    const fs::path g = gaussian_sphere(dir);
    const fs::path replay = dir / "clip.txt", saved = dir / "saved.glb";
    {
        std::ofstream f(replay);
        f << "1 key a shift\n3 key a\n5 key n\n7 key g\n9 text 0.02 0 0\n";
        for (int i = 0; i < 24; ++i) f << 11 + i << " key right\n";
        f << "40 key g\n42 text 0 0.4 0\n44 key s ctrl\n";
    }
    const CliRun v =
        tool("view " + g.string() + " --headless --size 160x120 --quality preview --frames 48 --replay " +
             replay.string() + " --save " + saved.string());
    ASSERT_EQ(v.code, 0) << v.out;
    ASSERT_TRUE(fs::exists(saved)) << v.out;
    const CliRun info = tool("info " + saved.string());
    EXPECT_TRUE(has(info.out, "Gaussians")) << info.out;
    const CliRun r = tool("render " + saved.string() + " --out " + (dir / "frames").string() +
                          " --frames 0:12 --size 160x120 --quality preview --format exr" + kCamera);
    ASSERT_EQ(r.code, 0) << r.out;
    const double p = psnr(dir / "frames" / "frame_0000.exr", dir / "frames" / "frame_0012.exr");
    EXPECT_TRUE(std::isfinite(p)) << "frame 12 is frame 0: the saved clip does not play (" << v.out << ")";
}
