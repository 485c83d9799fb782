// One scene, the same story from every command, through the built binary as a user runs it: a saved
// un-keyed edit shows in `view`, `render`, `deform` and `info` alike; every command's errors start with
// its name; `info` lists clips, a deformed cloud's bounds at rest and deformed, and lattice transforms;
// `convert` of a scene writes what render and deform show; Gaussian captures open upright from every
// format; the profiler's numbers say what they measured.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "systems/splat_render/image_io.h"
#include "tests/test_util/run_tool.h"

namespace fs = std::filesystem;
using sffd::test::CliRun;

namespace {

fs::path temp_dir(const std::string& name) {
    const fs::path d = fs::temp_directory_path() / ("sffd_scene_story_" + std::to_string(::getpid())) / name;
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

CliRun tool(const std::string& args) { return sffd::test::run_headless(args); }

bool has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

struct glm_free_size {
    double x, y, z;
};

// The first line of `text` whose words start with `start` (leading spaces skipped), or "".
std::string line_of(const std::string& text, const std::string& start) {
    std::istringstream lines(text);
    for (std::string line; std::getline(lines, line);)
        if (line.find_first_not_of(' ') != std::string::npos &&
            line.compare(line.find_first_not_of(' '), start.size(), start) == 0)
            return line;
    return "";
}

// The three sizes of a bounds line "... (size X x Y x Z)".
glm_free_size size_of(const std::string& line) {
    glm_free_size s{};
    const auto at = line.find("(size ");
    if (at == std::string::npos ||
        std::sscanf(line.c_str() + at, "(size %lf x %lf x %lf)", &s.x, &s.y, &s.z) != 3)
        ADD_FAILURE() << "no size in '" << line << "'";
    return s;
}

const std::string kCamera = " --camera 1.5,1.3,4.3,0,0,0,0,1,0,40";

// Frame FRAME of `scene` as EXR (HQ: the same image every run), with a fixed camera.
fs::path render_exr(const std::string& scene, const fs::path& out, int frame = 0,
                    std::string* log = nullptr) {
    const CliRun r =
        tool("render " + scene + " --out " + out.string() + " --frames " + std::to_string(frame) + ":" +
             std::to_string(frame) + " --size 160x120 --format exr" + kCamera);
    EXPECT_EQ(r.code, 0) << r.out;
    if (log) *log = r.out;
    char name[32];
    std::snprintf(name, sizeof name, "frame_%04d.exr", frame);
    return out / name;
}

// psnr_db of `compare A B` (inf for identical images; NaN when compare failed).
double psnr(const fs::path& a, const fs::path& b) {
    const CliRun r = tool("compare " + a.string() + " " + b.string());
    const auto at = r.out.find("psnr_db=");
    if (r.code != 0 || at == std::string::npos) {
        ADD_FAILURE() << r.out;
        return std::nan("");
    }
    return std::strtod(r.out.c_str() + at + 8, nullptr);
}

// The editor session of the issue: stretch and twist the sphere's inner control points without keying
// them, and save at the clip time 0 s.
fs::path saved_edit(const fs::path& dir, std::string* log = nullptr) {
    const fs::path v2 = dir / "v2.glb";
    const CliRun r = tool("view sphere --headless --replay " + std::string(SFFD_TEST_DATA_DIR) +
                          "/editor/session.txt --frames 66 --no-ui --save " + v2.string());
    EXPECT_EQ(r.code, 0) << r.out;
    if (log) *log = r.out;
    return v2;
}

}  // namespace

// The rule: an un-keyed edit belongs to the clip time it was made at. The editor warns when saving it;
// `info` lists the clip and the edit; `render` shows it at that time's frame and the clip's pose at every
// other, and says so; `deform` uses the control points as saved (the edit) and says so; `view` opens on it.
TEST(SceneStory, AnUnkeyedEditShowsAtItsClipTimeInEveryCommand) {
    const fs::path dir = temp_dir("unkeyed");
    std::string log;
    const fs::path v2 = saved_edit(dir, &log);
    EXPECT_TRUE(has(log, "un-keyed edit at clip time 0 s (48 control points off the clip's pose")) << log;

    const CliRun info = tool("info " + v2.string());
    ASSERT_EQ(info.code, 0) << info.out;
    EXPECT_TRUE(has(info.out, "clip     'paper demo': ")) << info.out;
    EXPECT_TRUE(has(info.out, "opens at clip time 0 s")) << info.out;
    EXPECT_TRUE(has(info.out, "WARNING  un-keyed edit at clip time 0 s (48 control points")) << info.out;

    // render: frame 0 (0 s) shows the edit, frame 1 the clip's pose, the same as the untouched sphere's.
    const fs::path sphere0 = render_exr("sphere", dir / "sphere0");
    const fs::path sphere1 = render_exr("sphere", dir / "sphere1", 1);
    std::string note;
    const fs::path edit0 = render_exr(v2.string(), dir / "edit0", 0, &note);
    EXPECT_TRUE(has(note, "splatffd render: note: 'sphere.lattice' has an un-keyed edit at clip time 0 s"))
        << note;
    EXPECT_TRUE(has(note, "(frame 0 at 24 fps)")) << note;
    const fs::path edit1 = render_exr(v2.string(), dir / "edit1", 1);
    EXPECT_LT(psnr(edit0, sphere0), 30.0) << "the saved edit is shown at its frame";
    EXPECT_GT(psnr(edit1, sphere1), 60.0) << "every other frame is the clip's";

    // deform: the control points as saved, the edit; its render without a lattice is the scene's frame 0.
    const fs::path deformed = dir / "deformed.glb";
    const CliRun d = tool("deform " + v2.string() + " " + deformed.string());
    ASSERT_EQ(d.code, 0) << d.out;
    EXPECT_TRUE(has(d.out, "splatffd deform: note: 'sphere.lattice' has an un-keyed edit")) << d.out;
    EXPECT_TRUE(has(d.out, "so this uses the edit")) << d.out;
    const fs::path deformed0 = render_exr(deformed.string(), dir / "deformed0");
    EXPECT_GT(psnr(deformed0, edit0), 30.0) << "deform and render tell the same story";
    EXPECT_LT(psnr(deformed0, sphere0), 30.0);

    // view: opens paused at the saved time, on the edit.
    const fs::path view_edit = dir / "view_edit.exr", view_sphere = dir / "view_sphere.exr";
    for (const auto& [scene, shot] :
         {std::pair{v2.string(), view_edit}, std::pair{std::string("sphere"), view_sphere}}) {
        const CliRun v =
            tool("view " + scene + " --headless --frames 2 --no-ui --size 320x240 --out " + shot.string());
        ASSERT_EQ(v.code, 0) << v.out;
    }
    EXPECT_LT(psnr(view_edit, view_sphere), 30.0) << "view shows the edit on opening";
}

// One message form: every error line starts with "splatffd <command>: ", whichever command meets the
// file (the message itself names the file and the problem).
TEST(SceneStory, EveryCommandsErrorsStartWithItsName) {
    const fs::path dir = temp_dir("errors");
    const std::string empty = (dir / "empty.ply").string(), exr = (dir / "empty.exr").string(),
                      json = (dir / "empty.json").string();
    for (const std::string& f : {empty, exr, json}) std::ofstream(f).flush();
    const std::string out = (dir / "out").string();
    struct Case {
        std::string command, args, problem;
    };
    const std::vector<Case> cases = {
        {"render", empty + " --out " + out, "empty.ply: not a PLY file"},
        {"pick", empty + " --at 1,1", "empty.ply: not a PLY file"},
        {"reference", empty + " --out " + out, "empty.ply: not a PLY file"},
        {"profile", empty + " --frames 1", "empty.ply: not a PLY file"},
        {"profile", "sphere --frames 1 --compare " + json, "empty.json"},
        {"view", empty + " --headless --frames 1", "empty.ply: not a PLY file"},
        {"deform", empty + " " + (dir / "o.ply").string() + " --lattice fit", "empty.ply: not a PLY file"},
        {"convert", empty + " " + (dir / "o.glb").string(), "empty.ply: not a PLY file"},
        {"info", empty, "empty.ply: not a PLY file"},
        {"compare", exr + " " + exr, "empty.exr: not a readable EXR"},
        {"assemble", (dir / "nothere").string(), "nothere: not a folder"},
    };
    for (const Case& c : cases) {
        const CliRun r = tool(c.command + " " + c.args);
        EXPECT_NE(r.code, 0) << c.command << ": " << r.out;
        bool found = false;
        std::istringstream lines(r.out);
        for (std::string line; std::getline(lines, line);) {
            if (!has(line, c.problem)) continue;
            found = true;
            EXPECT_EQ(line.rfind("splatffd " + c.command + ": ", 0), 0u) << line;
        }
        EXPECT_TRUE(found) << c.command << " " << c.args << ":\n" << r.out;
    }
}

// info says what the other commands will do with a scene: every clip (a built-in's too), a deformed cloud's
// bounds at rest and as its lattices deform it as saved, and each lattice's transform.
TEST(SceneStory, InfoListsClipsBothBoundsAndLatticeTransforms) {
    const fs::path dir = temp_dir("info");
    const CliRun sphere = tool("info sphere");
    ASSERT_EQ(sphere.code, 0) << sphere.out;
    EXPECT_TRUE(has(sphere.out,
                    "clip     'paper demo': 24 tracks, 96 keys, 4 s, loop, speed 1; opens at clip time 0 s"))
        << sphere.out;
    EXPECT_TRUE(
        has(sphere.out, "transform translation [0, 0, 0], rotation (x y z w) [0, 0, 0, 1], scale [1, 1, 1]"))
        << sphere.out;

    // A scene whose lattice is displaced (its top middle control point raised) and moved by its transform.
    const fs::path gltf = dir / "s.gltf";
    const CliRun c = tool("convert sphere " + gltf.string() + " --lattice fit:2 --splats 2000");
    ASSERT_EQ(c.code, 0) << c.out;
    nlohmann::json doc;
    std::ifstream(gltf) >> doc;
    nlohmann::json& lattice = doc["extensions"]["SFFD_scene"]["lattices"][0];
    lattice["control_points"][16][1] = lattice["control_points"][16][1].get<double>() + 0.5;
    lattice["transform"]["translation"] = {0.5, 0.0, 0.0};
    lattice["transform"]["rotation"] = {0.0, 0.70710678118654757, 0.0, 0.70710678118654757};
    std::ofstream(gltf) << doc.dump();
    const CliRun info = tool("info " + gltf.string());
    ASSERT_EQ(info.code, 0) << info.out;
    const std::string rest = line_of(info.out, "rest "), deformed = line_of(info.out, "deformed [");
    ASSERT_FALSE(rest.empty()) << info.out;
    ASSERT_FALSE(deformed.empty()) << info.out;
    EXPECT_TRUE(has(deformed, "by 'sphere.lattice' as saved")) << deformed;
    // The lattice deforms where its transform puts it: half a unit to +x, so its raised point sits off the
    // sphere's top and lifts it less than the 0.1 it would lift it in place (0.093 measured), but well
    // over the rest size.
    EXPECT_GT(size_of(deformed).y, size_of(rest).y + 0.05) << info.out;
    EXPECT_LT(size_of(deformed).y, size_of(rest).y + 0.1) << info.out;
    EXPECT_NEAR(size_of(deformed).x, size_of(rest).x, 0.05) << info.out;
    EXPECT_TRUE(
        has(info.out, "transform translation [0.5, 0, 0], rotation (x y z w) [0, 0.707107, 0, 0.707107]"))
        << info.out;
    EXPECT_TRUE(has(info.out, "1 displaced (max 0.5)")) << info.out;
}

namespace {

// The x range of the first bounds line of `info FILE` whose label is `label` ("bounds", "deformed").
std::pair<double, double> x_range(const std::string& file, const std::string& label = "bounds") {
    const CliRun r = tool("info " + file);
    EXPECT_EQ(r.code, 0) << r.out;
    const std::string line = line_of(r.out, label + " ");
    double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    const auto at = line.find('[');
    if (at == std::string::npos || std::sscanf(line.c_str() + at, "[%lf, %lf, %lf] .. [%lf, %lf, %lf]",
                                               &lo[0], &lo[1], &lo[2], &hi[0], &hi[1], &hi[2]) != 6)
        ADD_FAILURE() << file << ": no '" << label << "' line in\n" << r.out;
    return {lo[0], hi[0]};
}

}  // namespace

// convert of a scene tells the same story as render and deform: the Gaussians where render shows them in
// every Gaussian format (a scene of embedded Gaussians used to come out turned 180 degrees about z),
// deformed by the scene's lattices as saved unless --rest asks for the cloud at rest, and a scene the
// editor saved with its Gaussians in a file beside it converts like any other (it used to be refused).
TEST(SceneStory, ConvertOfASceneWritesWhatRenderAndDeformShow) {
    const fs::path dir = temp_dir("convert");
    const std::string g = (dir / "g.ply").string();
    ASSERT_EQ(tool("convert sphere " + g + " --gaussians --splats 4000").code, 0);
    // Off centre in x, so a turn about z shows in the x range.
    const fs::path shifted = dir / "shifted.json";
    {
        std::ofstream(shifted) << R"({"origin": [-2, -2, -2], "axes": [[4, 0, 0], [0, 4, 0], [0, 0, 4]],
            "divisions": [1, 1, 1], "control_points": [[-0.5, -2, -2], [-0.5, -2, 2], [-0.5, 2, -2], [-0.5, 2, 2],
            [3.5, -2, -2], [3.5, -2, 2], [3.5, 2, -2], [3.5, 2, 2]]})";
    }
    const std::string capture = (dir / "capture.ply").string();
    ASSERT_EQ(tool("deform " + g + " " + capture + " --lattice " + shifted.string()).code, 0);
    const auto rest = x_range(capture);
    ASSERT_GT(rest.first, 0.4) << "the capture lies at x > 0";

    const std::string fruit = (dir / "fruit.glb").string();
    ASSERT_EQ(tool("convert " + capture + " " + fruit + " --lattice fit:3,3,3").code, 0);
    for (const std::string out : {"o.ply", "o.spz", "o.compressed.ply"}) {
        const std::string path = (dir / out).string();
        const CliRun c = tool("convert " + fruit + " " + path + " --gaussians");
        ASSERT_EQ(c.code, 0) << c.out;
        EXPECT_TRUE(has(c.out, "its lattices 'capture.lattice' at rest")) << c.out;
        const auto x = x_range(path);
        EXPECT_NEAR(x.first, rest.first, 2e-3) << out;
        EXPECT_NEAR(x.second, rest.second, 2e-3) << out;
    }

    // The editor's save: lattice added, stretched along x, the Gaussians left in capture.ply.
    const std::string edited = (dir / "edited.glb").string();
    const CliRun v = tool("view " + capture + " --headless --replay " + std::string(SFFD_TEST_DATA_DIR) +
                          "/editor/lattice_add.txt --frames 14 --no-ui --save " + edited);
    ASSERT_EQ(v.code, 0) << v.out;
    const auto shown = x_range(edited, "deformed");
    ASSERT_GT(shown.second, rest.second + 0.05) << "the saved lattice moves the capture";
    const std::string deformed = (dir / "deformed.ply").string(), at_rest = (dir / "rest.ply").string(),
                      by_deform = (dir / "by_deform.ply").string();
    const CliRun c = tool("convert " + edited + " " + deformed);
    ASSERT_EQ(c.code, 0) << c.out;
    EXPECT_TRUE(has(c.out, "deformed by 'capture.lattice' as saved (--rest: the cloud at rest)")) << c.out;
    const CliRun r = tool("convert " + edited + " " + at_rest + " --rest");
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_TRUE(has(r.out, "at rest (without --rest: deformed by 'capture.lattice' as saved)")) << r.out;
    ASSERT_EQ(tool("deform " + edited + " " + by_deform).code, 0);
    const auto x_deformed = x_range(deformed), x_rest = x_range(at_rest), x_by_deform = x_range(by_deform);
    EXPECT_NEAR(x_deformed.second, shown.second, 1e-4) << "what info says the lattice does";
    EXPECT_NEAR(x_deformed.second, x_by_deform.second, 1e-4) << "what deform writes";
    EXPECT_NEAR(x_rest.first, rest.first, 1e-6);
    EXPECT_NEAR(x_rest.second, rest.second, 1e-6);
    // A scene OUT is the scene as loaded: its lattice still bound, still displaced.
    const std::string copy = (dir / "copy.glb").string();
    const CliRun s = tool("convert " + edited + " " + copy);
    ASSERT_EQ(s.code, 0) << s.out;
    EXPECT_NEAR(x_range(copy, "deformed").second, shown.second, 1e-9);
}

