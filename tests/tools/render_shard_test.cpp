// `splatffd render --shard K/N` and `splatffd assemble` end to end (the built binary, headless), and the
// manifest's own rules (tools/splatffd/render_manifest.h) without GL.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "runtime/simd/simd.h"
#include "tests/test_util/run_tool.h"
#include "tools/splatffd/render_manifest.h"

namespace fs = std::filesystem;
using sffd::cli::FrameSequence;
using sffd::cli::RunRecord;
using sffd::cli::Shard;

namespace {

// Small preview frames: the tests are about which files are written, not how they look.
const std::string kClip = " --size 32x18 --quality preview --format png";

int render(const std::string& args, std::string* log = nullptr) {
    const sffd::test::CliRun r = sffd::test::run_headless("render " + args);
    if (log) *log = r.out;
    return r.code;
}

int assemble(const fs::path& dir, std::string* log) {
    const sffd::test::CliRun r = sffd::test::run("assemble " + dir.string());
    *log = r.out;
    return r.code;
}

fs::path fresh_dir(const std::string& name) {
    const fs::path d = fs::temp_directory_path() / ("sffd_farm_" + std::to_string(::getpid())) / name;
    fs::remove_all(d);
    return d;
}

std::string slurp(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), {});
}

nlohmann::json manifest(const fs::path& p) { return nlohmann::json::parse(slurp(p)); }

}  // namespace

TEST(RenderShard, SequenceIsInterleavedAndCoversTheClipOnce) {
    // Frames 3..12 in 4 shards: 3,7,11 / 4,8,12 / 5,9 / 6,10.
    const FrameSequence s0 = sffd::cli::shard_frames(3, 12, Shard{0, 4});
    EXPECT_EQ(s0.first, 3);
    EXPECT_EQ(s0.step, 4);
    EXPECT_EQ(s0.count, 3);
    EXPECT_EQ(sffd::cli::shard_frames(3, 12, Shard{3, 4}).count, 2);
    int seen[13] = {};
    for (long k = 0; k < 4; ++k) {
        const FrameSequence s = sffd::cli::shard_frames(3, 12, Shard{k, 4});
        for (long i = 0; i < s.count; ++i) ++seen[s.at(i)];
    }
    for (int f = 3; f <= 12; ++f) EXPECT_EQ(seen[f], 1) << f;
    // More shards than frames: the extra shards have nothing to do.
    EXPECT_EQ(sffd::cli::shard_frames(0, 1, Shard{5, 8}).count, 0);
    EXPECT_FALSE(sffd::cli::parse_shard("4/4").ok());
    EXPECT_FALSE(sffd::cli::parse_shard("1/0").ok());
    EXPECT_FALSE(sffd::cli::parse_shard("2").ok());
    ASSERT_TRUE(sffd::cli::parse_shard("3/4").ok());
    EXPECT_EQ(sffd::cli::parse_shard("3/4")->index, 3);
}

// The running manifest is rewritten after every frame: its size must not grow with the frames written
// (it used to list them all, which made a long clip quadratic).
TEST(RenderShard, RunningManifestHasTheSameSizeAfterOneFrameAndAfterAMillion) {
    RunRecord r;
    r.settings = {{"first", 0}, {"last", 9'999'999}, {"formats", "png"}, {"fps", 24.0}};
    r.frames = FrameSequence{0, 1, 10'000'000};
    r.written = 1;
    const std::size_t one = sffd::cli::to_json(r).dump().size();
    r.written = 1'000'000;
    const std::size_t million = sffd::cli::to_json(r).dump().size();
    EXPECT_LE(million, one + 12);  // only the digits of the two counts change
    EXPECT_FALSE(sffd::cli::to_json(r).contains("files"));
    // Invalid UTF-8 (a file name from a hostile folder) is replaced, never an exception.
    r.command = "splatffd render \xff\xfe.ply";
    EXPECT_NO_THROW(
        (void)sffd::cli::to_json(r).dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace));
}

