// The lattice overlay's cache of unchanged edges (lattice_overlay.cpp, OverlayLineCache) changes no pixel
// beyond half-float rounding: the headless editor replays the sphere session (x-ray on, a box selection
// stretched and twisted) and stops in the middle of the twist, or, without x-ray, a few still frames after
// the drags (the faint hidden edges are the cached draw there); the last frame with the cache and with
// `--no-overlay-cache` must match. The log's counts show the cache was drawn, reused, and drawn over by
// the moving edges.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <unistd.h>

#include "systems/splat_render/image_io.h"
#include "tests/test_util/gl_required.h"
#include "tests/test_util/run_tool.h"

namespace fs = std::filesystem;

namespace sffd {
namespace {

struct CacheCounts {
    long frames = 0, rebuilt = 0, direct = 0, cached = 0, live = 0;
};

CacheCounts parse_counts(const std::string& log) {
    static const std::regex re(
        R"(lattice edges cached in (\d+) frames \((\d+) drew the cache again\), drawn )"
        R"(directly in (\d+); (\d+) cached and (\d+) live edges)");
    std::smatch m;
    CacheCounts c;
    if (std::regex_search(log, m, re))
        c = {std::stol(m[1]), std::stol(m[2]), std::stol(m[3]), std::stol(m[4]), std::stol(m[5])};
    return c;
}

class OverlayCache : public testing::Test {
protected:
    void SetUp() override {
        dir = fs::temp_directory_path() / ("sffd_overlay_cache_" + std::to_string(::getpid()));
        fs::create_directories(dir);
    }
    void TearDown() override { fs::remove_all(dir); }

    // The last frame of `session` (a file) after `frames` frames, with or without the cache; empty (width
    // 0) when the run failed, with `no_gl` set when it found no GL.
    render::FrameImage last_frame(const fs::path& session, int frames, bool cache, std::string& log) {
        const fs::path out = dir / (std::string(cache ? "cached" : "direct") + ".exr");
        const test::CliRun r =
            test::run_headless("view sphere --headless --replay " + session.string() + " --frames " +
                               std::to_string(frames) + " --save " + (dir / "saved.glb").string() +
                               " --out " + out.string() + (cache ? "" : " --no-overlay-cache"));
        log = r.out;
        if (r.code != 0) {
            no_gl = r.out.find("EGL") != std::string::npos;
            if (!no_gl) ADD_FAILURE() << r.out;
            return {};
        }
        auto img = render::read_exr(out);
        EXPECT_TRUE(img.ok()) << img.message();
        return img ? *img : render::FrameImage{};
    }

    void expect_same(const render::FrameImage& a, const render::FrameImage& b) {
        ASSERT_EQ(a.width, b.width);
        ASSERT_EQ(a.height, b.height);
        ASSERT_GT(a.width, 0);
        float worst = 0.0f;
        long off = 0, overlay = 0;
        for (std::size_t i = 0; i < a.color.size(); ++i) {
            const glm::vec4 d = glm::abs(a.color[i] - b.color[i]);
            const float m = std::max(std::max(d.x, d.y), std::max(d.z, d.w));
            worst = std::max(worst, m);
            off += m > 4e-3f ? 1 : 0;
            // Lattice-coloured pixels (the edges are light blue: blue well above red).
            overlay += a.color[i].z > a.color[i].x + 0.2f ? 1 : 0;
        }
        EXPECT_GT(overlay, 2000) << "the frame shows no lattice";
        // Half-float rounding of one blend order against another, nothing more.
        EXPECT_EQ(off, 0) << "worst difference " << worst;
    }

    // Both runs of `session`, their last frames compared; the cached run's log (empty when a run failed).
    std::string compare_runs(const fs::path& session, int frames) {
        std::string log_cached, log_direct;
        const render::FrameImage cached = last_frame(session, frames, true, log_cached);
        if (no_gl || HasFailure()) return log_cached;
        const render::FrameImage direct = last_frame(session, frames, false, log_direct);
        if (HasFailure()) return {};
        expect_same(cached, direct);
        EXPECT_EQ(parse_counts(log_direct).frames, 0) << log_direct;
        return log_cached;
    }

    fs::path dir;
    bool no_gl = false;
};

TEST_F(OverlayCache, XrayEdgesInTheMiddleOfADragMatchTheEdgesDrawnDirectly) {
    const fs::path session = fs::path(SFFD_TEST_DATA_DIR) / "editor/session.txt";
    const std::string log_cached = compare_runs(session, 40);
    if (no_gl) SFFD_GL_UNAVAILABLE(log_cached);
    if (HasFailure()) return;
    const CacheCounts c = parse_counts(log_cached);
    EXPECT_GT(c.frames, 20) << log_cached;
    EXPECT_GE(c.rebuilt, 2) << "a drag draws the cache again once its edges move" << log_cached;
    EXPECT_GT(c.frames - c.rebuilt, 10) << "frames reusing the cache" << log_cached;
    EXPECT_GT(c.live, 0) << "no edge was drawn over the cache" << log_cached;
    EXPECT_GT(c.cached, 10 * c.live) << log_cached;
}

TEST_F(OverlayCache, FaintHiddenEdgesOfStillFramesMatchTheEdgesDrawnDirectly) {
    // The same gestures without x-ray: hidden edges drawn faintly under the visible ones when still.
    std::ifstream in(fs::path(SFFD_TEST_DATA_DIR) / "editor/session.txt");
    std::ostringstream without_xray;
    for (std::string line; std::getline(in, line);)
        if (line.rfind("2 key t", 0) != 0) without_xray << line << "\n";
    const fs::path session = dir / "no_xray.txt";
    std::ofstream(session) << without_xray.str();
    const std::string log_cached = compare_runs(session, 60);
    if (no_gl) SFFD_GL_UNAVAILABLE(log_cached);
    if (HasFailure()) return;
    const CacheCounts c = parse_counts(log_cached);
    EXPECT_GE(c.frames - c.rebuilt, 3) << "frames reusing the cache" << log_cached;
    EXPECT_GT(c.cached, 0) << log_cached;
}

}  // namespace
}  // namespace sffd
