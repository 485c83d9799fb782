// `splatffd export` through the built binary: frame k is what `deform` writes for the scene saved at that
// clip time (byte for byte), every Gaussian format reads back within its quantisation, surface frames keep
// normals and splat axes, the manifest says what was written, shards add up to the whole, and bad input is
// refused with its message and exit code.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "runtime/app/clock.h"
#include "runtime/assets/import.h"
#include "runtime/assets/scene.h"
#include "runtime/scene/components.h"
#include "systems/animation/components.h"
#include "systems/animation/editing.h"
#include "systems/animation/evaluate.h"
#include "systems/animation/paper_demo.h"
#include "systems/engine/engine_frame.h"
#include "systems/gaussian/components.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "systems/gaussian/gaussian_read.h"
#include "tests/test_util/run_tool.h"
#include "tests/tools/splatffd/export_scenes.h"

namespace fs = std::filesystem;
using sffd::test::CliRun;

namespace {

fs::path temp_dir(const std::string& name) {
    const fs::path d = fs::temp_directory_path() / ("sffd_export_" + std::to_string(::getpid())) / name;
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

using sffd::test::export_scenes::gaussian_scene;
using sffd::test::export_scenes::kFps;
using sffd::test::export_scenes::save_at_frame;
using sffd::test::export_scenes::tool;
bool has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

std::string bytes_of(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), {});
}

// FNV-1a 64 of a file, written out here so the manifest's fingerprints are checked against an
// independent computation.
std::string fnv1a64(const fs::path& p) {
    std::uint64_t h = 14695981039346656037ull;
    for (unsigned char c : bytes_of(p)) h = (h ^ c) * 1099511628211ull;
    char s[17];
    std::snprintf(s, sizeof s, "%016llx", static_cast<unsigned long long>(h));
    return s;
}

const fs::path& shared_dir() {
    static const fs::path d = temp_dir("shared");
    return d;
}

std::string frame_name(long k, const std::string& ext) {
    char s[32];
    std::snprintf(s, sizeof s, "frame%04ld", k);
    return s + ext;
}

}  // namespace

// The definition of export: frame k is `deform` of the scene saved at frame k's clip time. Surface splats
// (PLY with its texture, GLB) and Gaussians (3DGS PLY, GLB), equal bytes.
TEST(Export, FrameKIsDeformOfTheSceneSavedAtThatClipTime) {
    const fs::path dir = temp_dir("equal");
    const long k = 40;  // inside the demo clip's local twist
    save_at_frame("sphere", dir / "sphere_at40.glb", k);
    const fs::path gs = gaussian_scene(shared_dir());
    save_at_frame(gs.string(), dir / "g_at40.glb", k);
    struct Case {
        std::string scene, saved, format, ext;
    };
    for (const Case& c :
         {Case{"sphere", "sphere_at40.glb", "ply", ".ply"}, Case{"sphere", "sphere_at40.glb", "glb", ".glb"},
          // The saved file itself: a Gaussian cloud embedded in a scene reads back with its
          // quaternions renormalised, so another file's cloud may differ in the last bits.
          Case{(dir / "g_at40.glb").string(), "g_at40.glb", "ply", ".ply"},
          Case{(dir / "g_at40.glb").string(), "g_at40.glb", "glb", ".glb"}}) {
        SCOPED_TRACE(c.scene + " " + c.format);
        const std::string tag = fs::path(c.saved).stem().string() + "_" + c.format;
        const fs::path ex = dir / ("ex_" + tag), de = dir / ("de_" + tag);
        fs::create_directories(de);
        CliRun r =
            tool("export " + c.scene + " --format " + c.format + " --frames 40:40 --out " + ex.string());
        ASSERT_EQ(r.code, 0) << r.out;
        // The same file name, so a PLY's TextureFile comment names the same side file.
        r = tool("deform " + (dir / c.saved).string() + " " + (de / frame_name(k, c.ext)).string());
        ASSERT_EQ(r.code, 0) << r.out;
        const std::string a = bytes_of(ex / frame_name(k, c.ext)), b = bytes_of(de / frame_name(k, c.ext));
        ASSERT_GT(a.size(), 1000u);
        EXPECT_TRUE(a == b) << "export and deform differ (" << a.size() << " vs " << b.size() << " bytes)";
        if (c.scene == "sphere" && c.format == "ply") {
            const std::string texture = frame_name(k, "_texture.png");
            EXPECT_TRUE(fs::exists(ex / texture));
            EXPECT_TRUE(bytes_of(ex / texture) == bytes_of(de / texture));
        }
    }
    // And the pose moves: frame 40 is not frame 0.
    const fs::path f0 = dir / "f0";
    ASSERT_EQ(tool("export sphere --format ply --frames 0:0 --out " + f0.string()).code, 0);
    EXPECT_FALSE(bytes_of(f0 / "frame0000.ply") == bytes_of(dir / "ex_sphere_at40_ply" / "frame0040.ply"));
}