TEST(RenderShard, ShardsWriteTheSameBytesAsOneRunAndAssemble) {
    const fs::path one = fresh_dir("one"), farm = fresh_dir("farm");
    std::string log;
    ASSERT_EQ(render("sphere --out " + one.string() + " --frames 2:6" + kClip, &log), 0) << log;
    ASSERT_EQ(render("sphere --out " + farm.string() + " --frames 2:6 --shard 1/2" + kClip, &log), 0) << log;
    // Shard 1 of 2 has frames 3 and 5 only, and a manifest of its own.
    EXPECT_TRUE(fs::exists(farm / "frame_0003.png"));
    EXPECT_FALSE(fs::exists(farm / "frame_0002.png"));
    EXPECT_FALSE(fs::exists(farm / "render_manifest.json"));
    const nlohmann::json m = manifest(farm / "render_manifest.shard-1-of-2.json");
    EXPECT_EQ(m["state"], "complete");
    EXPECT_EQ(m["frames"]["first"], 3);
    EXPECT_EQ(m["frames"]["step"], 2);
    EXPECT_EQ(m["frames_written"]["count"], 2);
    EXPECT_EQ(m["frames_written"]["last"], 5);
    ASSERT_EQ(m["files"].size(), 2u);
    EXPECT_NE(m["command"].get<std::string>().find("--shard 1/2"), std::string::npos);
    // Before every shard is in, assemble names the missing one and the command that renders it.
    EXPECT_EQ(assemble(farm, &log), 1) << log;
    EXPECT_NE(log.find("shard 0/2: no manifest"), std::string::npos) << log;
    EXPECT_NE(log.find("re-render it with: splatffd render sphere --out " + farm.string() +
                       " --frames 2:6 --shard 0/2"),
              std::string::npos)
        << log;
    EXPECT_FALSE(fs::exists(farm / "render_manifest.json"));
    ASSERT_EQ(render("sphere --out " + farm.string() + " --frames 2:6 --shard 0/2" + kClip, &log), 0) << log;
    ASSERT_EQ(assemble(farm, &log), 0) << log;
    for (int k = 2; k <= 6; ++k) {
        const std::string name = "frame_000" + std::to_string(k) + ".png";
        EXPECT_EQ(slurp(one / name), slurp(farm / name)) << name;
    }
    const nlohmann::json whole = manifest(farm / "render_manifest.json");
    EXPECT_EQ(whole["state"], "complete");
    EXPECT_EQ(whole["frames_written"]["count"], 5);
    EXPECT_EQ(whole["settings"], manifest(one / "render_manifest.json")["settings"]);
    EXPECT_EQ(whole["files"],
              manifest(one / "render_manifest.json")["files"]);  // same bytes, same fingerprints
}

// A hierarchy on a farm: every frame waits for its own cut, so a shard (its loader having held other
// pieces before, and evicted under a memory budget smaller than the turntable's whole set) writes the
// same bytes as one run of every frame.
TEST(RenderShard, HierarchyShardsWriteTheSameBytesAsOneRun) {
    const fs::path data = fresh_dir("lod_data"), one = fresh_dir("lod_one"), farm = fresh_dir("lod_farm");
    const sffd::test::CliRun conv = sffd::test::run(
        "convert synthetic-gaussians:40k " + (data / "lod-meta.json").string() + " --lod-chunk-count 2");
    ASSERT_EQ(conv.code, 0) << conv.out;
    const std::string scene = (data / "lod-meta.json").string();
    // HQ: the preview's discs drop Gaussians this small.
    const std::string lod =
        " --turntable 4 --splat-budget 12000 --lod-error 0.5 --memory-budget 1 --size 64x36 --format png";
    std::string log;
    ASSERT_EQ(render(scene + " --out " + one.string() + lod, &log), 0) << log;
    for (int k = 0; k < 2; ++k)
        ASSERT_EQ(
            render(scene + " --out " + farm.string() + lod + " --shard " + std::to_string(k) + "/2", &log), 0)
            << log;
    ASSERT_EQ(assemble(farm, &log), 0) << log;
    for (int k = 0; k < 4; ++k) {
        const std::string name = "frame_000" + std::to_string(k) + ".png";
        ASSERT_TRUE(fs::exists(one / name)) << name;
        EXPECT_EQ(slurp(one / name), slurp(farm / name)) << name;
    }
    // The turntable's frames differ: the cut follows the camera.
    EXPECT_NE(slurp(one / "frame_0000.png"), slurp(one / "frame_0001.png"));
}

// A cut that does not fit the memory budget would be drawn only in part, as far as it fits at that moment,
// so its bytes would depend on the loader's timing: render refuses it, naming the file and the budget,
// and writes no image. (Here the first cut, at full detail, is already over; a later frame's cut over the
// budget is refused the same way: LodStream.WaitedCutOverTheMemoryBudgetIsReportedToTheCaller.)
TEST(RenderShard, AHierarchyCutOverTheMemoryBudgetIsRefused) {
    const fs::path data = fresh_dir("lod_over_data"), out = fresh_dir("lod_over_out");
    const sffd::test::CliRun conv = sffd::test::run(
        "convert synthetic-gaussians:40k " + (data / "lod-meta.json").string() + " --lod-chunk-count 2");
    ASSERT_EQ(conv.code, 0) << conv.out;
    std::string log;
    // Full detail: 40k Gaussians, about 2 MB decoded.
    EXPECT_NE(render((data / "lod-meta.json").string() + " --out " + out.string() +
                         " --memory-budget 1 --size 64x36 --format png",
                     &log),
              0)
        << log;
    EXPECT_NE(log.find("splatffd render: " + (data / "lod-meta.json").string() + ": the cut of 40000 splats"),
              std::string::npos)
        << log;
    EXPECT_NE(log.find("more than the memory budget of 1.0 MB"), std::string::npos) << log;
    EXPECT_FALSE(fs::exists(out / "frame_0000.png"));
}

