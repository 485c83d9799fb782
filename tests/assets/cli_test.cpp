// `splatffd convert` and `splatffd info` as a user runs them: exit codes (0 ok, 1 bad input naming the
// file, 2 usage), exact splat counts, and what `info` prints.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "runtime/assets/import.h"
#include "tests/assets/textured_box.h"
#include "tests/test_util/run_tool.h"

namespace fs = std::filesystem;

namespace {

using sffd::test::CliRun;
using sffd::test::run;

fs::path temp_dir() {
    fs::path d = fs::temp_directory_path() / ("sffd_cli_test_" + std::to_string(::getpid()));
    fs::create_directories(d);
    return d;
}

}  // namespace

TEST(Cli, ConvertMeshToExactSplatCountAndInfoReportsIt) {
    const fs::path obj = temp_dir() / "tri.obj";
    std::ofstream(obj) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n";
    const fs::path glb = temp_dir() / "tri.glb";
    const CliRun c = run("convert " + obj.string() + " " + glb.string() + " --splats 1234");
    ASSERT_EQ(c.code, 0) << c.out;
    auto cloud = sffd::assets::import_splat_cloud(glb);
    ASSERT_TRUE(cloud.ok()) << cloud.message();
    EXPECT_EQ(cloud->size(), 1234u);
    const CliRun i = run("info " + glb.string());
    ASSERT_EQ(i.code, 0) << i.out;
    EXPECT_NE(i.out.find("1234 splats"), std::string::npos) << i.out;
    EXPECT_NE(i.out.find("columns  position vec3, normal vec3, axis_u vec3, axis_v vec3"), std::string::npos)
        << i.out;

    const fs::path ply = temp_dir() / "tri.ply";
    ASSERT_EQ(run("convert " + glb.string() + " " + ply.string()).code, 0);
    const CliRun pi = run("info " + ply.string());
    ASSERT_EQ(pi.code, 0) << pi.out;
    EXPECT_NE(pi.out.find("element  vertex: 1234"), std::string::npos) << pi.out;
    EXPECT_NE(pi.out.find("float axis_ux"), std::string::npos) << pi.out;
}

TEST(Cli, BadInputExitsOneAndNamesTheFile) {
    const fs::path bad = temp_dir() / "bad.ply";
    std::ofstream(bad) << "ply\nformat ascii 1.0\nelement vertex 99999999\nproperty float x\nend_header\n1\n";
    for (const std::string& cmd :
         {"info " + bad.string(), "convert " + bad.string() + " " + (temp_dir() / "o.glb").string()}) {
        const CliRun r = run(cmd);
        EXPECT_EQ(r.code, 1) << r.out;
        EXPECT_NE(r.out.find(bad.string()), std::string::npos) << r.out;
    }
    EXPECT_FALSE(fs::exists(temp_dir() / "o.glb"));
}

TEST(Cli, UsageErrorsExitTwo) {
    EXPECT_EQ(run("convert").code, 2);
    EXPECT_EQ(run("convert a.ply").code, 2);
    EXPECT_EQ(run("convert a.ply b.ply --splats zero").code, 2);
    EXPECT_EQ(run("convert a.ply b.ply --bogus").code, 2);
    EXPECT_EQ(run("info").code, 2);
}

// `reference` and `render` read numbers through the shared parser: the message names the option.
TEST(Cli, ReferenceAndRenderNumberErrorsNameTheOption) {
    const struct {
        const char* args;
        const char* message;
    } cases[] = {
        {"reference --out /tmp/sffd_ref_bad --size 32xq", "--size: expected an integer in 1..16384, got 'q'"},
        {"reference --out /tmp/sffd_ref_bad --supersample 99",
         "--supersample: expected an integer in 0..16, got '99'"},
        {"reference --out /tmp/sffd_ref_bad --fps abc", "--fps: expected a number"},
        {"reference --out /tmp/sffd_ref_bad --frames 1:x", "--frames: expected an integer"},
        {"render sphere --out /tmp/sffd_render_bad --size 0x5",
         "--size: expected an integer in 1..16384, got '0'"},
    };
    for (const auto& c : cases) {
        const auto r = run(c.args);
        EXPECT_EQ(r.code, 2) << c.args;
        EXPECT_NE(r.out.find(c.message), std::string::npos) << c.args << "\n" << r.out;
    }
}

