// The panel cache (systems/editor/ui_cache.h) changes no pixel a user could see: under xvfb-run the sphere
// session stops in the middle of its twist drag (after the tool and its panel changed from move to twist)
// and the window screenshot with the cache and with `--no-ui-cache` must match everywhere but the
// frame-time panel, whose numbers are this run's own timings. The log's counts show panels were drawn
// into the cache, copied from it, and drawn directly when they changed.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <regex>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "systems/editor/panel_layout.h"
#include "systems/splat_render/image_io.h"
#include "tests/assets/test_util.h"
#include "tests/test_util/run_tool.h"

using namespace sffd;
namespace fs = std::filesystem;

namespace {

using sffd::test::run_shell;
using sffd::test::slurp;

struct CacheCounts {
    long frames = -1, copied = -1, cached = -1, drawn = -1, direct = -1;
};

CacheCounts parse_counts(const std::string& log) {
    static const std::regex re(
        R"(panels through the cache in (\d+) frames \((\d+) copied as they were, (\d+) )"
        R"(drawn into it, (\d+) drawn directly\), every panel drawn directly in (\d+))");
    std::smatch m;
    CacheCounts c;
    if (std::regex_search(log, m, re))
        c = {std::stol(m[1]), std::stol(m[2]), std::stol(m[3]), std::stol(m[4]), std::stol(m[5])};
    return c;
}

// The "Frame time" panel's rectangle from --panel-rects-json.
editor::PanelRect frame_time_rect(const std::string& json) {
    std::istringstream in(json);
    for (std::string line; std::getline(in, line);) {
        editor::PanelRect r;
        if (std::sscanf(line.c_str(),
                        " {\"name\": \"Frame time\", \"x\": %f, \"y\": %f, \"w\": %f, \"h\": %f}", &r.x, &r.y,
                        &r.w, &r.h) == 4)
            return r;
    }
    return {};
}

}  // namespace

TEST(UiCache, CachedPanelsLookAsDrawnDirectly) {
    if (run_shell("command -v xvfb-run > /dev/null") != 0) GTEST_SKIP() << "xvfb-run not installed";
    const fs::path dir = fs::temp_directory_path() / ("sffd_ui_cache_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    render::Rgba8Image shots[2];
    std::string logs[2];
    editor::PanelRect frame_time;
    for (int cache = 0; cache < 2; ++cache) {
        const std::string name = cache ? "cached" : "direct";
        const fs::path png = dir / (name + ".png"), log = dir / (name + ".log"),
                       json = dir / (name + ".json");
        // XDG_CONFIG_HOME keeps the test away from the user's layout.
        ASSERT_EQ(run_shell("XDG_CONFIG_HOME=" + dir.string() + " xvfb-run -a -s '-screen 0 1280x1024x24' " +
                            std::string(SFFD_BINARY_DIR) + "/tools/splatffd view sphere --replay " +
                            (fs::path(SFFD_TEST_DATA_DIR) / "editor/session.txt").string() +
                            " --frames 40 --save " + (dir / "saved.glb").string() + " --panel-rects-json " +
                            json.string() + " --window-screenshot " + png.string() +
                            (cache ? "" : " --no-ui-cache") + " > " + log.string() + " 2>&1"),
                  0)
            << slurp(log);
        logs[cache] = slurp(log);
        auto img = render::read_png(png);
        ASSERT_TRUE(img) << img.message();
        shots[cache] = std::move(*img);
        if (cache) frame_time = frame_time_rect(slurp(json));
    }
    ASSERT_GT(frame_time.w, 0.0f) << "no Frame time panel in the panel rectangles";

    const CacheCounts direct = parse_counts(logs[0]), cached = parse_counts(logs[1]);
    EXPECT_EQ(direct.frames, 0) << logs[0];
    EXPECT_EQ(direct.direct, 40) << logs[0];
    EXPECT_EQ(cached.direct, 0) << logs[1];
    EXPECT_EQ(cached.frames, 40) << logs[1];
    EXPECT_GT(cached.copied, 100) << logs[1];  // six panels over 40 frames, most of them unchanged
    EXPECT_GT(cached.cached, 0) << logs[1];
    EXPECT_GT(cached.drawn, 0) << logs[1];  // at least the tools panel when the tool changed

    const render::Rgba8Image &a = shots[0], &b = shots[1];
    ASSERT_EQ(a.width, 1280);
    ASSERT_EQ(a.height, 720);
    ASSERT_EQ(b.width, a.width);
    ASSERT_EQ(b.height, a.height);
    int worst = 0;
    long differ = 0;
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x) {
            if (float(x) >= frame_time.x && float(x) < frame_time.x + frame_time.w &&
                float(y) >= frame_time.y && float(y) < frame_time.y + frame_time.h)
                continue;
            const std::size_t i = (std::size_t(y) * std::size_t(a.width) + std::size_t(x)) * 4;
            int d = 0;
            for (int c = 0; c < 3; ++c)
                d = std::max(d, std::abs(int(a.pixels[i + c]) - int(b.pixels[i + c])));
            worst = std::max(worst, d);
            differ += d > 0 ? 1 : 0;
        }
    // The texture is RGBA8 and the window's format may blend an anti-aliased edge a step apart.
    EXPECT_LE(worst, 2);
    EXPECT_LT(differ, 100);
    fs::remove_all(dir);
}