// A farm of mixed CPUs: shards pinned to one SIMD target are byte-identical to a single run pinned the same,
// the manifests say which target and GL renderer made them, and assemble warns (naming the frames) when a
// shard ran on another target, though the clip is still whole.
TEST(RenderShard, ShardsPinnedToOneSimdTargetMatchAndMixedTargetsAreNamed) {
    const std::string portable = sffd::simd::runnable().back().name,
                      best = sffd::simd::runnable().front().name;
    const fs::path one = fresh_dir("pinned_one"), farm = fresh_dir("pinned_farm");
    auto pinned = [](const std::string& target, const std::string& args, std::string* log) {
        const sffd::test::CliRun r =
            sffd::test::run_command("env -u DISPLAY -u WAYLAND_DISPLAY SFFD_SIMD=" + target + " " +
                                    std::string(SFFD_BINARY_DIR) + "/tools/splatffd render " + args);
        *log = r.out;
        return r.code;
    };
    std::string log;
    const std::string clip = " --frames 80:83" + kClip;  // the twist: the CPU kernels move every splat
    ASSERT_EQ(pinned(portable, "sphere --out " + one.string() + clip, &log), 0) << log;
    for (int k = 0; k < 2; ++k)
        ASSERT_EQ(
            pinned(portable, "sphere --out " + farm.string() + clip + " --shard " + std::to_string(k) + "/2",
                   &log),
            0)
            << log;
    ASSERT_EQ(assemble(farm, &log), 0) << log;
    EXPECT_EQ(log.find("warning"), std::string::npos) << log;
    for (int k = 80; k <= 83; ++k) {
        const std::string name = "frame_00" + std::to_string(k) + ".png";
        EXPECT_EQ(slurp(one / name), slurp(farm / name)) << name;
    }
    const nlohmann::json m = manifest(farm / "render_manifest.shard-1-of-2.json");
    EXPECT_EQ(m["machine"]["simd"], portable);
    EXPECT_FALSE(m["machine"]["gl_renderer"].get<std::string>().empty());
    if (best == portable) GTEST_SKIP() << "this CPU runs one SIMD target only: no mixed farm to assemble";
    ASSERT_EQ(pinned(best, "sphere --out " + farm.string() + clip + " --shard 1/2", &log), 0) << log;
    ASSERT_EQ(assemble(farm, &log), 0) << log;
    EXPECT_NE(log.find("warning: the shards of frames 80..83 ran on 2 different machines"), std::string::npos)
        << log;
    EXPECT_NE(log.find("shard 0/2 (frames 80, 82): simd " + portable + ", GL renderer "), std::string::npos)
        << log;
    EXPECT_NE(log.find("shard 1/2 (frames 81, 83): simd " + best + ", GL renderer "), std::string::npos)
        << log;
}

