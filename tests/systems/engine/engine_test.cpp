// The engine library without the command: the schedule's shape, and frames of the built-in sphere run
// through make_engine_schedule() and read back with render_engine_frame() on a headless EGL context.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

#include "runtime/assets/scene.h"
#include "runtime/gfx/context.h"
#include "runtime/scene/lattice.h"
#include "systems/animation/components.h"
#include "systems/engine/engine.h"
#include "systems/engine/engine_frame.h"
#include "systems/splat_render/splat_render.h"
#include "tests/test_util/gl_required.h"

namespace sffd {
namespace {

bool has(const Schedule& s, Phase phase, const std::string& name) {
    const auto& systems = s.systems(phase);
    return std::any_of(systems.begin(), systems.end(),
                       [&](const Schedule::Entry& e) { return e.name == name; });
}

TEST(EngineSchedule, HeadlessScheduleHasNoPresentAndNoEditor) {
    const Schedule s = make_engine_schedule({.present = false});
    EXPECT_TRUE(s.systems(Phase::present).empty());
    EXPECT_TRUE(has(s, Phase::deformation, "ffd"));
    EXPECT_TRUE(has(s, Phase::rendering, "splat_render"));
    EXPECT_FALSE(has(s, Phase::rendering, "editor.overlay"));
}

// The editor's gestures that need picking are applied right after the picking system, in its phase.
TEST(EngineSchedule, EditorPicksRunRightAfterPicking) {
    const Schedule s = make_engine_schedule({.present = false});
    const auto& picking = s.systems(Phase::picking);
    ASSERT_EQ(picking.size(), 2u);
    EXPECT_EQ(picking[0].name, "picking");
    EXPECT_EQ(picking[1].name, "editor.picks");
}

TEST(EngineSchedule, EditorScheduleAddsOverlayAndUi) {
    const Schedule s = make_engine_schedule({.present = true, .editor = true});
    EXPECT_TRUE(has(s, Phase::rendering, "editor.overlay"));
    EXPECT_TRUE(has(s, Phase::present, "editor.ui"));
    EXPECT_TRUE(has(s, Phase::present, "present.swap"));
}

// Every system of the engine's frame says what it reads and writes (checked by SFFD_CHECK_ACCESS builds).
TEST(EngineSchedule, EverySystemDeclaresItsAccess) {
    const std::vector<std::string> not_yet;
    const Schedule s = make_engine_schedule({.present = true, .editor = true});
    std::size_t systems = 0;
    for (std::size_t p = 0; p < phase_count; ++p)
        for (const Schedule::Entry& e : s.systems(static_cast<Phase>(p))) {
            ++systems;
            const bool exempt = std::find(not_yet.begin(), not_yet.end(), e.name) != not_yet.end();
            EXPECT_EQ(e.access.declared(), !exempt) << e.name;
        }
    EXPECT_EQ(systems, 15u);
}

// The declarations hold the types by the names the check and the README print.
TEST(EngineSchedule, DeclarationsNameTheirTypes) {
    const Schedule s = make_engine_schedule({.present = false});
    const auto& ffd = s.systems(Phase::deformation).at(0);
    ASSERT_EQ(ffd.name, "ffd");
    auto named = [](const std::vector<ecs::TypeRef>& v, std::string_view n) {
        return std::any_of(v.begin(), v.end(), [&](const ecs::TypeRef& t) { return t.name == n; });
    };
    EXPECT_TRUE(named(ffd.access.read_types(), "Lattice"));
    EXPECT_TRUE(named(ffd.access.write_types(), "DeformedSplats"));
    EXPECT_FALSE(named(ffd.access.write_types(), "Lattice"));
    EXPECT_TRUE(ffd.access.can_read(ecs::detail::type_id<Lattice>()));
    EXPECT_FALSE(ffd.access.can_write(ecs::detail::type_id<Lattice>()));
}

// A line diff (longest common subsequence): "-" for lines only in `want`, "+" only in `got`.
std::string line_diff(const std::vector<std::string>& want, const std::vector<std::string>& got) {
    const std::size_t n = want.size(), m = got.size();
    std::vector<std::vector<int>> l(n + 1, std::vector<int>(m + 1, 0));
    for (std::size_t i = n; i-- > 0;)
        for (std::size_t j = m; j-- > 0;)
            l[i][j] = want[i] == got[j] ? l[i + 1][j + 1] + 1 : std::max(l[i + 1][j], l[i][j + 1]);
    std::string out;
    std::size_t i = 0, j = 0;
    while (i < n || j < m) {
        if (i < n && j < m && want[i] == got[j]) ++i, ++j;
        else if (j < m && (i == n || l[i][j + 1] >= l[i + 1][j])) out += "+ " + got[j++] + "\n";
        else out += "- " + want[i++] + "\n";
    }
    return out;
}

std::vector<std::string> lines_of(const std::string& text) {
    std::vector<std::string> out;
    std::size_t at = 0;
    while (at < text.size()) {
        const std::size_t end = std::min(text.find('\n', at), text.size());
        out.push_back(text.substr(at, end - at));
        at = end + 1;
    }
    return out;
}

// The README's frame table is the schedule's declarations, so it cannot drift from what the check enforces.
TEST(EngineSchedule, ReadmeFrameTableIsTheGeneratedOne) {
    const std::string readme_path = std::string(SFFD_TEST_DATA_DIR) + "/../../README.md";
    std::ifstream in(readme_path);
    ASSERT_TRUE(in) << readme_path;
    const std::string readme((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::string begin = "<!-- frame-table:begin", end = "<!-- frame-table:end -->";
    const std::size_t b = readme.find(begin), e = readme.find(end);
    ASSERT_NE(b, std::string::npos) << readme_path << ": no '" << begin << "' marker";
    ASSERT_NE(e, std::string::npos) << readme_path << ": no '" << end << "' marker";
    ASSERT_LT(b, e);
    const std::size_t body = readme.find('\n', b) + 1;
    const std::string documented = readme.substr(body, e - body);
    const std::string generated = frame_table_markdown();
    EXPECT_EQ(documented, generated) << readme_path
                                     << ": the frame table differs from the schedule's declarations "
                                        "(regenerate it: tools/update_frame_table.sh build/<dir>)\n"
                                     << line_diff(lines_of(documented), lines_of(generated));
}

bool has_clip(const ecs::Registry& registry) { return registry.count<AnimationClip>() > 0; }

// What load_scene opens is the registry's own context: the engine's hooks in one registry, none in
// another, in the same process; a registry with no context at all is refused with a message, and a
// registry the first one makes gets the same hooks by copying them.
TEST(EngineSceneHooks, LoadSceneUsesTheRegistrysOwnHooks) {
    ecs::Registry engine;
    use_engine_scene_hooks(engine);
    ASSERT_TRUE(load_scene(engine, "sphere"));
    EXPECT_TRUE(has_clip(engine)) << "the animation hook gives the built-in sphere its demo clip";
    EXPECT_NE(scene_file_types(engine).find(".spz"), std::string::npos) << scene_file_types(engine);

    ecs::Registry bare;
    bare.set_resource<SceneHooks>();  // a context with no hooks: assets' own formats
    ASSERT_TRUE(load_scene(bare, "sphere"));
    EXPECT_FALSE(has_clip(bare));
    EXPECT_EQ(scene_file_types(bare), ".ply, .obj, .off, .gltf, .glb");
    EXPECT_EQ(engine_scene_hooks().file_types(), scene_file_types(engine));

    ecs::Registry copied;
    SceneHooks::copy_to(engine, copied);
    ASSERT_TRUE(load_scene(copied, "sphere"));
    EXPECT_TRUE(has_clip(copied));
}

// There is no process-wide set of loaders to fall back on: a registry set up without hooks is told so,
// both loading and saving, and is left as it was.
TEST(EngineSceneHooks, ARegistryWithoutHooksIsRefusedWithAMessage) {
    ecs::Registry engine;
    use_engine_scene_hooks(engine);  // hooks in another registry of the process change nothing
    ecs::Registry none;
    const Status loaded = load_scene(none, "sphere");
    ASSERT_FALSE(loaded);
    EXPECT_NE(loaded.message().find("sphere: no scene loaders registered in this registry"),
              std::string::npos)
        << loaded.message();
    EXPECT_EQ(none.count<SplatCloud>(), 0u);
    const std::filesystem::path out =
        std::filesystem::temp_directory_path() / ("sffd_no_hooks_" + std::to_string(::getpid()) + ".glb");
    const Status saved = save_scene(none, out);
    ASSERT_FALSE(saved);
    EXPECT_NE(saved.message().find(out.string() + ": no scene loaders registered in this registry"),
              std::string::npos)
        << saved.message();
    EXPECT_FALSE(std::filesystem::exists(out));
}

class EngineFrame : public testing::Test {
protected:
    static constexpr int kWidth = 96, kHeight = 54;
    void SetUp() override {
        auto c = gfx::create_context({.headless = true, .width = kWidth, .height = kHeight});
        if (!c) SFFD_GL_UNAVAILABLE(c.message());
        ctx.emplace(std::move(*c));
    }
    // The built-in sphere (with its demo clip) in a fresh registry, rendered at preview quality.
    static void load_sphere(ecs::Registry& registry) {
        use_engine_scene_hooks(registry);
        const Status loaded = load_scene(registry, "sphere");
        ASSERT_TRUE(loaded) << loaded.message();
        render::RenderSettings settings;
        settings.quality = render::Quality::preview;
        settings.width = kWidth;
        settings.height = kHeight;
        registry.set_resource<render::RenderSettings>(settings);
    }
    std::optional<gfx::GlContext> ctx;
};

std::size_t covered(const render::FrameImage& image) {
    return std::size_t(
        std::count_if(image.color.begin(), image.color.end(), [](const glm::vec4& c) { return c.w > 0.0f; }));
}

TEST_F(EngineFrame, FrameKAloneEqualsFrameKOfASequence) {
    const Schedule schedule = make_engine_schedule({.present = false});
    std::optional<render::FrameImage> in_sequence, alone;
    {
        ecs::Registry registry;
        load_sphere(registry);
        for (std::uint64_t k = 0; k <= 3; ++k) {
            auto image = render_engine_frame(registry, schedule, *ctx, {.frame = k});
            ASSERT_TRUE(image) << image.message();
            if (k == 3) in_sequence = std::move(*image);
        }
        render::release_render_state(registry);
    }
    {
        ecs::Registry registry;
        load_sphere(registry);
        auto image = render_engine_frame(registry, schedule, *ctx, {.frame = 3});
        ASSERT_TRUE(image) << image.message();
        alone = std::move(*image);
        render::release_render_state(registry);
    }
    ASSERT_EQ(in_sequence->width, kWidth);
    ASSERT_EQ(in_sequence->height, kHeight);
    const std::size_t pixels = std::size_t(kWidth) * kHeight;
    EXPECT_GT(covered(*alone), pixels / 10) << "the sphere covers a good part of the frame";
    EXPECT_LT(covered(*alone), pixels) << "and leaves background around it";
    ASSERT_EQ(in_sequence->color.size(), alone->color.size());
    std::size_t differing = 0;
    for (std::size_t i = 0; i < alone->color.size(); ++i)
        differing += in_sequence->color[i] != alone->color[i];
    EXPECT_EQ(differing, 0u) << "frame 3 depends on its index only, not on the frames run before it";
}

TEST_F(EngineFrame, NonPositiveFpsIsRefusedWithAMessage) {
    ecs::Registry registry;
    const Schedule schedule = make_engine_schedule({.present = false});
    auto image = render_engine_frame(registry, schedule, *ctx, {.frame = 0, .fps = 0.0});
    ASSERT_FALSE(image);
    EXPECT_NE(image.message().find("fps must be positive"), std::string::npos) << image.message();
}

}  // namespace
}  // namespace sffd
