// Acceptance: under xvfb-run, `splatffd view sphere --replay tests/data/editor/session.txt`
// selects control points (x-ray box select), stretches and twists the sphere, undoes and redoes, and
// saves. Checked here:
//   - the screenshot shows the change: against a run of the same length without the replay, the surface
//     depth differs over the middle of the sphere (where the edited control points are) and nowhere far
//     from it, and the colour differs there too;
//   - the saved scene reloads to the same lattice, bit for bit, as an independent in-process replay of
//     the same events through the editor's input system (no window, no GL), which also confirms that
//     undo + redo left the twist applied.
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "runtime/assets/scene.h"
#include "systems/animation/animation_system.h"
#include "systems/editor/editor_system.h"
#include "systems/ffd/components.h"
#include "systems/picking/picking_system.h"
#include "systems/splat_render/image_io.h"

using namespace sffd;
namespace fs = std::filesystem;

namespace {

const std::string session = std::string(SFFD_TEST_DATA_DIR) + "/editor/session.txt";
constexpr int frames = 66;

int run(const std::string& command) {
    const int rc = std::system(command.c_str());
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

std::string splatffd() { return std::string(SFFD_BINARY_DIR) + "/tools/splatffd"; }

ecs::Entity first_lattice(ecs::Registry& reg) {
    ecs::Entity found = ecs::null_entity;
    reg.view<Lattice>().each([&](ecs::Entity e, Lattice&) {
        if (found == ecs::null_entity) found = e;
    });
    return found;
}

bool bit_equal(const std::vector<glm::dvec3>& a, const std::vector<glm::dvec3>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(glm::dvec3)) == 0;
}

}  // namespace

TEST(ViewSession, ReplayedEditsShowInTheScreenshotAndTheSavedLatticeIsBitExact) {
    if (run("command -v xvfb-run > /dev/null") != 0) GTEST_SKIP() << "xvfb-run not installed";
    const fs::path dir = fs::temp_directory_path() / ("sffd_view_session_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const std::string common =
        " view sphere --size 1280x720 --quality preview --no-ui --frames " + std::to_string(frames);
    const fs::path edited_exr = dir / "edited.exr", plain_exr = dir / "plain.exr", saved = dir / "edited.glb";
    ASSERT_EQ(
        run("xvfb-run -a " + splatffd() + common + " --replay " + session + " --save " + saved.string() +
            " --screenshot " + edited_exr.string() + " > " + (dir / "edited.log").string() + " 2>&1"),
        0)
        << "see " << (dir / "edited.log");
    ASSERT_EQ(run("xvfb-run -a " + splatffd() + common + " --screenshot " + plain_exr.string() + " > " +
                  (dir / "plain.log").string() + " 2>&1"),
              0)
        << "see " << (dir / "plain.log");
    ASSERT_TRUE(fs::exists(saved)) << "the session's ctrl+s did not save";

    // --- the saved lattice: bit for bit what the editor's input system produces from the same events ---
    ecs::Registry expected;
    expected.set_resource<SceneHooks>();  // assets' own formats only
    ASSERT_TRUE(load_scene(expected, "sphere").ok());
    editor::EditorState& state = editor::setup_editor(expected, Viewport{1280, 720});
    auto events = editor::load_input_recording(session);
    ASSERT_TRUE(events.ok()) << events.message();
    state.replay.emplace(*events);
    for (std::uint64_t f = 0; f < frames; ++f) {  // the editor's steps of the engine's frame, in order
        const FrameContext frame{f, f / 60.0, 1 / 60.0};
        editor::editor_input_system(expected, frame);
        animation_system(expected, frame);  // the sphere's clip: the animation shows the edits (its pose)
        picking::picking_system(expected, frame);
        editor::editor_pick_system(expected, frame);
    }
    ASSERT_EQ(state.undo.size(), 3u);      // box select, stretch, twist
    ASSERT_EQ(state.undo.position(), 3u);  // undone and redone: all applied
    EXPECT_EQ(state.undo.at(2).label(), "twist");
    const Lattice& want = expected.get<Lattice>(first_lattice(expected));

    ecs::Registry reloaded;
    reloaded.set_resource<SceneHooks>();  // assets' own formats only
    auto st = load_scene(reloaded, saved.string());
    ASSERT_TRUE(st.ok()) << st.message();
    const ecs::Entity le = first_lattice(reloaded);
    ASSERT_TRUE(reloaded.valid(le));
    const Lattice& got = reloaded.get<Lattice>(le);
    EXPECT_EQ(got.divisions, want.divisions);
    EXPECT_TRUE(bit_equal(got.rest, want.rest));
    EXPECT_TRUE(bit_equal(got.current, want.current)) << "saved lattice is not the edited one, bit for bit";
    std::size_t moved = 0;
    for (std::size_t c = 0; c < got.current.size(); ++c) moved += got.current[c] != got.rest[c];
    EXPECT_GT(moved, 20u);

    // --- the screenshot shows the change where the edit is -------------------------------------------
    auto edited = render::read_exr(edited_exr);
    auto plain = render::read_exr(plain_exr);
    ASSERT_TRUE(edited.ok()) << edited.message();
    ASSERT_TRUE(plain.ok()) << plain.message();
    ASSERT_EQ(edited->width, 1280);
    ASSERT_EQ(plain->width, 1280);
    // Surface depth (the overlay writes colour only): changed inside the middle of the sphere's image,
    // unchanged in the outer band of the image (the outer control-point layer is pinned, so the sphere's
    // silhouette and everything far from the selection stays put).
    int middle = 0, middle_changed = 0, colour_changed = 0, far_changed = 0, far = 0;
    for (int y = 0; y < 720; ++y)
        for (int x = 0; x < 1280; ++x) {
            const std::size_t i = edited->index(x, y);
            const float a = edited->depth[i], b = plain->depth[i];
            const bool depth_changed =
                std::isfinite(a) != std::isfinite(b) || (std::isfinite(a) && std::abs(a - b) > 1e-3f);
            const bool in_middle = x >= 560 && x < 720 && y >= 250 && y < 400;
            const bool outside = x < 300 || x > 980 || y < 100 || y > 650;
            if (in_middle) {
                ++middle;
                middle_changed += depth_changed;
                colour_changed +=
                    glm::length(glm::vec3(edited->color[i]) - glm::vec3(plain->color[i])) > 0.02f;
            }
            if (outside) {
                ++far;
                far_changed += depth_changed;
            }
        }
    EXPECT_GT(middle_changed, middle / 10) << "surface barely moved where the edit is";
    EXPECT_GT(colour_changed, middle / 10);
    EXPECT_EQ(far_changed, 0) << "surface moved far from the edit";
    fs::remove_all(dir);
}
