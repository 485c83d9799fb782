// `splatffd export SCENE --web DIR` through the built binary, without a browser: what it refuses (no
// lattice, a clip without keys, surface splats, a folder that holds other files, no engine) and what the
// folder holds (the capture as SOG that reads back, the lattice and the clip as the scene has them).
// The browser test is web_player_test.cpp (label slow).
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <nlohmann/json.hpp>

#include "systems/animation/clip_io.h"
#include "systems/gaussian/gaussian_sog.h"
#include "tests/tools/splatffd/web_test_scene.h"

namespace fs = std::filesystem;
using sffd::test::run;
using sffd::test::run_command;

namespace {

const fs::path& scenes() {
    static const fs::path dir = [] {
        const fs::path d = fs::temp_directory_path() / ("sffd_web_export_" + std::to_string(::getpid()));
        fs::remove_all(d);
        fs::create_directories(d);
        const std::string problem = sffd::test::make_web_test_scenes(d);
        EXPECT_EQ(problem, "");
        return d;
    }();
    return dir;
}

fs::path out_dir(const std::string& name) {
    const fs::path d = scenes() / ("out_" + name);
    fs::remove_all(d);
    return d;
}

std::string slurp(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

bool engine_installed() {
    return run_command("test -f " + std::string(SFFD_BINARY_DIR) + "/tools/web/playcanvas.min.js").code == 0;
}

// The JSON of a `window.NAME = {...};` script.
nlohmann::json script_json(const fs::path& p) {
    std::string s = slurp(p);
    const auto a = s.find('{'), b = s.rfind('}');
    return nlohmann::json::parse(s.substr(a, b - a + 1));
}

std::string unbase64(const std::string& in) {
    std::string out;
    int val = 0, bits = -8;
    for (unsigned char c : in) {
        int d = c >= 'A' && c <= 'Z'   ? c - 'A'
                : c >= 'a' && c <= 'z' ? c - 'a' + 26
                : c >= '0' && c <= '9' ? c - '0' + 52
                : c == '+'             ? 62
                : c == '/'             ? 63
                                       : -1;
        if (d < 0) break;
        val = (val << 6) | d, bits += 6;
        if (bits >= 0) out += char((val >> bits) & 0xff), bits -= 8;
    }
    return out;
}

}  // namespace

TEST(WebExport, RefusesACloudWithoutALattice) {
    const fs::path out = out_dir("nolattice");
    const auto r = run("export " + (scenes() / "g.ply").string() + " --web " + out.string());
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_NE(r.out.find("splatffd export: "), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("has no lattice"), std::string::npos) << r.out;
    EXPECT_FALSE(fs::exists(out));
}

TEST(WebExport, RefusesALatticeWhoseClipHasNoKeys) {
    const fs::path out = out_dir("nokeys");
    const auto r = run("export " + (scenes() / "gs.glb").string() + " --web " + out.string());
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_NE(r.out.find("clip has no keys: nothing to play"), std::string::npos) << r.out;
    EXPECT_FALSE(fs::exists(out));
}

TEST(WebExport, RefusesSurfaceSplatsAndSaysHowToConvert) {
    const fs::path out = out_dir("surface");
    const auto r = run("export sphere --web " + out.string());
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_NE(r.out.find("plays 3D Gaussians only"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("--gaussians"), std::string::npos) << r.out;
}

TEST(WebExport, RefusesWithoutTheEngineAndNamesTheScript) {
    const fs::path out = out_dir("noengine");
    const auto r =
        run_command("SPLATFFD_WEB_ENGINE=/nonexistent/playcanvas.min.js " + std::string(SFFD_BINARY_DIR) +
                    "/tools/splatffd export " + (scenes() / "twist.glb").string() + " --web " + out.string());
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_NE(r.out.find("the PlayCanvas engine is not installed"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("run tools/fetch_web_engine.sh"), std::string::npos) << r.out;
    EXPECT_FALSE(fs::exists(out));
}

TEST(WebExport, RefusesAFolderWithOtherFilesUnlessForced) {
    const fs::path out = out_dir("busy");
    fs::create_directories(out);
    { std::ofstream(out / "notes.txt") << "mine"; }
    { std::ofstream(out / "index.html") << "my page"; }
    const std::string cmd = "export " + (scenes() / "twist.glb").string() + " --web " + out.string();
    const auto r = run(cmd);
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_NE(r.out.find("the folder is not empty"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("--force"), std::string::npos) << r.out;
    EXPECT_EQ(slurp(out / "index.html"), "my page");
    EXPECT_EQ(slurp(out / "notes.txt"), "mine");
    if (!engine_installed())
        GTEST_SKIP() << "the PlayCanvas engine is not installed (tools/fetch_web_engine.sh)";
    const auto forced = run(cmd + " --force");
    EXPECT_EQ(forced.code, 0) << forced.out;
    EXPECT_NE(slurp(out / "index.html"), "my page");  // --force replaces the player's own names
    EXPECT_EQ(slurp(out / "notes.txt"), "mine");      // and nothing else
}

TEST(WebExport, FolderHoldsThePlayerTheSogCaptureTheLatticeAndTheClip) {
    if (!engine_installed())
        GTEST_SKIP() << "the PlayCanvas engine is not installed (tools/fetch_web_engine.sh)";
    const fs::path out = out_dir("ok");
    const auto r =
        run("export " + (scenes() / "twist.glb").string() + " --web " + out.string() + " --size 320x200");
    ASSERT_EQ(r.code, 0) << r.out;
    for (const char* f :
         {"index.html", "player.js", "ffd_glsl.js", "clip.js", "scene.js", "capture.js", "playcanvas.min.js"})
        EXPECT_TRUE(fs::is_regular_file(out / f)) << f;
    EXPECT_FALSE(fs::exists(out / ".capture.tmp.sog"));
    // Every script the page loads is a classic <script src> (file:// refuses modules and fetch).
    const std::string html = slurp(out / "index.html");
    EXPECT_EQ(html.find("type=\"module\""), std::string::npos);
    for (const char* f : {"playcanvas.min.js", "scene.js", "capture.js", "player.js"})
        EXPECT_NE(html.find(std::string("<script src=\"") + f + "\">"), std::string::npos) << f;

    const nlohmann::json scene = script_json(out / "scene.js");
    EXPECT_EQ(scene["size"], nlohmann::json::array({320, 200}));
    EXPECT_EQ(scene["lattice"]["divisions"], nlohmann::json::array({4, 4, 4}));
    EXPECT_EQ(scene["lattice"]["basis"], "bernstein");
    EXPECT_EQ(scene["lattice"]["rest"].size(), 125u);
    auto clip = sffd::clip_from_json(scene["clip"], "scene.js");
    ASSERT_TRUE(clip) << clip.message();
    EXPECT_EQ(clip->name, "twist");
    EXPECT_EQ(clip->tracks.size(), 5u);
    EXPECT_DOUBLE_EQ(clip->duration, 2.0);
    EXPECT_DOUBLE_EQ(clip->tracks[4].keys[1].value.x, 60.0);
    EXPECT_EQ(scene["capture"]["format"], "sog");

    // The capture is SOG bytes that our own reader opens: every Gaussian of the scene.
    const std::string capture = slurp(out / "capture.js");
    const auto a = capture.find("base64: \"") + 9;
    const std::string bytes = unbase64(capture.substr(a, capture.find('"', a) - a));
    const fs::path sog = scenes() / "back.sog";
    { std::ofstream(sog, std::ios::binary) << bytes; }
    auto cloud = sffd::gaussian::read_sog(sog);
    ASSERT_TRUE(cloud) << cloud.message();
    EXPECT_EQ(cloud->size(), 59650u);
    EXPECT_EQ(scene["capture"]["count"], 59650);
}
