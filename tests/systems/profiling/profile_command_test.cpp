// `splatffd profile` end to end: the files it writes (JSON valid against the schema, trace parses),
// --compare exit codes against a baseline with a planted slowdown, bad baselines and usage errors.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <nlohmann/json.hpp>

#include "systems/profiling/json_schema.h"

namespace {

namespace fs = std::filesystem;

std::string read_text(const fs::path& p) {
    std::ifstream f(p);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

struct CmdResult {
    int code = -1;
    std::string out;
};

CmdResult profile(const std::string& args) {
    std::string name = "sffd_profile_cmd_";
    name += std::to_string(::getpid());
    name += ".log";
    const fs::path log = fs::temp_directory_path() / name;
    std::string cmd = SFFD_SPLATFFD_EXE;
    cmd += " profile ";
    cmd += args;
    cmd += " > ";
    cmd += log.string();
    cmd += " 2>&1";
    const int status = std::system(cmd.c_str());
    CmdResult r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = read_text(log);
    fs::remove(log);
    return r;
}

class ProfileCommand : public ::testing::Test {
protected:
    void SetUp() override {
        dir = fs::temp_directory_path() / ("sffd_profile_dir_" + std::to_string(::getpid()));
        fs::create_directories(dir);
    }
    void TearDown() override { fs::remove_all(dir); }
    std::string path(const char* name) const { return (dir / name).string(); }
    fs::path dir;
};

TEST_F(ProfileCommand, WritesSchemaValidJsonAndAParsableTrace) {
    const CmdResult r =
        profile("synthetic:20k --backend cpu --frames 8 --warmup 2 --json " + path("p.json") + " --trace " +
                path("p.trace.json") + " --csv " + path("p.csv") + " --svg " + path("p.svg"));
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_NE(r.out.find("frames: 8"), std::string::npos) << r.out;
    const auto errors =
        sffd::profiling::validate_json(read_text(SFFD_PROFILE_SCHEMA), read_text(path("p.json")));
    EXPECT_TRUE(errors.empty()) << errors.front();

    const auto report = nlohmann::json::parse(read_text(path("p.json")));
    EXPECT_EQ(report["config"]["points"], 20000);
    EXPECT_EQ(report["frame"]["cpu_ms"]["n"], 8);
    double systems = 0.0;
    for (const auto& s : report["systems"]) systems += s["cpu_ms"]["mean"].get<double>();
    EXPECT_LE(systems, report["frame"]["cpu_ms"]["mean"].get<double>());
    // The engine's own render passes are named for the profiler (runtime/app/pass_timer.h).
    std::vector<std::string> passes;
    for (const auto& p : report["passes"]) passes.push_back(p["name"].get<std::string>());
    for (const char* name : {"render.cull", "render.hq.visibility", "render.hq.attribute", "render.hq.shade"})
        EXPECT_NE(std::find(passes.begin(), passes.end(), name), passes.end())
            << name << " missing: " << report["passes"].dump();

    const auto trace = nlohmann::json::parse(read_text(path("p.trace.json")));
    int frames = 0;
    for (const auto& e : trace["traceEvents"]) frames += e.value("cat", "") == "frame";
    EXPECT_EQ(frames, 8);
    EXPECT_EQ(read_text(path("p.svg")).rfind("<svg", 0), 0u);
}

TEST_F(ProfileCommand, CompareFailsOnAPlantedSlowdownAndPassesWithinTheSpread) {
    ASSERT_EQ(profile("synthetic:20k --backend cpu --frames 10 --warmup 2 --json " + path("base.json")).code,
              0);
    auto base = nlohmann::json::parse(read_text(path("base.json")));
    // Planted slowdown: a baseline in which every system and the frame were 20x faster than measured.
    auto fast = base;
    auto shrink = [](nlohmann::json& stats) {
        for (const char* k : {"min", "mean", "p50", "p95", "p99", "max"})
            if (stats[k].is_number()) stats[k] = stats[k].get<double>() / 20.0;
    };
    // Every row the comparison reads: the frame, and the systems' and passes' CPU and GPU times (a row
    // left at its measured value compares two noisy runs, and the GPU rows of the render passes vary).
    auto every_row = [](nlohmann::json& report, const auto& fn) {
        fn(report["frame"]["cpu_ms"]);
        for (const char* table : {"systems", "passes"})
            for (auto& row : report[table])
                for (const char* metric : {"cpu_ms", "gpu_ms"})
                    if (row.contains(metric) && row[metric].is_object()) fn(row[metric]);
    };
    every_row(fast, shrink);
    std::ofstream(path("fast.json")) << fast.dump();
    const CmdResult slow =
        profile("synthetic:20k --backend cpu --frames 10 --warmup 2 --compare " + path("fast.json"));
    EXPECT_EQ(slow.code, 3) << slow.out;
    EXPECT_NE(slow.out.find("SLOWER"), std::string::npos) << slow.out;

    // A baseline 20x slower than now: nothing regressed.
    auto sluggish = base;
    auto grow = [](nlohmann::json& stats) {
        for (const char* k : {"min", "mean", "p50", "p95", "p99", "max"})
            if (stats[k].is_number()) stats[k] = stats[k].get<double>() * 20.0 + 1.0;
    };
    every_row(sluggish, grow);
    std::ofstream(path("slow.json")) << sluggish.dump();
    const CmdResult ok =
        profile("synthetic:20k --backend cpu --frames 10 --warmup 2 --compare " + path("slow.json"));
    EXPECT_EQ(ok.code, 0) << ok.out;
    EXPECT_NE(ok.out.find("no regression"), std::string::npos) << ok.out;
}

TEST_F(ProfileCommand, BadBaselineAndBadUsageAreReported) {
    std::ofstream(path("bad.json")) << "{\"format\": \"splatffd-profile\", \"version\": 1";
    const CmdResult bad =
        profile("synthetic:5k --backend cpu --frames 2 --warmup 0 --compare " + path("bad.json"));
    EXPECT_EQ(bad.code, 1) << bad.out;
    EXPECT_NE(bad.out.find(path("bad.json") + ": not valid JSON"), std::string::npos) << bad.out;
    const CmdResult missing =
        profile("synthetic:5k --backend cpu --frames 2 --warmup 0 --compare " + path("nope.json"));
    EXPECT_EQ(missing.code, 1) << missing.out;
    EXPECT_NE(missing.out.find("nope.json"), std::string::npos) << missing.out;
    EXPECT_EQ(profile("--frames zero").code, 2);
    EXPECT_EQ(profile("--quality ultra").code, 2);
    EXPECT_EQ(profile("--sweep points=abc").code, 2);
    EXPECT_EQ(profile("--bogus").code, 2);
}

TEST_F(ProfileCommand, DefaultsToTheEnginesOwnBackendAndSaysWhichRan) {
    // No --backend: the engine's automatic choice (the CPU on a software rasterizer, else the GPU), one
    // path for every measured frame, printed and in the report; --backend cpu is obeyed.
    const CmdResult r = profile("synthetic:5k --frames 3 --warmup 2 --json " + path("auto.json"));
    ASSERT_EQ(r.code, 0) << r.out;
    const auto report = nlohmann::json::parse(read_text(path("auto.json")));
    EXPECT_EQ(report["config"]["backend"], "auto");
    const std::string used = report["config"]["backend_used"].get<std::string>();
    EXPECT_TRUE(used == "cpu" || used == "gpu") << used;
    EXPECT_NE(r.out.find("deformation backend: " + used + " (--backend auto)"), std::string::npos) << r.out;
    const CmdResult c =
        profile("synthetic:5k --backend cpu --frames 3 --warmup 2 --json " + path("cpu.json"));
    ASSERT_EQ(c.code, 0) << c.out;
    EXPECT_EQ(nlohmann::json::parse(read_text(path("cpu.json")))["config"]["backend_used"], "cpu");
    EXPECT_NE(c.out.find("deformation backend: cpu (--backend cpu)"), std::string::npos) << c.out;
    EXPECT_EQ(profile("--backend tpu").code, 2);
}

TEST_F(ProfileCommand, SaysWhichBlendTheGaussianPassTookAndTheCoverageItWeighed) {
    // A small Gaussian sphere, rendered: the report names the blend of its last frame, the coverage and the
    // budget (4 images on a GPU, 128 on a software rasterizer), and the blend is the one they ask for.
    const CmdResult r =
        profile("synthetic-gaussians:3k --quality hq --frames 2 --warmup 1 --json " + path("g.json"));
    ASSERT_EQ(r.code, 0) << r.out;
    const auto config = nlohmann::json::parse(read_text(path("g.json")))["config"];
    ASSERT_TRUE(config.contains("gaussian_blend")) << config.dump();
    const double covered = config["gaussian_covered_images"].get<double>();
    const double budget = config["gaussian_quad_budget_images"].get<double>();
    EXPECT_TRUE(budget == 4.0 || budget == 128.0) << budget;
    EXPECT_GT(covered, 0.01);  // a sphere of 3,000 Gaussians in a 1280x720 frame covers part of it
    EXPECT_EQ(config["gaussian_blend"], covered > budget ? "tiles" : "quads") << covered << " / " << budget;
    EXPECT_NE(r.out.find("gaussian_blend="), std::string::npos) << r.out;
    // No Gaussians, no such entries.
    const CmdResult p = profile("synthetic:5k --backend cpu --frames 2 --warmup 0 --json " + path("s.json"));
    ASSERT_EQ(p.code, 0) << p.out;
    EXPECT_FALSE(nlohmann::json::parse(read_text(path("s.json")))["config"].contains("gaussian_blend"));
}

}  // namespace
