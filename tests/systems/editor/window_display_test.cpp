// Under xvfb-run, what the editor's window shows is the rendered frame (overlay included) over the view's
// background, sRGB-encoded: the display pass writes it straight into the window's back buffer. The window
// screenshot's pixels in the middle of the view (where no panel is) are compared with the same frame's
// linear capture (EXR), encoded on the CPU.
#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "systems/splat_render/image_io.h"
#include "tests/assets/test_util.h"
#include "tests/test_util/run_tool.h"

using namespace sffd;
namespace fs = std::filesystem;

namespace {

// `splatffd view sphere ARGS` under xvfb-run at 1280x720, its last frame both as the window shows it
// (--window-screenshot, PNG) and as captured (--out, linear EXR).
class WindowDisplay : public testing::Test {
protected:
    void SetUp() override {
        if (test::run_shell("command -v xvfb-run > /dev/null") != 0) GTEST_SKIP() << "xvfb-run not installed";
        dir = fs::temp_directory_path() / ("sffd_window_display_" + std::to_string(::getpid()) + "_" +
                                           testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::create_directories(dir);
    }
    void TearDown() override {
        if (!dir.empty()) fs::remove_all(dir);
    }
    // False (with a failure) when the run or a file failed.
    bool view(const std::string& args) {
        const fs::path window = dir / "window.png", frame = dir / "frame.exr", log = dir / "view.log";
        const int code = test::run_shell(
            "XDG_CONFIG_HOME=" + dir.string() + " xvfb-run -a -s '-screen 0 1280x720x24' " +
            std::string(SFFD_BINARY_DIR) + "/tools/splatffd view sphere " + args + " --out " +
            frame.string() + " --window-screenshot " + window.string() + " > " + log.string() + " 2>&1");
        EXPECT_EQ(code, 0) << test::slurp(log);
        auto png = render::read_png(window);
        auto exr = render::read_exr(frame);
        EXPECT_TRUE(png.ok()) << png.message();
        EXPECT_TRUE(exr.ok()) << exr.message();
        if (code != 0 || !png || !exr) return false;
        shown = std::move(*png), linear = std::move(*exr);
        EXPECT_EQ(shown.width, linear.width);
        EXPECT_EQ(shown.height, linear.height);
        return shown.width == linear.width && shown.height == linear.height;
    }
    // The view's background (view_app.cpp) where nothing was drawn; the capture keeps alpha 0 there.
    static glm::vec3 background() { return {0.045f, 0.05f, 0.06f}; }
    // fn(capture's colour, the capture encoded over the background (8-bit sRGB), the window's pixel) for
    // each pixel in the middle of the view: between the panel columns, below the menu and above the
    // Timeline of the 1280x720 layout.
    template <class Fn>
    void for_each_view_pixel(Fn&& fn) const {
        for (int y = 40; y < 600; ++y)
            for (int x = 280; x < 940; ++x) {
                const glm::vec4 c = linear.color[linear.index(x, y)];
                const glm::vec3 want = glm::mix(background(), glm::vec3(c), glm::clamp(c.w, 0.0f, 1.0f));
                const std::uint8_t* p =
                    &shown.pixels[(std::size_t(y) * std::size_t(shown.width) + std::size_t(x)) * 4];
                fn(c,
                   glm::ivec3(render::encode_srgb8(want.x), render::encode_srgb8(want.y),
                              render::encode_srgb8(want.z)),
                   glm::ivec3(p[0], p[1], p[2]));
            }
    }
    fs::path dir;
    render::Rgba8Image shown;
    render::FrameImage linear;
};

}  // namespace

TEST_F(WindowDisplay, TheWindowShowsTheFrameEncodedOverTheBackground) {
    ASSERT_TRUE(view("--size 1280x720 --quality preview --frames 3"));
    int compared = 0, covered = 0, off = 0, worst = 0;
    for_each_view_pixel([&](glm::vec4 c, glm::ivec3 want, glm::ivec3 got) {
        const glm::ivec3 e = glm::abs(got - want);
        const int d = std::max({e.x, e.y, e.z});
        ++compared, covered += c.w > 0.0f, off += d > 1, worst = std::max(worst, d);
    });
    EXPECT_GT(covered, compared / 10) << "the sphere is not in the middle of the window";
    // One level of rounding between the GPU's and the CPU's encoding; nothing more anywhere.
    EXPECT_EQ(off, 0) << "worst difference " << worst << " levels";
}

// While a drag previews at half resolution with x-ray on, the lattice reaches past the sphere: the display
// copies only the frame's drawn pixels (render::drawn_pixels(), which the overlay widens with its own), so
// an overlay that did not report its pixels would leave background where the capture shows edges. Mid-twist
// (frame 40 of the sphere session): no pixel the capture covers may show the plain background in the
// window, and all but the gizmo's (ImGui draws it over the view) match the capture encoded.
TEST_F(WindowDisplay, WhileDraggingTheWindowShowsTheLatticeBeyondTheSurface) {
    ASSERT_TRUE(view("--replay " + (fs::path(SFFD_TEST_DATA_DIR) / "editor/session.txt").string() +
                     " --frames 40 --save " + (dir / "saved.glb").string()));
    const glm::ivec3 bg8(render::encode_srgb8(background().x), render::encode_srgb8(background().y),
                         render::encode_srgb8(background().z));
    int compared = 0, covered = 0, lost = 0, off = 0;
    for_each_view_pixel([&](glm::vec4 c, glm::ivec3 want, glm::ivec3 got) {
        const glm::ivec3 d = glm::abs(got - want), from_bg = glm::abs(got - bg8),
                         want_bg = glm::abs(want - bg8);
        ++compared, covered += c.w > 0.0f;
        lost += c.w > 0.0f && std::max({want_bg.x, want_bg.y, want_bg.z}) > 2 &&
                        std::max({from_bg.x, from_bg.y, from_bg.z}) <= 1
                    ? 1
                    : 0;
        off += std::max({d.x, d.y, d.z}) > 1;
    });
    EXPECT_GT(covered, compared / 5) << "the sphere and its lattice are not in the view";
    EXPECT_EQ(lost, 0) << "drawn pixels the window shows as background";
    EXPECT_LT(off, compared / 100) << "more differences than the gizmo's";
}
