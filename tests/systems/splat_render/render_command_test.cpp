// `splatffd render` end to end (runs the built binary without DISPLAY): one PNG + one EXR per frame, frame k
// alone equals frame k of a sequence, background option, usage and error exits.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <initializer_list>
#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "runtime/assets/builtin_scenes.h"
#include "runtime/assets/scene.h"
#include "runtime/ecs/registry.h"
#include "systems/splat_render/image_io.h"
#include "systems/splat_render/splat_pack.h"
#include "tests/test_util/run_tool.h"

namespace fs = std::filesystem;
using namespace sffd::render;

namespace {

const std::string binary = std::string(SFFD_BINARY_DIR) + "/tools/splatffd";

int run(const std::string& args, std::string* output = nullptr) {
    const sffd::test::CliRun r = sffd::test::run_headless("render " + args);
    if (output) *output = r.out;
    return r.code;
}

fs::path fresh_dir(const std::string& name) {
    const fs::path d = fs::temp_directory_path() / ("sffd_render_cmd_" + std::to_string(::getpid())) / name;
    fs::remove_all(d);
    return d;
}

}  // namespace

TEST(RenderCommand, WritesOnePngAndOneExrWithoutADisplay) {
    const fs::path out = fresh_dir("one");
    std::string log;
    ASSERT_EQ(run("--out " + out.string() + " --frames 0:0 --size 640x360", &log), 0) << log;
    int files = 0;
    for (const auto& e : fs::directory_iterator(out)) files += e.is_regular_file();
    EXPECT_EQ(files, 3);  // frame_0000.png, frame_0000.exr, render_manifest.json
    auto png = read_png(out / "frame_0000.png");
    ASSERT_TRUE(png.ok()) << png.message();
    EXPECT_EQ(png->width, 640);
    EXPECT_EQ(png->height, 360);
    EXPECT_EQ(png->at(0, 0)[3], 0);  // transparent background
    auto exr = read_exr(out / "frame_0000.exr");
    ASSERT_TRUE(exr.ok()) << exr.message();
    ASSERT_EQ(exr->depth.size(), std::size_t(640 * 360));
    ASSERT_EQ(exr->normal.size(), std::size_t(640 * 360));
    // The default scene (textured sphere) is in the middle of the frame: finite depth, unit normals there.
    const std::size_t c = exr->index(320, 180);
    EXPECT_GT(exr->color[c].w, 0.99f);
    EXPECT_TRUE(std::isfinite(exr->depth[c]));
    EXPECT_NEAR(glm::length(exr->normal[c]), 1.0f, 0.01f);
    EXPECT_TRUE(std::isinf(exr->depth[0]));
    // No progress line in a log (stderr is not a terminal here), but the result line.
    EXPECT_NE(log.find("wrote frames 0..0 to"), std::string::npos) << log;
    EXPECT_EQ(log.find('\r'), std::string::npos) << log;
}

// HQ: its result does not depend on the order the cull pass compacts splats in (depth is a min, colours a
// sum); the preview's opaque discs may swap a few pixels where two splats' depths tie exactly.
TEST(RenderCommand, FrameKAloneEqualsFrameKOfASequence) {
    const fs::path seq = fresh_dir("seq"), alone = fresh_dir("alone");
    std::string log;
    ASSERT_EQ(run("sphere --out " + seq.string() + " --frames 0:3 --size 160x90 --format png", &log), 0)
        << log;
    ASSERT_EQ(run("sphere --out " + alone.string() + " --frames 3:3 --size 160x90 --format png", &log), 0)
        << log;
    EXPECT_TRUE(fs::exists(seq / "frame_0000.png"));
    EXPECT_FALSE(fs::exists(alone / "frame_0000.png"));
    auto a = read_png(seq / "frame_0003.png");
    auto b = read_png(alone / "frame_0003.png");
    ASSERT_TRUE(a.ok() && b.ok());
    int differing = 0;
    for (std::size_t i = 0; i < a->pixels.size(); ++i)
        differing += std::abs(int(a->pixels[i]) - int(b->pixels[i])) > 2;
    EXPECT_EQ(differing, 0);
    // Not trivially equal: the built-in sphere's demo clip animates its lattice, so frame 0 differs.
    auto f0 = read_png(seq / "frame_0000.png");
    ASSERT_TRUE(f0.ok());
    int moved = 0;
    for (std::size_t i = 0; i < f0->pixels.size(); ++i)
        moved += std::abs(int(f0->pixels[i]) - int(a->pixels[i])) > 2;
    EXPECT_GT(moved, 0);
}

