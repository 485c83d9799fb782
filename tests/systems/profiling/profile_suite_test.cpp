// `splatffd profile --suite quick` end to end: the JSON it writes is valid against suite.schema.json and
// every row has a value, or (GPU rows on a software rasterizer) says why not; each verdict agrees with its
// target and value. Speed itself is never asserted (a loaded machine would fail it): the suite reports it.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

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

CmdResult profile(const std::string& args, const fs::path& dir) {
    const fs::path log = dir / "suite.log";
    const std::string cmd =
        std::string(SFFD_SPLATFFD_EXE) + " profile " + args + " > " + log.string() + " 2>&1";
    const int status = std::system(cmd.c_str());
    CmdResult r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = read_text(log);
    return r;
}

class ProfileSuite : public ::testing::Test {
protected:
    void SetUp() override {
        dir = fs::temp_directory_path() / ("sffd_suite_test_" + std::to_string(::getpid()));
        fs::create_directories(dir);
    }
    void TearDown() override { fs::remove_all(dir); }
    fs::path dir;
};

TEST_F(ProfileSuite, QuickWritesOneValidRowPerClaim) {
    const fs::path json = dir / "suite.json";
    const CmdResult r = profile("--suite quick --json " + json.string(), dir);
    ASSERT_EQ(r.code, 0) << r.out;
    const auto errors = sffd::profiling::validate_json(read_text(SFFD_SUITE_SCHEMA), read_text(json));
    ASSERT_TRUE(errors.empty()) << errors.front();

    const auto j = nlohmann::json::parse(read_text(json));
    EXPECT_EQ(j["suite"], "quick");
    const bool gpu = j["machine"]["gpu"].get<bool>();
    std::set<std::string> ids;
    ASSERT_GE(j["rows"].size(), 8u);
    for (const auto& row : j["rows"]) {
        const std::string id = row["id"];
        EXPECT_TRUE(ids.insert(id).second) << "duplicate row " << id;
        EXPECT_NE(r.out.find(id), std::string::npos) << "row " << id << " missing from the table";
        if (row["gpu_only"].get<bool>() && !gpu) {
            EXPECT_EQ(row["status"], "not measured") << id;
            EXPECT_TRUE(row["value"].is_null()) << id;
            EXPECT_EQ(row["note"], "not measured (no GPU)") << id;
            continue;
        }
        ASSERT_TRUE(row["value"].is_number()) << id << ": " << row["note"];
        const double v = row["value"];
        EXPECT_GT(v, 0.0) << id;
        if (row["target"].is_null()) {
            EXPECT_EQ(row["status"], "info") << id;
        } else {
            const double t = row["target"];
            const bool met = row["better"] == "higher" ? v >= t : v <= t;
            EXPECT_EQ(row["status"], met ? "met" : "missed") << id;
        }
    }
    // The claims the quick suite covers: a frame of the sphere, CPU deformation, Gaussians, reading files.
    for (const char* id :
         {"sphere.preview", "sphere.hq", "deform.cpu.100k", "gaussians.deform_cpu.100k",
          "gaussians.moving.100k", "read.3dgs_ply", "read.surface_ply", "read.glb", "read.gaussian_glb"})
        EXPECT_TRUE(ids.count(id)) << id;
    // The anchor row says what became of Blender (a time, or why it did not run).
    for (const auto& row : j["rows"]) {
        if (row["id"] == "deform.cpu.100k") {
            EXPECT_NE(row["anchor"].get<std::string>().find("Blender"), std::string::npos);
        }
    }
}

// --only measures the rows whose ids begin so, and nothing else; the JSON says which rows it ran.
TEST_F(ProfileSuite, OnlyRunsTheRowsItNames) {
    const fs::path json = dir / "only.json";
    const CmdResult r = profile("--suite quick --only read.glb,read.surface --json " + json.string(), dir);
    ASSERT_EQ(r.code, 0) << r.out;
    const auto errors = sffd::profiling::validate_json(read_text(SFFD_SUITE_SCHEMA), read_text(json));
    ASSERT_TRUE(errors.empty()) << errors.front();
    const auto j = nlohmann::json::parse(read_text(json));
    EXPECT_EQ(j["only"], nlohmann::json::array({"read.glb", "read.surface"}));
    std::set<std::string> ids;
    for (const auto& row : j["rows"]) {
        ids.insert(row["id"].get<std::string>());
        EXPECT_TRUE(row["value"].is_number()) << row["id"] << ": " << row["note"];
    }
    EXPECT_EQ(ids, (std::set<std::string>{"read.glb", "read.surface_ply"}));
    // Nothing else ran: no frame was profiled, no deformation measured.
    EXPECT_EQ(r.out.find("profile: sphere"), std::string::npos) << r.out;
    EXPECT_EQ(r.out.find("sphere.preview"), std::string::npos) << r.out;
}

// A beginning that no row id has (a typo, or a row of the full suite only) is refused before anything is
// measured, with the ids to choose from.
TEST_F(ProfileSuite, OnlyWithAnUnknownRowListsTheRows) {
    const CmdResult r = profile("--suite quick --only read.glb,gpu.deform.cpu_time", dir);
    EXPECT_EQ(r.code, 2) << r.out;
    EXPECT_NE(r.out.find("--only gpu.deform.cpu_time: no row id starts with it"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("\n  sphere.preview"), std::string::npos) << r.out;
    EXPECT_EQ(r.out.find("performance suite"), std::string::npos) << r.out;
    EXPECT_EQ(r.out.find("profile --suite: read.glb"), std::string::npos) << "measured before refusing";
    const CmdResult alone = profile("sphere --only read.glb", dir);
    EXPECT_EQ(alone.code, 2) << alone.out;
    EXPECT_NE(alone.out.find("--only selects rows of --suite"), std::string::npos) << alone.out;
}

TEST_F(ProfileSuite, UnknownSuiteIsAUsageError) {
    const CmdResult r = profile("--suite medium", dir);
    EXPECT_EQ(r.code, 2) << r.out;
    EXPECT_NE(r.out.find("--suite quick|full"), std::string::npos) << r.out;
}

TEST_F(ProfileSuite, MissingOutputFolderFailsBeforeMeasuring) {
    const CmdResult r = profile("--suite quick --json " + (dir / "nosuch" / "s.json").string(), dir);
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_NE(r.out.find("does not exist"), std::string::npos) << r.out;
    EXPECT_EQ(r.out.find("performance suite"), std::string::npos) << r.out;
}

}  // namespace