// Frames past the clip's end follow its play mode: the demo clip loops every 96 frames, so frame 97 is
// frame 1 (to the rounding of the wrapped clip time) and not frame 0.
TEST(Export, FramesPastTheClipFollowItsPlayMode) {
    const fs::path dir = temp_dir("loop");
    for (const char* k : {"0", "1", "97"}) {
        const CliRun r = tool(std::string("export sphere --format ply --frames ") + k + ":" + k + " --out " +
                              (dir / k).string());
        ASSERT_EQ(r.code, 0) << r.out;
    }
    auto f0 = sffd::assets::import_splat_cloud(dir / "0" / "frame0000.ply");
    auto f1 = sffd::assets::import_splat_cloud(dir / "1" / "frame0001.ply");
    auto f97 = sffd::assets::import_splat_cloud(dir / "97" / "frame0097.ply");
    ASSERT_TRUE(f0 && f1 && f97);
    ASSERT_EQ(f97->size(), f1->size());
    float to_1 = 0.0f, to_0 = 0.0f;
    for (std::size_t i = 0; i < f1->size(); ++i) {
        to_1 = std::max(to_1, glm::length(f97->positions[i] - f1->positions[i]));
        to_0 = std::max(to_0, glm::length(f97->positions[i] - f0->positions[i]));
    }
    EXPECT_LT(to_1, 1e-5f);
    EXPECT_GT(to_0, 1e-4f);
}

// Each Gaussian format read back by our readers, against the exact 3DGS PLY frame, within the format's
// quantisation.
TEST(Export, EveryGaussianFormatReadsBackWithinItsQuantisation) {
    const fs::path dir = temp_dir("formats");
    const fs::path gs = gaussian_scene(shared_dir());
    const long k = 80;  // the global twist
    auto exported = [&](const std::string& format, const std::string& ext) {
        const fs::path out = dir / format;
        const CliRun r =
            tool("export " + gs.string() + " --format " + format + " --frames 80:80 --out " + out.string());
        EXPECT_EQ(r.code, 0) << r.out;
        auto g = sffd::gaussian::read_gaussians(out / frame_name(k, ext));
        EXPECT_TRUE(g) << g.message();
        return g ? *g : sffd::GaussianCloud{};
    };
    const sffd::GaussianCloud exact = exported("ply", ".ply");
    ASSERT_EQ(exact.size(), 6000u);
    struct Tolerance {
        std::string format, ext;
        double position, log_scale, opacity, dc;
    };
    // compressed PLY: 11/10-bit positions in each 256-splat chunk's bounds (the cloud's order, so chunks
    // are spread: up to its extent, 2.4, over 1023 steps); SPZ: 12 fractional bits, log scales in 1/16,
    // colours in 1/255 of 1/0.15; SOG: 16-bit positions in a log space, codebooks of 256 for log scales
    // and colours; GLB: float.
    for (const Tolerance& t :
         {Tolerance{"compressed-ply", ".compressed.ply", 2.4 / 1023.0, 0.1, 1.0 / 255.0, 0.02},
          Tolerance{"spz", ".spz", 1.0 / 4096.0, 1.0 / 32.0 + 1e-4, 1.0 / 255.0, 0.04},
          Tolerance{"sog", ".sog", 2e-4, 0.1, 1.0 / 255.0, 0.05},
          Tolerance{"glb", ".glb", 1e-6, 1e-6, 1e-6, 1e-6}}) {
        SCOPED_TRACE(t.format);
        const sffd::GaussianCloud g = exported(t.format, t.ext);
        ASSERT_EQ(g.size(), exact.size());
        double pos = 0, scale = 0, opacity = 0, dc = 0;
        for (std::size_t i = 0; i < g.size(); ++i) {
            const glm::dvec3 a = g.origin + glm::dvec3(g.positions[i]),
                             b = exact.origin + glm::dvec3(exact.positions[i]);
            pos = std::max(pos, glm::length(a - b));
            for (int c = 0; c < 3; ++c) {
                scale = std::max(
                    scale, std::abs(std::log(double(g.scales[i][c])) - std::log(double(exact.scales[i][c]))));
                dc = std::max(
                    dc,
                    double(std::abs(
                        g.sh[i * 3 * std::size_t(sffd::sh_coeffs(g.sh_degree)) + std::size_t(c)] -
                        exact.sh[i * 3 * std::size_t(sffd::sh_coeffs(exact.sh_degree)) + std::size_t(c)])));
            }
            opacity = std::max(opacity, double(std::abs(g.opacities[i] - exact.opacities[i])));
        }
        EXPECT_LE(pos, t.position * 1.5);
        EXPECT_LE(scale, t.log_scale);
        EXPECT_LE(opacity, t.opacity);
        EXPECT_LE(dc, t.dc);
    }
}