// A glTF from the web must not leak local files into an export; --allow-outside-resources
// is the explicit opt-in for trusted files.
TEST(Cli, ConvertRefusesResourcesOutsideTheFileFolderUnlessAllowed) {
    const fs::path root = temp_dir() / "exfil";
    fs::remove_all(root);
    fs::create_directories(root / "x");
    fs::create_directories(root / "a" / "b");
    std::ofstream(root / "x" / "secret.txt") << "SECRET123";
    const fs::path gltf = root / "a" / "b" / "exfil.gltf";
    std::ofstream(gltf)
        << R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
      "meshes":[{"primitives":[{"mode":0,"attributes":{"POSITION":0}}]}],
      "accessors":[{"bufferView":0,"componentType":5121,"count":3,"type":"VEC3"}],
      "bufferViews":[{"buffer":0,"byteLength":9}],"buffers":[{"uri":"%2e%2e/%2e%2e/x/secret.txt","byteLength":9}]})";
    const fs::path leak = root / "leak.ply";
    const CliRun r = run("convert " + gltf.string() + " " + leak.string() + " --ascii");
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_NE(r.out.find(gltf.string() + ": resource '../../x/secret.txt' is outside the file's folder"),
              std::string::npos)
        << r.out;
    EXPECT_FALSE(fs::exists(leak));
    const CliRun ok =
        run("--allow-outside-resources convert " + gltf.string() + " " + leak.string() + " --ascii");
    EXPECT_EQ(ok.code, 0) << ok.out;
    EXPECT_TRUE(fs::exists(leak));
}

// Running out of memory is a message and exit 1, never an uncaught std::bad_alloc (rc 134);
// requests beyond the stated budget are refused before any work.
TEST(Cli, OutOfMemoryIsAMessageAndOverBudgetRequestsAreRefusedEarly) {
    const fs::path obj = temp_dir() / "oom.obj";
    std::ofstream(obj) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n";
    const double phys = double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGESIZE));
    if (phys < 322e9) {  // a machine with more memory than 2^28 splats need would start the work
        const CliRun early =
            run("convert " + obj.string() + " " + (temp_dir() / "oom.ply").string() + " --splats 268435456");
        EXPECT_EQ(early.code, 1) << early.out;
        EXPECT_NE(early.out.find(obj.string() +
                                 ": sampling 268435456 splats needs about 322.1 GB (1.2 KB per splat)"),
                  std::string::npos)
            << early.out;
    }
    // Under a 300 MB address-space limit, sampling 2M splats (about 2.2 GB) runs out of memory.
#if defined(__SANITIZE_ADDRESS__)
    GTEST_SKIP() << "AddressSanitizer reserves terabytes of shadow memory: it cannot start under ulimit -v";
#endif
    CliRun r;
    const std::string cmd = "sh -c 'ulimit -v 300000; exec " + std::string(SFFD_BINARY_DIR) +
                            "/tools/splatffd convert " + obj.string() + " " +
                            (temp_dir() / "oom.ply").string() + " --splats 2000000' 2>&1";
    std::FILE* p = popen(cmd.c_str(), "r");
    ASSERT_NE(p, nullptr);
    std::array<char, 4096> buf{};
    while (std::size_t n = std::fread(buf.data(), 1, buf.size(), p)) r.out.append(buf.data(), n);
    const int status = pclose(p);
    ASSERT_TRUE(WIFEXITED(status)) << "killed by a signal: " << r.out;
    EXPECT_EQ(WEXITSTATUS(status), 1) << r.out;
    EXPECT_NE(r.out.find("splatffd convert: out of memory"), std::string::npos) << r.out;
    EXPECT_FALSE(fs::exists(temp_dir() / "oom.ply"));
}