namespace {

// How much redder than blue the top third of the object's pixels is, minus the same for the bottom third:
// the sphere's north cap is red and its south cap blue, so upright is > 0 and upside down < 0.
double red_on_top(const fs::path& png) {
    auto image = sffd::render::read_png(png);
    if (!image) {
        ADD_FAILURE() << image.message();
        return 0.0;
    }
    int top = image->height, bottom = -1;
    for (int y = 0; y < image->height; ++y)
        for (int x = 0; x < image->width; ++x)
            if (image->at(x, y)[3] > 128) top = std::min(top, y), bottom = std::max(bottom, y);
    const auto redness = [&](int y0, int y1) {
        double sum = 0.0, n = 0.0;
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < image->width; ++x)
                if (const std::uint8_t* p = image->at(x, y); p[3] > 128)
                    sum += double(p[0]) - double(p[2]), n += 1;
        return n > 0 ? sum / n : 0.0;
    };
    const int third = (bottom - top + 1) / 3;
    return redness(top, top + third) - redness(bottom + 1 - third, bottom + 1);
}

// Frame 0 of `scene` with the automatic camera (the scene has none), as PNG.
fs::path auto_camera_png(const std::string& scene, const fs::path& out, const std::string& global = "") {
    const CliRun r =
        tool(global + "render " + scene + " --out " + out.string() + " --size 160x120 --format png");
    EXPECT_EQ(r.code, 0) << r.out;
    return out / "frame_0000.png";
}

}  // namespace