// Surface frames keep what a splat needs: PLY and GLB read back with normals and splat axes, deformed.
TEST(Export, SurfaceFramesReadBackWithNormalsAndAxes) {
    const fs::path dir = temp_dir("surface");
    for (const std::string format : {"ply", "glb"}) {
        SCOPED_TRACE(format);
        const fs::path out = dir / format;
        const CliRun r =
            tool("export sphere --format " + format + " --frames 0:0 --out " + out.string() + " && " +
                 std::string(SFFD_BINARY_DIR) + "/tools/splatffd export sphere --format " + format +
                 " --frames 84:84 --out " + out.string() + " --force");
        ASSERT_EQ(r.code, 0) << r.out;
        auto rest = sffd::assets::import_splat_cloud(out / ("frame0000." + format));
        auto twisted = sffd::assets::import_splat_cloud(out / ("frame0084." + format));
        ASSERT_TRUE(rest && twisted);
        ASSERT_EQ(twisted->size(), 59650u);
        ASSERT_EQ(twisted->normals.size(), twisted->size());
        ASSERT_EQ(twisted->axis_u.size(), twisted->size());
        ASSERT_EQ(twisted->axis_v.size(), twisted->size());
        // The global twist turns the normals and axes with the surface; each normal stays perpendicular to
        // its splat's axes (FFD's cofactor normals against J-mapped axes, to first order).
        std::size_t turned = 0;
        for (std::size_t i = 0; i < twisted->size(); ++i) {
            turned += glm::dot(rest->normals[i], twisted->normals[i]) < 0.99f;
            const glm::vec3 u = glm::normalize(twisted->axis_u[i]), v = glm::normalize(twisted->axis_v[i]);
            EXPECT_LT(std::abs(glm::dot(twisted->normals[i], u)), 1e-3f) << i;
            EXPECT_LT(std::abs(glm::dot(twisted->normals[i], v)), 1e-3f) << i;
            if (::testing::Test::HasFailure()) break;
        }
        EXPECT_GT(turned, twisted->size() / 4);
    }
}