TEST(RenderCommand, BackgroundFillsThePng) {
    const fs::path out = fresh_dir("bg");
    ASSERT_EQ(
        run("--out " + out.string() + " --size 96x54 --format png --background 1,0,0 --quality preview"), 0);
    auto png = read_png(out / "frame_0000.png");
    ASSERT_TRUE(png.ok());
    EXPECT_FALSE(fs::exists(out / "frame_0000.exr"));
    EXPECT_EQ(png->at(0, 0)[0], 255);
    EXPECT_EQ(png->at(0, 0)[1], 0);
    EXPECT_EQ(png->at(0, 0)[3], 255);
}

TEST(RenderCommand, BadInputExitsWithAMessage) {
    std::string log;
    EXPECT_EQ(run("--frames 0:0", &log), 2);  // no --out
    EXPECT_NE(log.find("--out"), std::string::npos);
    EXPECT_EQ(run("--out /tmp/x --size 0x10", &log), 2);
    EXPECT_EQ(run("--out /tmp/x --frames 3:1", &log), 2);
    EXPECT_EQ(run("--out /tmp/x --quality ultra", &log), 2);
    const fs::path missing = fs::temp_directory_path() / "sffd_no_such_scene.ply";
    EXPECT_EQ(run(missing.string() + " --out " + fresh_dir("bad").string(), &log), 1);
    EXPECT_NE(log.find(missing.string()), std::string::npos) << log;
}

// DIR/render_manifest.json tells which frames this run wrote and whether it finished.
TEST(RenderCommand, ManifestListsTheFramesAndSaysWhetherTheRunCompleted) {
    const fs::path out = fresh_dir("manifest");
    std::string log;
    ASSERT_EQ(
        run("sphere --out " + out.string() + " --frames 2:3 --size 64x36 --format png --quality preview",
            &log),
        0)
        << log;
    std::ifstream in(out / "render_manifest.json");
    const std::string m((std::istreambuf_iterator<char>(in)), {});
    const nlohmann::json j = nlohmann::json::parse(m);
    EXPECT_EQ(j["state"], "complete") << m;
    EXPECT_EQ(j["complete"], true) << m;
    EXPECT_EQ(j["frames_written"]["count"], 2) << m;  // the first `count` frames of first, first + step, ...
    EXPECT_EQ(j["frames"]["first"], 2) << m;
    EXPECT_EQ(j["frames_written"]["last"], 3) << m;
    EXPECT_EQ(j["settings"]["size"], nlohmann::json::array({64, 36})) << m;
    EXPECT_EQ(j["settings"]["quality"], "preview") << m;
    EXPECT_EQ(j["settings"]["formats"], "png") << m;
    EXPECT_EQ(j["settings"]["scene"], "sphere") << m;
    ASSERT_EQ(j["files"].size(), 2u) << m;  // each frame's bytes and FNV-1a, written once at the end
    EXPECT_EQ(j["files"][1]["frame"], 3) << m;
    EXPECT_EQ(j["files"][1]["png"]["bytes"], fs::file_size(out / "frame_0003.png")) << m;
    // A frame that cannot be written (its name is taken by a folder): the run fails and says so.
    const fs::path bad = fresh_dir("manifest_failed");
    fs::create_directories(bad / "frame_0001.png");
    EXPECT_EQ(
        run("sphere --out " + bad.string() + " --frames 0:2 --size 64x36 --format png --quality preview",
            &log),
        1)
        << log;
    std::ifstream in2(bad / "render_manifest.json");
    const std::string f((std::istreambuf_iterator<char>(in2)), {});
    const nlohmann::json fj = nlohmann::json::parse(f);
    EXPECT_EQ(fj["state"], "failed") << f;
    EXPECT_EQ(fj["complete"], false) << f;
    EXPECT_EQ(fj["frames_written"]["count"], 1) << f;
    EXPECT_EQ(fj["frames_written"]["last"], 0) << f;
}

