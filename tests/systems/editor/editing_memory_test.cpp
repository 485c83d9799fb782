// A long editing session stays flat. The headless editor (run_view, what `splatffd view --headless`
// runs) replays, every 20 frames: a drag of every control point of the lattice, three material slider
// edits (`set material.<field>` lines, the inspector's code path), and undo/redo of both; on the face scan
// (the built-in sphere, with a note, when the content cache has no face). The resident set is sampled
// after every frame. Passes when its peak after frame 500 stays within 50 MB of its size at frame 500.
//
// SFFD_EDITING_MEMORY_FRAMES sets the length (default 2,000; the long check is 10,000):
//   SFFD_EDITING_MEMORY_FRAMES=10000 build/release/tests/systems/editor/editor_editing_memory_tests
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>
#include <vector>

#include "runtime/assets/builtin_scenes.h"
#include "systems/editor/view_app.h"
#include "systems/engine/engine.h"
#include "systems/engine/engine_frame.h"

namespace fs = std::filesystem;

namespace sffd::editor {
namespace {

constexpr std::uint64_t settle_frames = 500;
constexpr double limit_mb = 50.0;

double resident_mb() {
    std::ifstream statm("/proc/self/statm");
    long pages = 0, resident = 0;
    statm >> pages >> resident;
    return double(resident) * double(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

// The session, one 20-frame cycle after another (the lattice and the material end each cycle as they
// began, so the scene does not drift; the undo stack fills to its limit and stays there).
std::string session(std::uint64_t frames) {
    std::string s = "3 key a ctrl\n5 key g\n";  // select every control point, move tool
    for (std::uint64_t f = 10, cycle = 0; f + 20 <= frames; f += 20, ++cycle) {
        auto line = [&](std::uint64_t at, const std::string& what) {
            s += std::to_string(f + at) + " " + what + "\n";
        };
        line(0, "move 80 60");
        line(1, "press left");
        for (int k = 1; k <= 6; ++k)
            line(1 + k, "move " + std::to_string(80 + 2 * k) + " " + std::to_string(60 - k));
        line(8, "release left");
        // Values off the 0.1 grid: a value equal to the current one is no edit (and no undo step), and the
        // undos below must each undo one of this cycle's steps.
        line(9, "set material.specular " + std::to_string(0.05 + 0.1 * double(cycle % 9)));
        line(10, "set material.shininess " + std::to_string(5 + 8 * (cycle % 16)));
        line(11, "set material.base_color.r " + std::to_string(0.05 + 0.1 * double(cycle % 9)));
        line(12, "key z ctrl");
        line(13, "key y ctrl");
        for (int k = 14; k <= 17; ++k) line(std::uint64_t(k), "key z ctrl");  // three materials, the drag
        line(18, "key y ctrl");
        line(19, "key z ctrl");
    }
    return s;
}

TEST(EditingMemory, ALongSessionOfDragsSliderEditsAndUndoStaysFlat) {
    std::uint64_t frames = 2000;
    if (const char* v = std::getenv("SFFD_EDITING_MEMORY_FRAMES")) frames = std::strtoull(v, nullptr, 10);
    ASSERT_GT(frames, settle_frames + 20) << "SFFD_EDITING_MEMORY_FRAMES must exceed " << settle_frames + 20;
    std::error_code ec;
    const bool face = fs::exists(assets::face_cache_path(), ec);
    if (!face)
        std::printf("note: %s is missing, the session runs on the sphere\n",
                    assets::face_cache_path().string().c_str());
    const fs::path dir = fs::temp_directory_path() / ("sffd_editing_memory_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const fs::path replay = dir / "session.txt";
    std::ofstream(replay) << session(frames);

    std::vector<double> rss;
    rss.reserve(frames);
    Schedule schedule = make_engine_schedule({.present = true, .editor = true});
    schedule.add(Phase::present, "test.resident",
                 [&](ecs::Registry&, const FrameContext&) { rss.push_back(resident_mb()); });
    ViewOptions options;
    options.scene_hooks = engine_scene_hooks();
    options.scene = face ? "face" : "sphere";
    options.replay = replay.string();
    options.frames = frames;
    options.width = 160, options.height = 120;
    options.headless = true;
    options.preview = true;
    ASSERT_EQ(run_view(options, std::move(schedule)), 0);
    fs::remove_all(dir, ec);

    ASSERT_GE(rss.size(), frames - 1);
    const double settled = rss[settle_frames - 1];
    const double peak = *std::max_element(rss.begin() + std::ptrdiff_t(settle_frames), rss.end());
    std::printf(
        "%s, %zu frames: resident %.1f MB at frame %llu, peak after it %.1f MB (+%.1f MB, limit +%.0f)\n",
        options.scene.c_str(), rss.size(), settled, (unsigned long long)settle_frames, peak, peak - settled,
        limit_mb);
    EXPECT_LE(peak - settled, limit_mb);
}

}  // namespace
}  // namespace sffd::editor
