// Under xvfb-run, `splatffd view` on a 3D Gaussian file: shift+a adds a lattice with control points
// inside the Gaussians' box (the status line the Lattice panel's count comes from; it said 0), ctrl+e
// exports each lattice under its own name, and at 800x600 the panels leave the model uncovered: no pixel
// of the rendered model (--out, not black) lies under a drawn panel (--panel-rects-json).
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/assets/test_util.h"
#include "tests/test_util/run_tool.h"
#include "systems/editor/panel_layout.h"
#include "systems/ffd/lattice_io.h"
#include "systems/splat_render/image_io.h"

using namespace sffd;
namespace fs = std::filesystem;

namespace {

using sffd::test::run_shell;
using sffd::test::slurp;

std::string splatffd() { return std::string(SFFD_BINARY_DIR) + "/tools/splatffd"; }

struct Rect {
    std::string name;
    editor::PanelRect r;
};

std::vector<Rect> parse_rects(const std::string& json) {
    std::vector<Rect> out;
    std::istringstream in(json);
    for (std::string line; std::getline(in, line);) {
        char name[64] = {};
        Rect r;
        if (std::sscanf(line.c_str(), " {\"name\": \"%63[^\"]\", \"x\": %f, \"y\": %f, \"w\": %f, \"h\": %f}",
                        name, &r.r.x, &r.r.y, &r.r.w, &r.r.h) == 5) {
            r.name = name;
            out.push_back(r);
        }
    }
    return out;
}

struct Fixture {
    fs::path dir, gaussians;
    Fixture(const std::string& name) {
        dir = fs::temp_directory_path() / ("sffd_gaussian_view_" + name + "_" + std::to_string(::getpid()));
        fs::remove_all(dir);
        fs::create_directories(dir);
        gaussians = dir / "g.ply";
        EXPECT_EQ(run_shell(splatffd() + " convert sphere " + gaussians.string() +
                            " --gaussians --splats 4000 > /dev/null 2>&1"),
                  0);
    }
    // `view g.ply` in a window under xvfb (its own config folder: no remembered layout).
    int view(const std::string& args, const fs::path& log) const {
        return run_shell("XDG_CONFIG_HOME=" + dir.string() + " xvfb-run -a -s '-screen 0 1400x1000x24' " +
                         splatffd() + " view " + gaussians.string() + " " + args + " > " + log.string() +
                         " 2>&1");
    }
};

}  // namespace

TEST(GaussianView, AddLatticeCountsControlPointsInsideAndExportsEachUnderItsName) {
    if (run_shell("command -v xvfb-run > /dev/null") != 0) GTEST_SKIP() << "xvfb-run not installed";
    Fixture f("add");
    const fs::path replay = f.dir / "add.txt", log = f.dir / "add.log";
    std::ofstream(replay) << "1 key a shift\n3 key e ctrl\n5 key a shift\n7 key e ctrl\n";
    ASSERT_EQ(f.view("--size 1280x720 --quality preview --frames 10 --replay " + replay.string(), log), 0)
        << slurp(log);
    const std::string out = slurp(log);
    std::smatch m;
    ASSERT_TRUE(std::regex_search(out, m, std::regex("'g.lattice' on 'g', ([0-9]+) control points inside")))
        << out;
    EXPECT_GT(std::stoul(m[1]), 0u) << out;
    EXPECT_LT(std::stoul(m[1]), 1331u) << out;  // 11^3: the padded outer layer is outside the box
    // Two lattices, two files, each named after its lattice, beside the save (g.glb in the same folder).
    EXPECT_TRUE(fs::exists(f.dir / "g.lattice.json")) << out;
    EXPECT_TRUE(fs::exists(f.dir / "g.lattice2.json")) << out;
    EXPECT_TRUE(ffd::load_lattice(f.dir / "g.lattice2.json")) << out;
    fs::remove_all(f.dir);
}

TEST(GaussianView, At800x600ThePanelsDoNotCoverTheModel) {
    if (run_shell("command -v xvfb-run > /dev/null") != 0) GTEST_SKIP() << "xvfb-run not installed";
    Fixture f("small");
    const fs::path json = f.dir / "rects.json", png = f.dir / "frame.png", log = f.dir / "small.log";
    ASSERT_EQ(f.view("--size 800x600 --quality preview --frames 4 --out " + png.string() +
                         " --panel-rects-json " + json.string(),
                     log),
              0)
        << slurp(log);
    const std::vector<Rect> rects = parse_rects(slurp(json));
    ASSERT_GE(rects.size(), 6u) << slurp(json);
    auto img = render::read_png(png);
    ASSERT_TRUE(img) << img.message();
    ASSERT_EQ(img->width, 800);
    ASSERT_EQ(img->height, 600);
    std::size_t model = 0, covered = 0;
    std::string first;
    for (int y = 0; y < img->height; ++y)
        for (int x = 0; x < img->width; ++x) {
            // --out is the render over black (opaque): the model is every pixel that is not black.
            const std::uint8_t* p = &img->pixels[(std::size_t(y) * 800 + std::size_t(x)) * 4];
            if (std::max({p[0], p[1], p[2]}) <= 8) continue;
            ++model;
            for (const Rect& r : rects)
                if (float(x) + 0.5f > r.r.x && float(x) + 0.5f < r.r.x + r.r.w && float(y) + 0.5f > r.r.y &&
                    float(y) + 0.5f < r.r.y + r.r.h) {
                    if (covered++ == 0) first = r.name + " at " + std::to_string(x) + "," + std::to_string(y);
                    break;
                }
        }
    EXPECT_GT(model, 5000u) << "the model is not in the frame";
    EXPECT_EQ(covered, 0u) << covered << " of " << model << " model pixels under a panel, first: " << first;
    fs::remove_all(f.dir);
}