TEST(RenderCommand, SizeOverTheStatedMemoryBudgetIsRefusedUpFront) {
    std::string log;
    EXPECT_EQ(run("--out /tmp/x --size 16384x16384", &log), 2);
    EXPECT_NE(
        log.find("--size 16384x16384 is 268435456 pixels, more than the budget of 67108864 (8192x8192)"),
        std::string::npos)
        << log;
}

// SIGTERM during a sequence exits 143 with a message, leaves no temporary files, and the
// manifest still says the run did not complete and lists only the frames it finished.
TEST(RenderCommand, InterruptedSequenceLeavesAnIncompleteManifestAndNoTemporaries) {
    const fs::path out = fresh_dir("interrupted");
    fs::create_directories(out);
    const fs::path log = out.parent_path() / "interrupted.log";
    const pid_t pid = ::fork();
    if (pid == 0) {
        const std::string cmd =
            "exec env -u DISPLAY -u WAYLAND_DISPLAY " + binary + " render sphere --out " + out.string() +
            " --frames 0:100000 --size 64x36 --format png --quality preview 2>" + log.string();
        ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
        ::_exit(127);
    }
    bool sent = false;
    for (int i = 0; i < 60000 && !sent; ++i) {  // up to 60 s for the first frame
        if (fs::exists(out / "frame_0001.png")) {
            ::kill(pid, SIGTERM);
            sent = true;
        } else {
            ::usleep(1000);
        }
    }
    int status = 0;
    ::waitpid(pid, &status, 0);
    ASSERT_TRUE(sent);
    std::ifstream lin(log);
    const std::string err((std::istreambuf_iterator<char>(lin)), {});
    ASSERT_TRUE(WIFEXITED(status)) << err;
    EXPECT_EQ(WEXITSTATUS(status), 143) << err;
    EXPECT_NE(err.find("splatffd render: terminated (SIGTERM)"), std::string::npos) << err;
    std::ifstream in(out / "render_manifest.json");
    const std::string m((std::istreambuf_iterator<char>(in)), {});
    const nlohmann::json j = nlohmann::json::parse(m);
    EXPECT_EQ(j["state"], "running") << m;
    EXPECT_EQ(j["complete"], false) << m;
    // Frame 0 was finished; frame 1's file may exist before the manifest records it (the manifest is
    // written after each frame's files, so it never counts a frame that is not complete).
    EXPECT_GE(j["frames_written"]["count"].get<long>(), 1) << m;
    EXPECT_LT(j["frames_written"]["count"].get<long>(), 100001) << m;
    for (const auto& e : fs::directory_iterator(out))
        EXPECT_EQ(e.path().filename().string().find("sffd-tmp"), std::string::npos) << e.path();
}

// ---- --camera, --turntable, --video ------------------------------------------------------