// Progress: with --progress every step prints its start, each further 10 % and its end with
// its time, in order; without it (stderr is a pipe here, not a terminal) no progress lines, but the
// timing summary is printed always.
TEST(Cli, ConvertProgressReportsEveryStepInOrderAndAlwaysTheTiming) {
    const fs::path obj = temp_dir() / "progress.obj";
    std::ofstream(obj) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n";
    const fs::path ply = temp_dir() / "progress.ply";
    const CliRun c = run("convert " + obj.string() + " " + ply.string() + " --splats 5000 --progress");
    ASSERT_EQ(c.code, 0) << c.out;
    const std::vector<std::string> steps = {"reading",
                                            "sampling the surface",
                                            "finding neighbours for thinning",
                                            "thinning (sample elimination)",
                                            "finding neighbours",
                                            "splat radii and axes",
                                            "writing"};
    std::istringstream lines(c.out);
    std::string line;
    std::size_t step = 0;
    int last_percent = -1;
    while (std::getline(lines, line)) {
        if (line.rfind("convert: ", 0) != 0 || line.rfind("convert: done in", 0) == 0) continue;
        ASSERT_LT(step, steps.size()) << "unexpected line after the last step: " << line << "\n" << c.out;
        const std::string head = "convert: " + steps[step] + ": ";
        ASSERT_EQ(line.rfind(head, 0), 0u) << "expected step '" << steps[step] << "', got: " << line << "\n"
                                           << c.out;
        const int percent = std::stoi(line.substr(head.size()));
        if (last_percent < 0) {
            EXPECT_EQ(percent, 0) << line;  // every step announces its start
        }
        EXPECT_GE(percent, last_percent) << line;
        last_percent = percent;
        if (percent == 100) {
            EXPECT_NE(line.find("% in "), std::string::npos) << line;  // the end carries the step's time
            ++step;
            last_percent = -1;
        }
    }
    EXPECT_EQ(step, steps.size()) << c.out;
    const auto done = c.out.find("convert: done in ");
    ASSERT_NE(done, std::string::npos) << c.out;
    for (const std::string& s : steps)
        EXPECT_NE(c.out.find(s + " ", done), std::string::npos) << s << "\n" << c.out;

    const CliRun quiet = run("convert " + obj.string() + " " + ply.string() + " --splats 5000");
    ASSERT_EQ(quiet.code, 0) << quiet.out;
    EXPECT_EQ(quiet.out.find("%"), std::string::npos) << quiet.out;
    EXPECT_NE(quiet.out.find("convert: done in "), std::string::npos) << quiet.out;
}

// A textured mesh converts to a textured cloud: the PLY carries the uv frame and its texture
// beside it; `reference MESH` ray traces the mesh itself; a tinted mesh (colours baked per splat) has no
// texture to trace and is refused naming the file.
TEST(Cli, TexturedMeshConvertsWithItsUvFrameAndReferenceTracesTheMesh) {
    const fs::path dir = temp_dir() / "textured";
    const fs::path obj = sffd::test::write_textured_box(dir);
    const fs::path ply = dir / "box.ply";
    const CliRun c = run("convert " + obj.string() + " " + ply.string() + " --splats 3000");
    ASSERT_EQ(c.code, 0) << c.out;
    EXPECT_TRUE(fs::exists(dir / "box_texture.png"));
    const CliRun i = run("info " + ply.string());
    ASSERT_EQ(i.code, 0) << i.out;
    for (const char* p :
         {"float du_ds", "float dv_ds", "float du_dt", "float dv_dt", "TextureFile box_texture.png"})
        EXPECT_NE(i.out.find(p), std::string::npos) << p << "\n" << i.out;
    const CliRun r =
        run("reference " + obj.string() + " --out " + (dir / "ref").string() + " --size 96x54 --format png");
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_TRUE(fs::exists(dir / "ref" / "frame_0000.png"));
    std::ofstream(dir / "box.mtl") << "newmtl checker\nKd 1 0.5 1\nmap_Kd checker.png\n";
    const CliRun tinted =
        run("reference " + obj.string() + " --out " + (dir / "ref2").string() + " --size 96x54 --format png");
    EXPECT_EQ(tinted.code, 1) << tinted.out;
    EXPECT_NE(tinted.out.find(obj.string()), std::string::npos) << tinted.out;
    EXPECT_NE(tinted.out.find("baked per splat"), std::string::npos) << tinted.out;
}