TEST(RenderShard, AssembleRefusesOtherSettingsFailedShardsAndForeignFrames) {
    const fs::path farm = fresh_dir("mixed");
    std::string log;
    ASSERT_EQ(render("sphere --out " + farm.string() + " --frames 0:3 --shard 0/2" + kClip, &log), 0) << log;
    // Shard 1 rendered with another size: not part of the same clip.
    ASSERT_EQ(render("sphere --out " + farm.string() +
                         " --frames 0:3 --shard 1/2 --size 48x27 --quality preview --format png",
                     &log),
              0)
        << log;
    EXPECT_EQ(assemble(farm, &log), 1) << log;
    EXPECT_NE(
        log.find("render_manifest.shard-1-of-2.json: settings differ from render_manifest.shard-0-of-2.json"),
        std::string::npos)
        << log;
    // The odd shard is named with what differs, and re-rendered with the kept settings (shard 0's on a tie),
    // not with its own.
    EXPECT_NE(log.find("settings differ from render_manifest.shard-0-of-2.json (size 48x27 against 32x18)"),
              std::string::npos)
        << log;
    EXPECT_NE(log.find("re-render it with: splatffd render sphere --out " + farm.string() +
                       " --frames 0:3 --shard 1/2 --size 32x18"),
              std::string::npos)
        << log;
    // Shard 1 again with the right settings, but frame 3's name is taken by a folder: the shard fails.
    fs::remove(farm / "frame_0003.png");
    fs::create_directories(farm / "frame_0003.png");
    EXPECT_EQ(render("sphere --out " + farm.string() + " --frames 0:3 --shard 1/2" + kClip, &log), 1) << log;
    EXPECT_EQ(manifest(farm / "render_manifest.shard-1-of-2.json")["state"], "failed");
    EXPECT_EQ(assemble(farm, &log), 1) << log;
    EXPECT_NE(log.find("shard 1/2: failed after 1 of 2 frames; re-render it with: splatffd render sphere"),
              std::string::npos)
        << log;
    fs::remove(farm / "frame_0003.png");
    ASSERT_EQ(render("sphere --out " + farm.string() + " --frames 0:3 --shard 1/2" + kClip, &log), 0) << log;
    ASSERT_EQ(assemble(farm, &log), 0) << log;
    // Another run's files in the folder: a frame outside the clip, and a frame of the clip overwritten.
    fs::copy_file(farm / "frame_0000.png", farm / "frame_0050.png");
    fs::copy_file(farm / "frame_0000.png", farm / "frame_0002.png", fs::copy_options::overwrite_existing);
    EXPECT_EQ(assemble(farm, &log), 1) << log;
    EXPECT_NE(log.find("frame_0050.png: not a frame of this clip (frames 0..3, png)"), std::string::npos)
        << log;
    EXPECT_NE(log.find("frame_0002.png: not the bytes shard 0/2 wrote"), std::string::npos) << log;
}

// With three shards, the settings two of them share are kept, even when shard 0 is the odd one.
TEST(RenderShard, AssembleKeepsTheMajoritysSettings) {
    const fs::path farm = fresh_dir("majority");
    std::string log;
    ASSERT_EQ(render("sphere --out " + farm.string() +
                         " --frames 0:2 --shard 0/3 --size 40x20 --quality preview --format png",
                     &log),
              0)
        << log;
    for (int k = 1; k < 3; ++k)
        ASSERT_EQ(render("sphere --out " + farm.string() + " --frames 0:2 --shard " + std::to_string(k) +
                             "/3" + kClip,
                         &log),
                  0)
            << log;
    EXPECT_EQ(assemble(farm, &log), 1) << log;
    EXPECT_NE(
        log.find("render_manifest.shard-0-of-3.json: settings differ from render_manifest.shard-1-of-3.json "
                 "(size 40x20 against 32x18)"),
        std::string::npos)
        << log;
    EXPECT_NE(log.find("re-render it with: splatffd render sphere --out " + farm.string() +
                       " --frames 0:2 --shard 0/3 --size 32x18"),
              std::string::npos)
        << log;
    EXPECT_EQ(log.find("shard-1-of-3.json: settings differ"), std::string::npos) << log;
}

TEST(RenderShard, BadShardOptionsAreRefused) {
    std::string log;
    EXPECT_EQ(render("sphere --out /tmp/x --shard 2/2", &log), 2);
    EXPECT_NE(log.find("--shard: expected an integer in 0..1, got '2'"), std::string::npos) << log;
    EXPECT_EQ(render("sphere --out /tmp/x --shard a/b", &log), 2);
    EXPECT_EQ(render("sphere --out /tmp/x --shard 0/2 --video /tmp/x.mp4", &log), 2);
    EXPECT_NE(log.find("--video cannot be combined with --shard"), std::string::npos) << log;
    const fs::path empty = fresh_dir("empty");
    fs::create_directories(empty);
    EXPECT_EQ(assemble(empty, &log), 1);
    EXPECT_NE(log.find("no shard manifests"), std::string::npos) << log;
}

// A range whose output cannot fit the free disk space is refused before the first frame (it used to be
// accepted and rendered until the disk was full).
TEST(RenderShard, RangeLargerThanTheFreeDiskSpaceIsRefusedUpFront) {
    const fs::path out = fresh_dir("huge");
    std::string log;
    EXPECT_EQ(render("sphere --out " + out.string() + " --frames 0:99999999 --size 1280x720", &log), 1)
        << log;
    EXPECT_NE(log.find(out.string() + ": 100000000 frames need about"), std::string::npos) << log;
    EXPECT_NE(log.find("free; render fewer frames"), std::string::npos) << log;
    EXPECT_FALSE(fs::exists(out / "frame_0000.png"));
}