namespace {

// Pixels whose channels differ by more than 2 (of 255).
int differing_pixels(const fs::path& a, const fs::path& b) {
    auto x = read_png(a);
    auto y = read_png(b);
    if (!x.ok() || !y.ok() || x->pixels.size() != y->pixels.size()) return -1;
    int n = 0;
    for (std::size_t i = 0; i < x->pixels.size(); i += 4) {
        bool d = false;
        for (int c = 0; c < 4; ++c) d = d || std::abs(int(x->pixels[i + c]) - int(y->pixels[i + c])) > 2;
        n += d;
    }
    return n;
}

std::string numbers(std::initializer_list<double> v) {
    std::string s;
    char buf[40];
    for (double x : v) {
        std::snprintf(buf, sizeof buf, "%.17g", x);
        if (!s.empty()) s += ',';
        s += buf;
    }
    return s;
}

// A scene file with one still cloud (the built-in sphere's points, no clip) seen by a known camera.
struct CameraScene {
    fs::path path;
    sffd::Camera camera;
    glm::dvec3 centre{0.0};  // the cloud's bounding-sphere centre in world space (= the scene bounds centre)
};

CameraScene camera_scene() {
    CameraScene s;
    s.path = fresh_dir("camera_scene");
    fs::create_directories(s.path);
    s.path /= "still.glb";
    sffd::ecs::Registry r;
    r.set_resource<sffd::SceneHooks>();  // assets' own formats only
    const sffd::SplatCloud cloud = sffd::assets::make_sphere_cloud(20000);
    const sffd::render::BoundingSphere b = sffd::render::bounding_sphere(cloud);
    s.centre = cloud.origin + b.center;
    r.emplace<sffd::SplatCloud>(r.create(), cloud);
    s.camera.eye = glm::dvec3(0.4, 0.9, 2.6);
    s.camera.target = glm::dvec3(0.1, 0.0, 0.0);
    s.camera.up = glm::dvec3(0.0, 1.0, 0.0);
    s.camera.fov_y_degrees = 40.0f;
    s.camera.near_plane = 0.5f;
    s.camera.far_plane = 6.0f;
    r.emplace<sffd::Camera>(r.create(), s.camera);
    sffd::DirectionalLight light;
    r.emplace<sffd::DirectionalLight>(r.create(), light);
    EXPECT_TRUE(sffd::save_scene(r, s.path).ok());
    return s;
}

std::string camera_option(const glm::dvec3& eye, const glm::dvec3& target, const glm::dvec3& up, double fov) {
    return " --camera " + numbers({eye.x, eye.y, eye.z, target.x, target.y, target.z, up.x, up.y, up.z, fov});
}

}  // namespace

TEST(RenderCommand, CameraOptionMovesTheViewAndMatchesTheSameSceneCamera) {
    const CameraScene scene = camera_scene();
    const fs::path own = fresh_dir("cam_own"), same = fresh_dir("cam_same"), other = fresh_dir("cam_other");
    const std::string common = " --size 160x90 --format png --quality preview";
    std::string log;
    ASSERT_EQ(run(scene.path.string() + " --out " + own.string() + common, &log), 0) << log;
    const sffd::Camera& c = scene.camera;
    ASSERT_EQ(run(scene.path.string() + " --out " + same.string() + common +
                      camera_option(c.eye, c.target, c.up, c.fov_y_degrees),
                  &log),
              0)
        << log;
    ASSERT_EQ(run(scene.path.string() + " --out " + other.string() + common +
                      camera_option({2.5, 0.2, -1.0}, {0, 0, 0}, {0, 1, 0}, 25.0),
                  &log),
              0)
        << log;
    // The same camera given on the command line draws the scene camera's image (only the clip planes,
    // fitted to the scene, differ); another camera draws another image.
    const int same_diff = differing_pixels(own / "frame_0000.png", same / "frame_0000.png");
    const int other_diff = differing_pixels(own / "frame_0000.png", other / "frame_0000.png");
    EXPECT_GE(same_diff, 0);
    EXPECT_LE(same_diff, 160 * 90 / 200) << "more than 0.5 % of the pixels differ";
    EXPECT_GT(other_diff, 160 * 90 / 10) << "the --camera view should differ from the scene camera's";
    // The scene's coverage is not empty in either (a camera looking away would pass the test above).
    auto png = read_png(other / "frame_0000.png");
    ASSERT_TRUE(png.ok());
    int covered = 0;
    for (std::size_t i = 3; i < png->pixels.size(); i += 4) covered += png->pixels[i] > 0;
    EXPECT_GT(covered, 160 * 90 / 50);
}