// Gaussian captures are stored y down (3DGS, COLMAP, SuperSplat); they open upright, the same from every
// Gaussian format and from a scene made of them, and `--up` names another up for a file stored otherwise.
// The built-in sphere converted to Gaussians is written as such a capture (its north cap at -y in the file).
TEST(SceneStory, GaussianCapturesOpenUprightFromEveryFormat) {
    const fs::path dir = temp_dir("up");
    const std::string capture = (dir / "capture.ply").string();
    ASSERT_EQ(tool("convert sphere " + capture + " --gaussians --splats 20000").code, 0);
    const CliRun info = tool("info " + capture);
    ASSERT_EQ(info.code, 0) << info.out;

    const double ply = red_on_top(auto_camera_png(capture, dir / "ply"));
    EXPECT_GT(ply, 20.0) << "upright";
    EXPECT_LT(red_on_top(auto_camera_png(capture, dir / "ply_up_y", "--up y ")), -20.0)
        << "--up y: the file taken as stored y up, so upside down";
    // The same capture from every Gaussian format, and from a scene with a lattice around it.
    for (const std::string out : {"c.spz", "c.compressed.ply", "c.glb"}) {
        const std::string path = (dir / out).string();
        ASSERT_EQ(tool("convert " + capture + " " + path).code, 0);
        EXPECT_NEAR(red_on_top(auto_camera_png(path, dir / ("r_" + out))), ply, 5.0) << out;
    }
    const std::string scene = (dir / "scene.glb").string();
    ASSERT_EQ(tool("convert " + capture + " " + scene + " --lattice fit:3").code, 0);
    EXPECT_GT(red_on_top(auto_camera_png(scene, dir / "scene")), 20.0) << "a scene of it (its own framing)";
    // The surface sphere it came from, through the same automatic camera: the same way up.
    EXPECT_GT(red_on_top(auto_camera_png("sphere", dir / "surface")), 20.0);
    // A bad --up is refused before any work.
    const CliRun bad = tool("--up q render " + capture + " --out " + (dir / "bad").string());
    EXPECT_EQ(bad.code, 2) << bad.out;
    EXPECT_TRUE(has(bad.out, "--up: expected -y")) << bad.out;
}

