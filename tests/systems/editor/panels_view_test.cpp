// Under xvfb-run, `splatffd view` with its panels at 1280x720 and 1920x1080: the rectangles ImGui drew
// in the last frame (--panel-rects-json) neither overlap nor leave the window, the six panels, the menu
// and the status bar are all there, and the window screenshot shows panel pixels in each panel's rect.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/assets/test_util.h"
#include "tests/test_util/run_tool.h"
#include "systems/editor/panel_layout.h"
#include "systems/splat_render/image_io.h"

using namespace sffd;
namespace fs = std::filesystem;

namespace {

using sffd::test::run_shell;
using sffd::test::slurp;

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

}  // namespace

TEST(PanelsView, PanelsFitTheWindowWithoutOverlap) {
    if (run_shell("command -v xvfb-run > /dev/null") != 0) GTEST_SKIP() << "xvfb-run not installed";
    const fs::path dir = fs::temp_directory_path() / ("sffd_panels_view_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    for (const auto& [w, h] : {std::pair{1280, 720}, {1920, 1080}}) {
        const std::string size = std::to_string(w) + "x" + std::to_string(h);
        const fs::path json = dir / (size + ".json"), png = dir / (size + ".png"),
                       log = dir / (size + ".log");
        // xvfb's screen must hold the window; XDG_CONFIG_HOME keeps the test away from the user's layout.
        ASSERT_EQ(run_shell("XDG_CONFIG_HOME=" + dir.string() + " xvfb-run -a -s '-screen 0 2048x1200x24' " +
                            std::string(SFFD_BINARY_DIR) + "/tools/splatffd view sphere --size " + size +
                            " --quality preview --frames 4 --panel-rects-json " + json.string() +
                            " --window-screenshot " + png.string() + " > " + log.string() + " 2>&1"),
                  0)
            << slurp(log);
        const std::vector<Rect> rects = parse_rects(slurp(json));
        ASSERT_EQ(rects.size(), 8u) << slurp(json);
        for (std::size_t i = 0; i < rects.size(); ++i) {
            const editor::PanelRect& r = rects[i].r;
            EXPECT_GE(r.x, 0.0f) << rects[i].name << " " << size;
            EXPECT_GE(r.y, 0.0f) << rects[i].name << " " << size;
            EXPECT_LE(r.x + r.w, float(w)) << rects[i].name << " " << size;
            EXPECT_LE(r.y + r.h, float(h)) << rects[i].name << " " << size;
            for (std::size_t j = i + 1; j < rects.size(); ++j)
                EXPECT_FALSE(editor::overlaps(r, rects[j].r))
                    << rects[i].name << " overlaps " << rects[j].name << " at " << size;
        }
        // The screenshot is the window at that size, and each panel is drawn where it says: the middle of
        // its title bar has ImGui's title colour (dark theme: TitleBg 0.04 grey, or TitleBgActive
        // 0.16/0.29/0.48 for the focused panel), not the scene behind it.
        auto img = render::read_png(png);
        ASSERT_TRUE(img) << img.message();
        ASSERT_EQ(img->width, w);
        ASSERT_EQ(img->height, h);
        const auto near = [](const std::uint8_t* p, int r, int g, int b) {
            return std::abs(p[0] - r) <= 6 && std::abs(p[1] - g) <= 6 && std::abs(p[2] - b) <= 6;
        };
        for (const Rect& r : rects) {
            if (r.name.rfind("##", 0) == 0) continue;
            const int x = int(r.r.x + r.r.w * 0.75f), y = int(r.r.y + 6);
            const std::uint8_t* p = &img->pixels[(std::size_t(y) * std::size_t(w) + std::size_t(x)) * 4];
            EXPECT_TRUE(near(p, 10, 10, 10) || near(p, 41, 74, 122))
                << r.name << " title bar not at " << x << "," << y << " (" << size << "): " << int(p[0])
                << " " << int(p[1]) << " " << int(p[2]);
            // Inside the border, left of the content (ImGui's 8-unit padding): the opaque panel colour
            // (WindowBg 0.06 grey, 15 of 255), whatever the window shows behind the panel.
            const int bx = int(r.r.x) + 3, by = int(r.r.y + r.r.h * 0.6f);
            const std::uint8_t* q = &img->pixels[(std::size_t(by) * std::size_t(w) + std::size_t(bx)) * 4];
            EXPECT_TRUE(q[0] == 15 && q[1] == 15 && q[2] == 15)
                << r.name << " background at " << bx << "," << by << " (" << size << "): " << int(q[0]) << " "
                << int(q[1]) << " " << int(q[2]);
        }
    }
    fs::remove_all(dir);
}