TEST(RenderCommand, DegenerateCamerasAreRefused) {
    std::string log;
    const std::string out = " --out " + fresh_dir("cam_bad").string();
    EXPECT_EQ(run(out + " --camera 1,2,3,1,2,3,0,1,0,45", &log), 2);
    EXPECT_NE(log.find("--camera: eye and target are the same point"), std::string::npos) << log;
    EXPECT_EQ(run(out + " --camera 0,0,3,0,0,0,0,0,-2,45", &log), 2);
    EXPECT_NE(log.find("--camera: up (0, 0, -2) is parallel to the view direction"), std::string::npos)
        << log;
    EXPECT_EQ(run(out + " --camera 0,0,3,0,0,0,0,1,0,0", &log), 2);
    EXPECT_NE(log.find("--camera: fov 0 is outside (0, 180) degrees"), std::string::npos) << log;
    EXPECT_EQ(run(out + " --camera 0,0,3,0,0,0,0,1,0,180", &log), 2);
    EXPECT_NE(log.find("--camera: fov 180 is outside (0, 180) degrees"), std::string::npos) << log;
    EXPECT_EQ(run(out + " --camera 0,0,3,0,0,0,0,1,0", &log), 2);
    EXPECT_NE(log.find("--camera expects 10 numbers"), std::string::npos) << log;
    EXPECT_EQ(run(out + " --camera 0,0,3,0,nan,0,0,1,0,45", &log), 2);
    EXPECT_NE(log.find("--camera: expected a number"), std::string::npos) << log;
    EXPECT_EQ(run(out + " --turntable 0", &log), 2);
    EXPECT_NE(log.find("--turntable: expected an integer in 1..100000, got '0'"), std::string::npos) << log;
    EXPECT_EQ(run(out + " --turntable 4 --frames 0:3", &log), 2);
    EXPECT_EQ(run(out + " --frames 0:abc", &log), 2);
    EXPECT_NE(log.find("--frames: expected an integer"), std::string::npos) << log;
    EXPECT_EQ(run(out + " --size 640x-5", &log), 2);
    EXPECT_NE(log.find("--size: expected an integer in 1..16384, got '-5'"), std::string::npos) << log;
    EXPECT_EQ(run(out + " --video clip.avi", &log), 2);
    EXPECT_NE(log.find("must end in .mp4 or .gif"), std::string::npos) << log;
    // 3D Gaussian files go through the engine like any scene: --turntable works on them and a
    // degenerate --camera is refused the same way.
    const fs::path g = fresh_dir("cam_bad").parent_path() / "gaussians.ply";
    fs::create_directories(g.parent_path());
    ASSERT_EQ(
        std::system((binary + " convert sphere " + g.string() + " --gaussians > /dev/null 2>&1").c_str()), 0);
    const fs::path turn = fresh_dir("gaussian_turn");
    EXPECT_EQ(run(g.string() + " --out " + turn.string() + " --size 48x32 --turntable 3", &log), 0) << log;
    EXPECT_TRUE(fs::exists(turn / "frame_0002.png"));
    EXPECT_EQ(run(g.string() + out + " --camera 1,2,3,1,2,3,0,1,0,45", &log), 2);
    EXPECT_NE(log.find("--camera: eye and target are the same point"), std::string::npos) << log;
}

