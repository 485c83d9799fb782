// `splatffd export SCENE --web DIR` through the built binary, without a browser: what it refuses (no
// lattice, a clip without keys, surface splats, a folder that holds other files, no engine) and what the
// folder holds (the capture as SOG that reads back, the lattice and the clip as the scene has them).
// The page's clip evaluation (clip.js, run by node) equals systems/animation/evaluate.cpp on a clip with
// every interpolation, easing and play-mode path. The browser test is web_player_test.cpp (label slow).
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "systems/animation/clip_io.h"
#include "systems/animation/evaluate.h"
#include "runtime/assets/formats/gaussian/gaussian_sog.h"
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

TEST(WebExport, PlayerClipEvaluationEqualsTheEngines) {
    if (run_command("command -v node").code != 0)
        GTEST_SKIP() << "node is not installed (tools/bootstrap.sh)";
    if (!engine_installed())
        GTEST_SKIP() << "the PlayCanvas engine is not installed (tools/fetch_web_engine.sh)";
    using namespace sffd;
    ecs::Registry reg;
    reg.set_resource<SceneHooks>();  // assets' own formats only
    use_engine_scene_hooks(reg);
    ASSERT_TRUE(load_scene(reg, (scenes() / "gs.glb").string()));
    const Lattice* lattice = nullptr;
    reg.view<const Lattice>().each([&](ecs::Entity e, const Lattice& l) {
        lattice = &l;
        AnimationClip clip;
        clip.name = "every path";
        clip.duration = 1.6;
        clip.mode = PlayMode::ping_pong;
        clip.speed = 1.5;
        std::vector<std::uint32_t> low, high;
        for (std::uint32_t i = 0; i < 40; ++i) low.push_back(i);
        for (std::uint32_t i = 30; i < 90; ++i) high.push_back(i);
        const std::size_t a = add_stretch_track(clip, "stretch", low);
        set_key(clip.tracks[a], {0.0, glm::dvec3(0.0), Interpolation::step, Easing::none});
        set_key(clip.tracks[a], {0.3, glm::dvec3(0.1, 0.2, -0.1), Interpolation::smooth, Easing::ease_in});
        set_key(clip.tracks[a], {0.7, glm::dvec3(0.3, 0.0, 0.05), Interpolation::smooth, Easing::ease_out});
        set_key(clip.tracks[a], {1.2, glm::dvec3(0.0, 0.1, 0.0), Interpolation::linear, Easing::ease_in_out});
        set_key(clip.tracks[a], {1.6, glm::dvec3(0.0), Interpolation::smooth, Easing::none});
        const std::size_t b =
            add_twist_track(clip, "twist pivot", high, {0.3, 1.0, 0.2}, glm::dvec3(0.1, -0.2, 0.3));
        set_key(clip.tracks[b], {0.0, glm::dvec3(0.0), Interpolation::smooth, Easing::none});
        set_key(clip.tracks[b], {0.5, glm::dvec3(90.0, 0, 0), Interpolation::linear, Easing::none});
        set_key(clip.tracks[b], {1.0, glm::dvec3(450.0, 0, 0), Interpolation::step, Easing::none});
        set_key(clip.tracks[b], {1.3, glm::dvec3(-30.0, 0, 0), Interpolation::smooth, Easing::ease_in_out});
        const std::size_t c = add_twist_track(clip, "twist centroid", low, {1.0, 0.0, 0.0});
        set_key(clip.tracks[c], {0.2, glm::dvec3(0.0), Interpolation::smooth, Easing::none});
        set_key(clip.tracks[c], {1.4, glm::dvec3(200.0, 0, 0), Interpolation::smooth, Easing::none});
        reg.emplace<AnimationClip>(e, std::move(clip));
        AnimationState state;
        state.speed = 0.75;
        reg.emplace<AnimationState>(e, state);
    });
    ASSERT_NE(lattice, nullptr);
    const fs::path scene = scenes() / "every_path.glb";
    ASSERT_TRUE(save_scene(reg, scene));
    const fs::path out = out_dir("clip");
    const auto ex = run("export " + scene.string() + " --web " + out.string());
    ASSERT_EQ(ex.code, 0) << ex.out;

    const std::vector<double> times = {
        -0.7, 0.0, 0.1, 0.2666666666666667, 0.45, 0.8888888888888888, 1.0, 1.1, 1.4222222222222223, 1.9,
        2.5,  3.3, 7.77};
    std::string args;
    for (double t : times) args += " " + std::to_string(t);
    const fs::path js =
        fs::path(SFFD_TEST_DATA_DIR).parent_path() / "tools" / "splatffd" / "web_clip_eval.js";
    const auto r = run_command("node " + js.string() + " " + out.string() + args);
    ASSERT_EQ(r.code, 0) << r.out;
    const nlohmann::json got = nlohmann::json::parse(r.out);
    ASSERT_EQ(got.size(), times.size());
    const AnimationClip* c = nullptr;
    reg.view<const AnimationClip>().each([&](const AnimationClip& x) { c = &x; });
    for (std::size_t i = 0; i < times.size(); ++i) {
        const double t = got[i]["t"].get<double>();  // as node read it
        const double clip_time = map_clip_time(*c, t * 0.75 * c->speed);
        EXPECT_DOUBLE_EQ(got[i]["clip_time"].get<double>(), clip_time) << "t " << t;
        const auto pose = evaluate_pose(*c, *lattice, clip_time);
        ASSERT_EQ(got[i]["points"].size(), pose.size());
        double worst = 0.0;
        for (std::size_t p = 0; p < pose.size(); ++p)
            for (int k = 0; k < 3; ++k)
                worst = std::max(worst, std::abs(got[i]["points"][p][k].get<double>() - pose[p][k]));
        EXPECT_LT(worst, 1e-12) << "t " << t << " (clip time " << clip_time << ")";
    }
}
