// `splatffd view --timing-json` with and without --sync-timing, headless (EGL), on the editor's replay:
// the report says how it was timed and splits the drag frames per system and per named GL pass. With
// sync timing each system's GL work is finished inside it, so the systems' medians can be compared.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace fs = std::filesystem;

namespace {

int run(const std::string& command) {
    const int rc = std::system(command.c_str());
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

nlohmann::json timing(const fs::path& dir, const std::string& extra) {
    const fs::path json = dir / "timing.json", log = dir / "view.log";
    const std::string cmd = std::string(SFFD_BINARY_DIR) +
                            "/tools/splatffd view sphere --headless --size 1280x720 --frames 40 --replay " +
                            SFFD_TEST_DATA_DIR + "/editor/session.txt --save " + (dir / "s.glb").string() +
                            " --timing-json " + json.string() + extra + " > " + log.string() + " 2>&1";
    EXPECT_EQ(run(cmd), 0) << "see " << log;
    std::ifstream f(json);
    std::stringstream ss;
    ss << f.rdbuf();
    return nlohmann::json::parse(ss.str(), nullptr, false);
}

}  // namespace

TEST(ViewTiming, SyncTimingIsReportedAndSplitsTheDragFramesPerSystemAndPass) {
    const fs::path dir = fs::temp_directory_path() / ("sffd_view_timing_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const nlohmann::json plain = timing(dir, "");
    ASSERT_TRUE(plain.is_object());
    EXPECT_EQ(plain["timing"], "unsynchronised");
    const nlohmann::json sync = timing(dir, " --sync-timing");
    ASSERT_TRUE(sync.is_object());
    EXPECT_EQ(sync["timing"], "sync");
    EXPECT_GT(sync["drag_frames"].get<int>(), 5);
    double systems = 0.0;
    for (const auto& [name, ms] : sync["drag_system_ms_p50"].items()) systems += ms.get<double>();
    EXPECT_GT(systems, 0.0);
    EXPECT_TRUE(sync["drag_system_ms_p50"].contains("splat_render")) << sync.dump();
    EXPECT_TRUE(sync["drag_pass_ms_p50"].is_object()) << sync.dump();
    EXPECT_FALSE(sync["drag_pass_ms_p50"].empty()) << sync.dump();
    fs::remove_all(dir);
}