TEST(RenderCommand, TurntableOrbitsAndStartsAtTheSceneCamerasEye) {
    const CameraScene scene = camera_scene();
    const fs::path turn = fresh_dir("turntable"), start = fresh_dir("turntable_start");
    const std::string common = " --size 160x90 --format png --quality preview";
    std::string log;
    ASSERT_EQ(run(scene.path.string() + " --out " + turn.string() + common + " --turntable 4", &log), 0)
        << log;
    for (int k = 0; k < 4; ++k)
        EXPECT_TRUE(fs::exists(turn / ("frame_000" + std::to_string(k) + ".png"))) << k;
    EXPECT_FALSE(fs::exists(turn / "frame_0004.png"));
    // Frame 0 = the scene camera's eye looking at the bounds centre, as --camera gives it.
    const glm::dvec3 up = glm::normalize(scene.camera.up);
    ASSERT_EQ(run(scene.path.string() + " --out " + start.string() + common +
                      camera_option(scene.camera.eye, scene.centre, up, scene.camera.fov_y_degrees),
                  &log),
              0)
        << log;
    EXPECT_EQ(differing_pixels(turn / "frame_0000.png", start / "frame_0000.png"), 0);
    // The other frames see the scene from elsewhere (the cloud is still: only the camera moves).
    for (int k = 1; k < 4; ++k)
        EXPECT_GT(
            differing_pixels(turn / "frame_0000.png", turn / ("frame_000" + std::to_string(k) + ".png")), 100)
            << k;
}

TEST(RenderCommand, VideoNamesFfmpegWhenItIsMissing) {
    const fs::path out = fresh_dir("video_missing");
    fs::create_directories(out.parent_path());
    const fs::path log = out.parent_path() / "video_missing.log";
    // PATH without ffmpeg: refused before any frame is rendered, naming the package.
    const std::string cmd = "env -u DISPLAY -u WAYLAND_DISPLAY PATH=/nonexistent " + binary +
                            " render sphere --out " + out.string() + " --video " +
                            (out.parent_path() / "v.mp4").string() + " > " + log.string() + " 2>&1";
    const int status = std::system(cmd.c_str());
    std::ifstream in(log);
    const std::string text((std::istreambuf_iterator<char>(in)), {});
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 1) << text;
    EXPECT_NE(
        text.find(
            "--video needs ffmpeg, which is not on PATH; install it (Debian/Ubuntu: apt-get install ffmpeg)"),
        std::string::npos)
        << text;
    EXPECT_FALSE(fs::exists(out / "frame_0000.png"));
}

TEST(RenderCommand, VideoOfATurntableHasOneFramePerImage) {
    if (std::system("command -v ffmpeg > /dev/null 2>&1 && command -v ffprobe > /dev/null 2>&1") != 0)
        GTEST_SKIP() << "ffmpeg/ffprobe not installed (tools/bootstrap.sh installs them; --video needs them)";
    const fs::path out = fresh_dir("video");
    fs::create_directories(out.parent_path());  // the videos go next to the frames' folder
    for (const char* name : {"turn clip.mp4", "turn.gif"}) {
        const fs::path video = out.parent_path() / name;
        fs::remove(video);
        std::string log;
        ASSERT_EQ(run("sphere --out " + out.string() +
                          " --size 97x55 --format png --quality preview --turntable 5 --video '" +
                          video.string() + "'",
                      &log),
                  0)
            << log;
        ASSERT_TRUE(fs::exists(video)) << log;
        const fs::path probe = out.parent_path() / "probe.txt";
        const std::string cmd =
            "ffprobe -v error -count_frames -select_streams v:0 -show_entries stream=nb_read_frames -of "
            "csv=p=0 '" +
            video.string() + "' > " + probe.string();
        ASSERT_EQ(std::system(cmd.c_str()), 0);
        std::ifstream in(probe);
        int frames = 0;
        in >> frames;
        EXPECT_EQ(frames, 5) << name;
        for (const auto& e : fs::directory_iterator(out.parent_path()))
            EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos)
                << "temporary left: " << e.path();
    }
}