// Numbers a profiler can trust: the GPU track of a trace has no two slices that overlap without nesting
// (timer queries, no --sync), a baseline of another run is refused naming what differs, a Gaussian scene
// is not counted as surface splats, the usage line and the option text agree, and `deform --backend gpu`
// times the programs' compilation apart from the deformation.
TEST(SceneStory, ProfilerNumbersSayWhatTheyMeasured) {
    const fs::path dir = temp_dir("profile");
    const std::string trace = (dir / "trace.json").string(), base = (dir / "base.json").string();
    const CliRun run = tool("profile sphere --frames 6 --warmup 1 --trace " + trace + " --json " + base);
    ASSERT_EQ(run.code, 0) << run.out;
    nlohmann::json events;
    std::ifstream(trace) >> events;
    for (const int track : {1, 2}) {
        std::vector<std::pair<double, double>> slices;  // start, end in microseconds
        for (const auto& e : events["traceEvents"])
            if (e.value("ph", "") == "X" && e.value("tid", 0) == track)
                slices.emplace_back(e["ts"].get<double>(), e["ts"].get<double>() + e["dur"].get<double>());
        if (track == 2 && slices.empty()) continue;  // no GPU times on this machine
        std::sort(slices.begin(), slices.end(), [](const auto& a, const auto& b) {
            return a.first < b.first || (a.first == b.first && a.second > b.second);
        });
        std::vector<double> open;  // ends of the enclosing slices
        int crossing = 0;
        for (const auto& [start, end] : slices) {
            while (!open.empty() && open.back() <= start + 1e-3) open.pop_back();
            if (!open.empty() && end > open.back() + 1e-3) ++crossing;
            open.push_back(end);
        }
        EXPECT_EQ(crossing, 0) << "track " << track << ": slices that overlap without nesting";
    }

    const CliRun other = tool("profile sphere --quality preview --frames 2 --warmup 0 --compare " + base);
    EXPECT_EQ(other.code, 1) << other.out;
    EXPECT_TRUE(has(other.out, "splatffd profile: " + base +
                                   ": a baseline of another run: quality 'hq' (this run "
                                   "'preview')"))
        << other.out;
    const CliRun same = tool("profile sphere --frames 3 --warmup 1 --compare " + base);
    EXPECT_TRUE(same.code == 0 || same.code == 3) << same.out;
    EXPECT_FALSE(has(same.out, "a baseline of another run")) << same.out;

    const std::string g = (dir / "g.ply").string();
    ASSERT_EQ(tool("convert sphere " + g + " --gaussians --splats 3000").code, 0);
    const CliRun gaussians = tool("profile " + g + " --frames 2 --warmup 0");
    ASSERT_EQ(gaussians.code, 0) << gaussians.out;
    EXPECT_TRUE(has(gaussians.out, "points=0")) << gaussians.out;
    EXPECT_TRUE(has(gaussians.out, "gaussians=3000")) << gaussians.out;
    const CliRun scene_of_gaussians = tool("profile " + g + " --frames 2 --warmup 0 --compare " + base);
    EXPECT_EQ(scene_of_gaussians.code, 1) << scene_of_gaussians.out;
    EXPECT_TRUE(has(scene_of_gaussians.out, "scene 'sphere' (this run '" + g + "')"))
        << scene_of_gaussians.out;

    const CliRun help = tool("profile --help");
    EXPECT_TRUE(has(line_of(help.out, "[--backend"), "[--backend auto|cpu|gpu]")) << help.out;
    EXPECT_TRUE(has(help.out, "--backend auto|cpu|gpu  deformation backend")) << help.out;

    const CliRun gpu =
        tool("deform " + g + " " + (dir / "gd.ply").string() + " --lattice fit:3 --backend gpu");
    ASSERT_EQ(gpu.code, 0) << gpu.out;
    const auto at = gpu.out.find("deformation ");
    ASSERT_NE(at, std::string::npos) << gpu.out;
    EXPECT_TRUE(has(gpu.out, "GPU program set-up (shader compilation, first dispatch) ")) << gpu.out;
    // Surface splats, streamed and in memory, the same.
    const std::string splats = (dir / "s.ply").string();
    ASSERT_EQ(tool("convert sphere " + splats + " --splats 3000").code, 0);
    for (const std::string out : {"sd.ply", "sd.glb"}) {
        const CliRun d =
            tool("deform " + splats + " " + (dir / out).string() + " --lattice fit:3 --backend gpu");
        ASSERT_EQ(d.code, 0) << d.out;
        EXPECT_TRUE(has(d.out, "GPU program set-up (shader compilation, first dispatch) "))
            << out << ": " << d.out;
    }
}
