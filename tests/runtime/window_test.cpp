// Window context test: a real GLFW window with a GL 4.5 core debug context (label `xvfb`; tools/test.sh
// runs it under `xvfb-run -a`). Without a display it skips, unless SFFD_REQUIRE_DISPLAY=1 (set by
// tools/test.sh) makes a missing display a failure, so CI cannot pass it silently.
#include <gtest/gtest.h>

#include <GLFW/glfw3.h>

#include <array>
#include <cstdlib>
#include <vector>

#include "runtime/app/app.h"
#include "runtime/gfx/context.h"
#include "runtime/gfx/render_target.h"
#include "tests/runtime/gl_version.h"

using namespace sffd;

TEST(Window, OpensCore45WindowAndPresentsAnOffscreenTarget) {
    if (!gfx::display_available()) {
        const char* require = std::getenv("SFFD_REQUIRE_DISPLAY");
        if (require && std::string(require) == "1") FAIL() << "no DISPLAY: run under xvfb-run -a";
        GTEST_SKIP() << "no DISPLAY (run under xvfb-run -a)";
    }
    auto created = gfx::create_context({.width = 96, .height = 64, .title = "SplatFFD window test"});
    ASSERT_TRUE(created.ok()) << created.message();
    gfx::GlContext ctx = std::move(created).value();
    EXPECT_FALSE(ctx.is_headless());
    ASSERT_NE(ctx.window(), nullptr);
    EXPECT_EQ(glfwGetCurrentContext(), ctx.window());
    const gfx::FramebufferSize size = ctx.framebuffer_size();
    EXPECT_EQ(size.width, 96);
    EXPECT_EQ(size.height, 64);
    const test::CurrentContext current = test::current_context();
    EXPECT_GE(current.version, 45);
    EXPECT_TRUE(current.core);
    EXPECT_TRUE(current.debug);

    // The same offscreen path as headless: render into a target, blit it to the window, read it back.
    const std::uint64_t errors = gfx::debug_error_count();
    auto target = gfx::RenderTarget::create({.label = "test.window_target",
                                             .width = 48,
                                             .height = 32,
                                             .color = {{"color", gfx::ColorFormat::rgba8}}});
    ASSERT_TRUE(target.ok()) << target.message();
    const float green[4] = {0.0f, 1.0f, 0.0f, 1.0f};
    target->clear_color("color", green);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glClearColor(1.0f, 0.0f, 0.0f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);
    target->blit_to_default_framebuffer("color", size.width, size.height);
    std::uint8_t pixel[4] = {};
    glReadBuffer(GL_BACK);
    glReadPixels(size.width / 2, size.height / 2, 1, 1, GL_RGBA, GL_UNSIGNED_BYTE, pixel);
    EXPECT_EQ(pixel[0], 0);
    EXPECT_EQ(pixel[1], 255);
    ctx.swap_buffers();
    ctx.poll_events();
    EXPECT_FALSE(ctx.should_close());
    ctx.request_close();
    EXPECT_TRUE(ctx.should_close());
    EXPECT_EQ(gfx::debug_error_count(), errors);
}

TEST(Window, HeadlessFlagForcesEglEvenWithADisplay) {
    auto created = gfx::create_context({.headless = true, .width = 8, .height = 8});
    ASSERT_TRUE(created.ok()) << created.message();
    EXPECT_TRUE(created->is_headless());
    EXPECT_EQ(created->window(), nullptr);
}

TEST(Window, AppRunPresentsTheSourceAndStopsWhenTheWindowCloses) {
    if (!gfx::display_available()) {
        const char* require = std::getenv("SFFD_REQUIRE_DISPLAY");
        if (require && std::string(require) == "1") FAIL() << "no DISPLAY: run under xvfb-run -a";
        GTEST_SKIP() << "no DISPLAY (run under xvfb-run -a)";
    }
    auto created = gfx::create_context({.width = 64, .height = 48});
    ASSERT_TRUE(created.ok()) << created.message();
    gfx::GlContext ctx = std::move(created).value();
    glfwSwapInterval(0);
    auto target = gfx::RenderTarget::create(
        {.label = "test.present", .width = 32, .height = 24, .color = {{"color", gfx::ColorFormat::rgba8}}});
    ASSERT_TRUE(target.ok()) << target.message();
    const float blue[4] = {0.0f, 0.0f, 1.0f, 1.0f};
    target->clear_color("color", blue);

    ecs::Registry registry;
    registry.set_resource<app::PresentSource>(
        app::PresentSource{.framebuffer = target->framebuffer(), .width = 32, .height = 24});
    Schedule schedule;
    int frames_seen = 0;
    std::vector<std::array<std::uint8_t, 4>> window_pixels;
    schedule.add(Phase::rendering, "count", [&](ecs::Registry&, const FrameContext&) {
        // Clear the window red each frame, so only the blit can make it blue.
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
        glClearColor(1.0f, 0.0f, 0.0f, 1.0f);
        glClear(GL_COLOR_BUFFER_BIT);
        if (++frames_seen == 3) ctx.request_close();  // e.g. the user closed the window
    });
    schedule.add(Phase::present, "present.blit", app::present_blit_system);
    // Where window UI draws: between the blit and the swap. Read what the blit left there.
    schedule.add(Phase::present, "check", [&](ecs::Registry&, const FrameContext&) {
        std::array<std::uint8_t, 4> pixel{};
        glReadBuffer(GL_BACK);
        glReadPixels(40, 30, 1, 1, GL_RGBA, GL_UNSIGNED_BYTE, pixel.data());
        window_pixels.push_back(pixel);
    });
    schedule.add(Phase::present, "present.swap", app::present_swap_system);
    Clock clock = app::make_clock(&ctx);
    EXPECT_FALSE(clock.fixed_step());  // a window runs in real time
    const std::uint64_t errors = gfx::debug_error_count();
    const app::RunResult r = app::run(registry, schedule, clock, &ctx, {});
    EXPECT_EQ(r.frames, 3u);
    EXPECT_TRUE(r.closed);
    ASSERT_EQ(window_pixels.size(), 3u);
    for (const auto& p : window_pixels) {
        EXPECT_EQ(p[0], 0);
        EXPECT_EQ(p[2], 255);
    }
    EXPECT_EQ(gfx::debug_error_count(), errors);
}