// The manifest: frames, fps, the clip, the format, the scene, and fingerprints that match the files.
TEST(Export, ManifestSaysWhatWasWritten) {
    const fs::path dir = temp_dir("manifest");
    const fs::path gs = gaussian_scene(shared_dir());
    const fs::path out = dir / "out";
    const CliRun r =
        tool("export " + gs.string() + " --format spz --frames 3:6 --fps 30 --out " + out.string());
    ASSERT_EQ(r.code, 0) << r.out;
    const auto j = nlohmann::json::parse(bytes_of(out / "export_manifest.json"));
    EXPECT_EQ(j["state"], "complete");
    EXPECT_EQ(j["format"], "spz");
    EXPECT_EQ(j["fps"], 30.0);
    EXPECT_EQ(j["first"], 3);
    EXPECT_EQ(j["last"], 6);
    EXPECT_EQ(j["scene"]["path"], gs.string());
    EXPECT_EQ(j["scene"]["fnv1a64"], fnv1a64(gs));
    EXPECT_EQ(j["scene"]["bytes"], fs::file_size(gs));
    EXPECT_EQ(j["cloud"]["kind"], "gaussians");
    EXPECT_EQ(j["cloud"]["count"], 6000);
    ASSERT_EQ(j["clips"].size(), 1u);
    EXPECT_EQ(j["clips"][0]["clip"]["name"], "paper demo");
    EXPECT_EQ(j["clips"][0]["clip"]["duration"], 4.0);
    EXPECT_EQ(j["clips"][0]["clip"]["mode"], "loop");
    ASSERT_EQ(j["files"].size(), 4u);
    std::set<std::string> listed;
    for (std::size_t i = 0; i < 4; ++i) {
        const auto& f = j["files"][i];
        EXPECT_EQ(f["frame"], 3 + long(i));
        EXPECT_DOUBLE_EQ(f["time"].get<double>(), double(3 + long(i)) / 30.0);
        const std::string name = f["file"]["file"];
        EXPECT_EQ(name, frame_name(3 + long(i), ".spz"));
        EXPECT_EQ(f["file"]["fnv1a64"], fnv1a64(out / name));
        EXPECT_EQ(f["file"]["bytes"], fs::file_size(out / name));
        listed.insert(name);
    }
    std::set<std::string> on_disk;
    for (const auto& e : fs::directory_iterator(out)) on_disk.insert(e.path().filename().string());
    listed.insert("export_manifest.json");
    EXPECT_EQ(on_disk, listed);
}

// Shards into one folder, in any order, add up to the single run's files, byte for byte.
TEST(Export, ShardsAddUpToTheWhole) {
    const fs::path dir = temp_dir("shards");
    const fs::path whole = dir / "whole", sharded = dir / "sharded";
    ASSERT_EQ(tool("export sphere --format ply --frames 0:6 --out " + whole.string()).code, 0);
    for (const char* s : {"2/3", "0/3", "1/3"}) {
        const CliRun r =
            tool("export sphere --format ply --frames 0:6 --out " + sharded.string() + " --shard " + s);
        ASSERT_EQ(r.code, 0) << r.out;
    }
    std::set<std::string> frames;
    for (long k = 0; k <= 6; ++k) {
        const std::string name = frame_name(k, ".ply");
        EXPECT_TRUE(bytes_of(whole / name) == bytes_of(sharded / name)) << name;
        frames.insert(name);
    }
    long listed = 0;
    for (int s = 0; s < 3; ++s) {
        const auto j = nlohmann::json::parse(
            bytes_of(sharded / ("export_manifest.shard-" + std::to_string(s) + "-of-3.json")));
        EXPECT_EQ(j["state"], "complete");
        for (const auto& f : j["files"]) {
            EXPECT_EQ(f["frame"].get<long>() % 3, s);
            EXPECT_EQ(frames.count(f["file"]["file"].get<std::string>()), 1u);
            ++listed;
        }
    }
    EXPECT_EQ(listed, 7);
}

