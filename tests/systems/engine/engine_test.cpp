// The engine library without the command: the schedule's shape, and frames of the built-in sphere run
// through make_engine_schedule() and read back with render_engine_frame() on a headless EGL context.
#include <gtest/gtest.h>

#include <algorithm>
#include <optional>
#include <string>

#include "runtime/assets/scene.h"
#include "runtime/gfx/context.h"
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

class EngineFrame : public testing::Test {
protected:
    static constexpr int kWidth = 96, kHeight = 54;
    void SetUp() override {
        register_engine_scene_hooks();
        auto c = gfx::create_context({.headless = true, .width = kWidth, .height = kHeight});
        if (!c) SFFD_GL_UNAVAILABLE(c.message());
        ctx.emplace(std::move(*c));
    }
    // The built-in sphere (with its demo clip) in a fresh registry, rendered at preview quality.
    static void load_sphere(ecs::Registry& registry) {
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
