// `splatffd convert IN DIR/metadata.json`, `info` and `render` of a Potree 2 octree as a user runs them:
// the progress lines, what info prints, exit codes (1 bad input naming the file, 2 usage).
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <string>

#include "runtime/assets/formats/surface/potree2.h"
#include "tests/assets/test_util.h"
#include "tests/test_util/run_tool.h"

namespace fs = std::filesystem;
using sffd::test::CliRun;
using sffd::test::run;

TEST(Potree2Cli, ConvertWritesWithProgressAndInfoDescribes) {
    const fs::path dir = sffd::test::fresh_dir("potree2_cli", "synthetic");
    const CliRun c = run("convert synthetic:50k " + (dir / "metadata.json").string() +
                         " --potree-leaf 2000 --potree-grid 32 --progress");
    ASSERT_EQ(c.code, 0) << c.out;
    EXPECT_NE(c.out.find("convert: building cells"), std::string::npos) << c.out;
    EXPECT_NE(c.out.find("wrote " + (dir / "metadata.json").string() + ": 50000 splats in"),
              std::string::npos)
        << c.out;
    const CliRun i = run("info " + (dir / "metadata.json").string());
    ASSERT_EQ(i.code, 0) << i.out;
    EXPECT_NE(i.out.find("points: 50000"), std::string::npos) << i.out;
    EXPECT_NE(i.out.find("position (int32 x 3) rgb (uint16 x 3) normal (float x 3)"), std::string::npos)
        << i.out;
    auto o = sffd::assets::open_potree2(dir / "metadata.json");
    ASSERT_TRUE(o) << o.message();
    EXPECT_GT(o->depth, 1);
    // Back to a splat PLY (the full detail), and that PLY streamed into an octree again.
    const fs::path ply = dir.parent_path() / "back.ply";
    ASSERT_EQ(run("convert " + (dir / "metadata.json").string() + " " + ply.string()).code, 0);
    const fs::path again = sffd::test::fresh_dir("potree2_cli", "again") / "metadata.json";
    ASSERT_EQ(
        run("convert " + ply.string() + " " + again.string() + " --potree-leaf 2000 --potree-grid 32").code,
        0);
    auto a = sffd::assets::open_potree2(again);
    ASSERT_TRUE(a) << a.message();
    EXPECT_EQ(a->points, 50000u);
    EXPECT_EQ(a->attributes.size(), o->attributes.size());
}

TEST(Potree2Cli, BadInputAndUsage) {
    const fs::path dir = sffd::test::fresh_dir("potree2_cli", "bad");
    sffd::test::write(dir / "metadata.json", "{\"version\": \"2.0\"}");
    const CliRun i = run("info " + (dir / "metadata.json").string());
    EXPECT_EQ(i.code, 1) << i.out;
    EXPECT_NE(i.out.find("splatffd info: " + (dir / "metadata.json").string() + ": "), std::string::npos)
        << i.out;
    const CliRun r = run("render " + (dir / "metadata.json").string() + " --out " + (dir / "img").string());
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_NE(r.out.find((dir / "metadata.json").string()), std::string::npos) << r.out;
    const CliRun u = run("convert synthetic:10 " + (dir / "o" / "metadata.json").string() + " --splats 5");
    EXPECT_EQ(u.code, 2) << u.out;
    EXPECT_NE(u.out.find("'--splats' does not apply to a metadata.json output"), std::string::npos) << u.out;
    const CliRun n = run("convert synthetic:abc " + (dir / "o" / "metadata.json").string());
    EXPECT_EQ(n.code, 1) << n.out;
    EXPECT_NE(n.out.find("expected synthetic:N"), std::string::npos) << n.out;
}
