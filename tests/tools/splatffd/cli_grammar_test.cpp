// The one grammar of every `splatffd` command, through the built binary as a user meets it: `--help` on
// stdout with exit 0, usage errors on stderr with exit 2, every option of the usage line described (and
// every described option in the usage line), one meaning of --frames, old option spellings that still
// work and say their new name, progress only on a terminal, and profile saying what it runs.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "tests/test_util/run_tool.h"

namespace fs = std::filesystem;

namespace {

const std::string exe = std::string(SFFD_BINARY_DIR) + "/tools/splatffd";
const char* const all_commands[] = {"view",    "render", "reference", "compare", "deform",
                                    "profile", "pick",   "convert",   "info",    "fetch"};

fs::path temp_dir(const std::string& name) {
    const fs::path d = fs::temp_directory_path() / ("sffd_cli_grammar_" + std::to_string(::getpid())) / name;
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

std::string read(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

// stdout and stderr apart (run_command joins them), without a display.
struct Split {
    int code = -1;
    std::string out, err;
};
Split run_split(const std::string& args, const std::string& name) {
    const fs::path dir = temp_dir("split_" + name);
    const std::string cmd = "env -u DISPLAY -u WAYLAND_DISPLAY " + exe + " " + args + " >" +
                            (dir / "out").string() + " 2>" + (dir / "err").string();
    Split s;
    s.code = sffd::test::run_shell(cmd);
    s.out = read(dir / "out");
    s.err = read(dir / "err");
    return s;
}

std::set<std::string> flags_in(const std::string& text) {
    std::set<std::string> out;
    const std::regex flag("--[a-z][a-z-]*");
    for (auto it = std::sregex_iterator(text.begin(), text.end(), flag); it != std::sregex_iterator(); ++it)
        out.insert(it->str());
    return out;
}

}  // namespace

TEST(CliGrammar, HelpGoesToStdoutAndExitsZero) {
    for (const char* c : all_commands) {
        for (const char* h : {"--help", "-h"}) {
            const Split s = run_split(std::string(c) + " " + h, std::string(c) + h);
            EXPECT_EQ(s.code, 0) << c << " " << h << "\n" << s.err;
            EXPECT_EQ(s.out.rfind("usage: splatffd " + std::string(c), 0), 0u)
                << c << " " << h << " printed on stdout:\n"
                << s.out;
            EXPECT_EQ(s.err, "") << c << " " << h;
        }
    }
    const Split top = run_split("--help", "top");
    EXPECT_EQ(top.code, 0);
    EXPECT_NE(top.out.find("usage: splatffd <command>"), std::string::npos);
}

TEST(CliGrammar, UsageErrorsGoToStderrAndExitTwo) {
    for (const char* c :
         {"view", "render", "reference", "compare", "deform", "profile", "pick", "convert", "fetch"}) {
        const Split s = run_split(std::string(c) + " --no-such-option", std::string(c) + "_bad");
        EXPECT_EQ(s.code, 2) << c << "\n" << s.err;
        EXPECT_EQ(s.out, "") << c;
        EXPECT_NE(s.err.find("splatffd " + std::string(c) + ": "), std::string::npos) << c << "\n" << s.err;
        EXPECT_NE(s.err.find("--no-such-option"), std::string::npos) << c << "\n" << s.err;
    }
    const Split info = run_split("info", "info_none");
    EXPECT_EQ(info.code, 2);
    EXPECT_NE(info.err.find("usage: splatffd info"), std::string::npos) << info.err;
    const Split bare = run_split("", "bare");
    EXPECT_EQ(bare.code, 2);
    EXPECT_EQ(bare.out, "");
}

// The synopsis (the "usage:" line and its continuation lines) names every option the description lines
// describe, and every option of the synopsis is described below it.
TEST(CliGrammar, EveryOptionInTheUsageLineIsDescribedAndViceVersa) {
    for (const char* c : all_commands) {
        const Split s = run_split(std::string(c) + " --help", std::string(c) + "_synopsis");
        ASSERT_EQ(s.code, 0) << c;
        std::istringstream lines(s.out);
        std::string line, synopsis, described_text;
        std::set<std::string> described;
        bool in_synopsis = true;
        while (std::getline(lines, line)) {
            // Description lines start with two spaces and then text; synopsis continuations are indented
            // deeper.
            if (in_synopsis && line.size() > 2 && line.rfind("  ", 0) == 0 && line[2] != ' ')
                in_synopsis = false;
            if (in_synopsis) {
                synopsis += line + "\n";
                continue;
            }
            described_text += line + "\n";
            static const std::regex leading("^  (--[a-z][a-z-]*)");
            std::smatch m;
            if (std::regex_search(line, m, leading)) described.insert(m[1]);
        }
        const std::set<std::string> in_synopsis_flags = flags_in(synopsis),
                                    described_anywhere = flags_in(described_text);
        for (const std::string& f : in_synopsis_flags)
            EXPECT_TRUE(described_anywhere.count(f))
                << "splatffd " << c << ": " << f << " is in the usage line but not described\n"
                << s.out;
        for (const std::string& f : described)
            EXPECT_TRUE(in_synopsis_flags.count(f))
                << "splatffd " << c << ": " << f << " is described but not in the usage line\n"
                << s.out;
    }
}

TEST(CliGrammar, RenderHelpNamesItsCameraTurntableVideoAndFormats) {
    const Split s = run_split("render --help", "render_help");
    for (const char* want : {"--camera", "--turntable", "--video", ".spz", ".splat", ".obj", "clips play"})
        EXPECT_NE(s.out.find(want), std::string::npos) << want << "\n" << s.out;
}

// --frames N is the frames 0..N-1 in every command; A:B is a range; a bad value names the option.
TEST(CliGrammar, FramesMeansTheSameInEveryCommand) {
    const fs::path out = temp_dir("frames3");
    const auto r = sffd::test::run_headless(
        "render sphere --frames 3 --size 32x18 --format png --quality preview --out " + out.string());
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_TRUE(fs::exists(out / "frame_0000.png"));
    EXPECT_TRUE(fs::exists(out / "frame_0002.png"));
    EXPECT_FALSE(fs::exists(out / "frame_0003.png"));
    const auto range = sffd::test::run_headless(
        "render sphere --frames 5:6 --size 32x18 --format png --quality preview --out " +
        (out / "range").string());
    ASSERT_EQ(range.code, 0) << range.out;
    EXPECT_TRUE(fs::exists(out / "range" / "frame_0005.png"));
    EXPECT_TRUE(fs::exists(out / "range" / "frame_0006.png"));
    EXPECT_FALSE(fs::exists(out / "range" / "frame_0004.png"));

    for (const std::string& cmd :
         {"render sphere --out " + (out / "bad").string(), std::string("view --headless"),
          std::string("profile synthetic:2k --backend cpu")}) {
        const auto bad = sffd::test::run_headless(cmd + " --frames 0");
        EXPECT_EQ(bad.code, 2) << cmd << "\n" << bad.out;
        EXPECT_NE(bad.out.find("--frames: expected an integer N (frames 0..N-1) or a range A:B"),
                  std::string::npos)
            << cmd << "\n"
            << bad.out;
    }
    // The editor and the profiler start at frame 0: a range that does not is refused, saying so.
    const auto view = sffd::test::run_headless("view --headless --frames 2:5");
    EXPECT_EQ(view.code, 2);
    EXPECT_NE(view.out.find("starts at frame 0"), std::string::npos) << view.out;
    const auto profile = sffd::test::run_headless("profile synthetic:2k --backend cpu --frames 3:4");
    EXPECT_EQ(profile.code, 2);
    EXPECT_NE(profile.out.find("starts at frame 0"), std::string::npos) << profile.out;
}

// profile says how many frames it runs, warm-up included, and its config line names the rasterisers.
TEST(CliGrammar, ProfileSaysWhatItRuns) {
    const auto r = sffd::test::run_headless(
        "profile synthetic:2k --frames 0:3 --warmup 2 --quality preview --raster compute --sprite-raster "
        "cpu");
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_NE(r.out.find("2 warm-up + 4 measured frames (6 in all)"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find(" raster=compute"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find(" sprite_raster=cpu"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find(" frames=4"), std::string::npos) << r.out;
}

// The sprite rasteriser is auto, raster or cpu, for the editor and the profiler alike.
TEST(CliGrammar, SpriteRasterTakesAutoRasterOrCpu) {
    const auto view = sffd::test::run_headless("view --headless --frames 2 --sprite-raster gpu");
    EXPECT_EQ(view.code, 2) << view.out;
    EXPECT_NE(view.out.find("--sprite-raster takes auto, raster or cpu"), std::string::npos) << view.out;
    const auto profile = sffd::test::run_headless("profile synthetic:2k --frames 2 --sprite-raster");
    EXPECT_EQ(profile.code, 2) << profile.out;
    EXPECT_NE(profile.out.find("--sprite-raster auto|raster|cpu"), std::string::npos) << profile.out;
}

// Progress rewrites a line with \r on a terminal; a log file gets the result line and no \r.
TEST(CliGrammar, RenderProgressOnlyOnATerminal) {
    const fs::path dir = temp_dir("progress");
    const fs::path log = dir / "log.txt";
    const std::string args = "render sphere --frames 0:2 --size 32x18 --format png --quality preview --out " +
                             (dir / "frames").string();
    ASSERT_EQ(
        sffd::test::run_shell("env -u DISPLAY -u WAYLAND_DISPLAY " + exe + " " + args + " 2>" + log.string()),
        0);
    const std::string text = read(log);
    EXPECT_EQ(text.find('\r'), std::string::npos) << text;
    EXPECT_NE(text.find("wrote frames 0..2 to"), std::string::npos) << text;
    // Under a pseudo-terminal (script(1)) the same command shows its progress line.
    if (sffd::test::run_shell("command -v script >/dev/null 2>&1") != 0)
        GTEST_SKIP() << "script(1) is not installed";
    const fs::path tty_log = dir / "tty.txt";
    ASSERT_EQ(sffd::test::run_shell("env -u DISPLAY -u WAYLAND_DISPLAY script -qec '" + exe + " " + args +
                                    "' " + tty_log.string() + " >/dev/null 2>&1 </dev/null"),
              0);
    const std::string tty = read(tty_log);
    EXPECT_NE(tty.find("\rsplatffd render: frame 2 (3/3, 100%)"), std::string::npos) << tty;
}

// The old spellings still work, and say the new one.
TEST(CliGrammar, RenamedViewOptionsStillWorkAndWarn) {
    const fs::path dir = temp_dir("renamed");
    const auto r = sffd::test::run_headless(
        "view sphere --headless --no-ui --quality preview --size 64x48 --frames 2 --timing-json " +
        (dir / "t.json").string() + " --screenshot " + (dir / "last.png").string());
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_NE(r.out.find("splatffd view: --timing-json is deprecated; use --json"), std::string::npos)
        << r.out;
    EXPECT_NE(r.out.find("splatffd view: --screenshot is deprecated; use --out"), std::string::npos) << r.out;
    EXPECT_TRUE(fs::exists(dir / "t.json"));
    EXPECT_TRUE(fs::exists(dir / "last.png"));
    const auto now = sffd::test::run_headless(
        "view sphere --headless --no-ui --quality preview --size 64x48 --frames 2 --json " +
        (dir / "t2.json").string() + " --out " + (dir / "last2.png").string());
    ASSERT_EQ(now.code, 0) << now.out;
    EXPECT_EQ(now.out.find("deprecated"), std::string::npos) << now.out;
    EXPECT_TRUE(fs::exists(dir / "t2.json"));
    EXPECT_TRUE(fs::exists(dir / "last2.png"));
}