// Bad input: each refusal's message and exit code.
TEST(Export, RefusalsSayWhatIsWrong) {
    const fs::path dir = temp_dir("refusals");
    const fs::path g = shared_dir() / "g.ply", fitted = shared_dir() / "g_fit.glb";
    (void)gaussian_scene(shared_dir());

    CliRun r = tool("export " + g.string() + " --format ply --out " + (dir / "a").string());
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_TRUE(
        has(r.out, "splatffd export: " + g.string() + ": no lattice bound to the cloud; nothing to export"))
        << r.out;

    // A scene without a clip: one frame, its saved pose; more are refused.
    r = tool("export " + fitted.string() + " --format ply --frames 0:3 --out " + (dir / "b").string());
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_TRUE(has(r.out, "no clip on the lattice 'g.lattice': every frame would be the saved pose"))
        << r.out;
    r = tool("export " + fitted.string() + " --format ply --out " + (dir / "c").string());
    EXPECT_EQ(r.code, 0) << r.out;
    EXPECT_TRUE(has(r.out, "has no clip: frame 0 is the pose as saved")) << r.out;
    EXPECT_TRUE(fs::exists(dir / "c" / "frame0000.ply"));
    EXPECT_FALSE(fs::exists(dir / "c" / "frame0001.ply"));

    // A clip without keys: exported with a warning, every frame the rest pose.
    save_at_frame(fitted.string(), dir / "empty.glb", 0, false, true);
    r = tool("export " + (dir / "empty.glb").string() + " --format ply --frames 0:2 --out " +
             (dir / "d").string());
    EXPECT_EQ(r.code, 0) << r.out;
    EXPECT_TRUE(has(r.out, "warning: " + (dir / "empty.glb").string() +
                               ": the clip has no keys: every frame is the rest pose"))
        << r.out;
    ASSERT_EQ(tool("deform " + (dir / "empty.glb").string() + " " + (dir / "empty_rest.ply").string()).code,
              0);
    for (const char* f : {"frame0000.ply", "frame0001.ply", "frame0002.ply"})
        EXPECT_TRUE(bytes_of(dir / "d" / f) == bytes_of(dir / "empty_rest.ply")) << f;

    // The output folder: other files, then an earlier export's frames, each only with --force.
    fs::create_directories(dir / "e");
    std::ofstream(dir / "e" / "notes.txt") << "mine";
    r = tool("export sphere --format ply --frames 0:1 --out " + (dir / "e").string());
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_TRUE(has(r.out, (dir / "e").string() + ": holds 1 other files (e.g. 'notes.txt'); export into an "
                                                  "empty folder, or pass --force"))
        << r.out;
    EXPECT_FALSE(fs::exists(dir / "e" / "frame0000.ply"));
    r = tool("export sphere --format ply --frames 0:1 --out " + (dir / "e").string() + " --force");
    EXPECT_EQ(r.code, 0) << r.out;
    EXPECT_EQ(bytes_of(dir / "e" / "notes.txt"), "mine");
    fs::remove(dir / "e" / "notes.txt");
    r = tool("export sphere --format ply --frames 0:1 --out " + (dir / "e").string());
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_TRUE(has(r.out, "files of an earlier export (e.g. '")) << r.out;
    EXPECT_TRUE(has(r.out, "pass --force to overwrite them")) << r.out;

    r = tool("export sphere --format obj --out " + (dir / "f").string());
    EXPECT_EQ(r.code, 2) << r.out;
    EXPECT_TRUE(
        has(r.out, "splatffd export: --format expects ply, compressed-ply, sog, spz or glb, got 'obj'"))
        << r.out;

    r = tool("export sphere --format spz --out " + (dir / "g").string());
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_TRUE(has(
        r.out, "is surface splats; --format spz is for 3D Gaussians: surface splats export as ply or glb"))
        << r.out;
    EXPECT_FALSE(fs::exists(dir / "g"));

    r = tool("export sphere --out " + (dir / "h").string());
    EXPECT_EQ(r.code, 2) << r.out;
    EXPECT_TRUE(has(r.out, "--format is required")) << r.out;

    // --web goes to the web player, whatever else is on the line: its own refusal of surface splats.
    r = tool("export sphere --web " + (dir / "web").string());
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_TRUE(has(r.out, "the web player plays 3D Gaussians only")) << r.out;

    r = tool("export --help");
    EXPECT_EQ(r.code, 0);
    EXPECT_TRUE(has(r.out, "usage: splatffd export SCENE")) << r.out;
    EXPECT_TRUE(has(r.out, "its play mode decides")) << r.out;
    EXPECT_TRUE(has(r.out, "--web DIR")) << r.out;
}
