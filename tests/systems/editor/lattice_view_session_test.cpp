// Under xvfb-run, the lattice workflow on an imported cloud through the real window (`splatffd view
// copy.ply`, which showed "no lattice" before): tests/data/editor/lattice_add.txt adds a fitted lattice
// (shift+a), stretches it, exports it as JSON (ctrl+e) and saves; lattice_import.txt reopens the saved
// scene, resets the lattice, imports the JSON (ctrl+i) and saves again. Checked: the saved scene holds
// the lattice bound to the cloud, fitted by ffd::fit_lattice's defaults and edited; the JSON is that
// lattice bit for bit; after reset + import the saved lattice is the JSON's again; and `splatffd deform`
// gives the same output with the scene file or the JSON as its lattice (moving lattices between tools).
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "tests/assets/test_util.h"
#include "tests/test_util/run_tool.h"
#include "runtime/assets/import.h"
#include "runtime/assets/scene.h"
#include "runtime/scene/components.h"
#include "systems/ffd/components.h"
#include "systems/ffd/lattice_io.h"
#include "systems/ffd/operations.h"

using namespace sffd;
namespace fs = std::filesystem;

namespace {

using sffd::test::run_shell;
using sffd::test::slurp;

std::string splatffd() { return std::string(SFFD_BINARY_DIR) + "/tools/splatffd"; }

bool bit_equal(const std::vector<glm::dvec3>& a, const std::vector<glm::dvec3>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(glm::dvec3)) == 0;
}

// The one lattice of a saved scene and the cloud it is bound to.
struct Saved {
    Lattice lattice;
    SplatCloud cloud;
    bool bound = false;
    std::size_t lattices = 0;
};
Saved load_saved(const fs::path& file) {
    Saved s;
    ecs::Registry r;
    r.set_resource<SceneHooks>();  // assets' own formats only
    auto st = load_scene(r, file.string());
    EXPECT_TRUE(st.ok()) << st.message();
    r.view<const Lattice>().each([&](ecs::Entity, const Lattice& l) { s.lattice = l, ++s.lattices; });
    r.view<const SplatCloud, const Deformers>().each(
        [&](ecs::Entity, const SplatCloud& c, const Deformers& d) {
            s.cloud = c;
            s.bound = d.lattices.size() == 1;
        });
    return s;
}

}  // namespace

TEST(LatticeViewSession, AddExportImportThroughTheWindow) {
    if (run_shell("command -v xvfb-run > /dev/null") != 0) GTEST_SKIP() << "xvfb-run not installed";
    const fs::path dir = fs::temp_directory_path() / ("sffd_lattice_view_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const fs::path ply = dir / "copy.ply", scene = dir / "edited.glb",
                   json = dir / "copy.lattice.json";  // named after the lattice
    const std::string data = std::string(SFFD_TEST_DATA_DIR) + "/editor/";
    ASSERT_EQ(run_shell(splatffd() + " convert sphere " + ply.string() + " --splats 3000 > /dev/null 2>&1"),
              0);
    // Panels on in the first run (the Lattices panel is drawn), off in the second.
    ASSERT_EQ(
        run_shell("xvfb-run -a " + splatffd() + " view " + ply.string() +
                  " --size 1280x720 --quality preview --frames 14 --replay " + data +
                  "lattice_add.txt --save " + scene.string() + " > " + (dir / "add.log").string() + " 2>&1"),
        0)
        << slurp(dir / "add.log");
    ASSERT_TRUE(fs::exists(scene)) << slurp(dir / "add.log");
    ASSERT_TRUE(fs::exists(json)) << slurp(dir / "add.log");

    const Saved added = load_saved(scene);
    ASSERT_EQ(added.lattices, 1u);
    EXPECT_TRUE(added.bound);
    // Fitted with the default settings around the cloud as stored, then edited (inner points moved 0.3 in x).
    auto fit = ffd::fit_lattice(added.cloud.positions, added.cloud.origin, ffd::FitOptions{});
    ASSERT_TRUE(fit.ok());
    EXPECT_TRUE(bit_equal(added.lattice.rest, fit->rest));
    std::size_t moved = 0;
    for (std::size_t c = 0; c < added.lattice.current.size(); ++c) {
        const glm::dvec3 d = added.lattice.current[c] - added.lattice.rest[c];
        if (d != glm::dvec3(0.0)) {
            ++moved;
            EXPECT_NEAR(d.x, 0.3, 1e-12);
        }
    }
    EXPECT_EQ(moved, 9u * 9u * 9u);  // 11^3 control points minus the pinned outer layer
    auto exported = ffd::load_lattice(json);
    ASSERT_TRUE(exported.ok()) << exported.message();
    EXPECT_TRUE(bit_equal(exported->current, added.lattice.current));

    // Reopen, reset, import, save: the JSON's lattice again.
    ASSERT_EQ(run_shell("xvfb-run -a " + splatffd() + " view " + scene.string() +
                        " --size 1280x720 --quality preview --no-ui --frames 8 --replay " + data +
                        "lattice_import.txt > " + (dir / "import.log").string() + " 2>&1"),
              0)
        << slurp(dir / "import.log");
    EXPECT_NE(slurp(dir / "import.log").find("imported"), std::string::npos) << slurp(dir / "import.log");
    const Saved imported = load_saved(scene);
    ASSERT_EQ(imported.lattices, 1u);
    EXPECT_TRUE(bit_equal(imported.lattice.current, exported->current));

    // deform: the scene file and the JSON are the same lattice.
    const fs::path a = dir / "a.ply", b = dir / "b.ply";
    ASSERT_EQ(run_shell(splatffd() + " deform " + ply.string() + " " + a.string() + " --lattice " +
                        scene.string() + " > /dev/null 2>&1"),
              0);
    ASSERT_EQ(run_shell(splatffd() + " deform " + ply.string() + " " + b.string() + " --lattice " +
                        json.string() + " > /dev/null 2>&1"),
              0);
    EXPECT_EQ(slurp(a), slurp(b));
    EXPECT_NE(slurp(a), slurp(ply));  // and it deformed something
    fs::remove_all(dir);
}
