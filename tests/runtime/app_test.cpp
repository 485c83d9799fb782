// App runner: N frames and exit, quit requests, fixed-step clock without a window, phase order.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "runtime/app/app.h"

using namespace sffd;

namespace {
struct Counter {
    int value = 0;
};
}  // namespace

TEST(AppRun, RunsExactlyNFramesWithFixedStepTimes) {
    ecs::Registry registry;
    Schedule schedule;
    std::vector<FrameContext> seen;
    schedule.add(Phase::animation, "record",
                 [&](ecs::Registry&, const FrameContext& f) { seen.push_back(f); });
    Clock clock = app::make_clock(nullptr, 0.5);
    EXPECT_TRUE(clock.fixed_step());
    const app::RunResult r = app::run(registry, schedule, clock, nullptr, {.max_frames = 4});
    EXPECT_EQ(r.frames, 4u);
    EXPECT_FALSE(r.closed);
    ASSERT_EQ(seen.size(), 4u);
    for (std::size_t i = 0; i < 4; ++i) {
        EXPECT_EQ(seen[i].frame, i);
        EXPECT_EQ(seen[i].time, 0.5 * double(i));
        EXPECT_EQ(seen[i].dt, i == 0 ? 0.0 : 0.5);
    }
    ASSERT_NE(registry.try_resource<app::AppContext>(), nullptr);
    EXPECT_EQ(registry.resource<app::AppContext>().context, nullptr);
}

TEST(AppRun, DefaultFixedStepIsOneSixtiethWithoutAWindow) {
    Clock clock = app::make_clock(nullptr);
    (void)clock.tick();
    EXPECT_DOUBLE_EQ(clock.tick().dt, 1.0 / 60.0);
}

TEST(AppRun, QuitRequestStopsAnUnboundedRunAfterThatFrame) {
    ecs::Registry registry;
    registry.set_resource<Counter>();
    Schedule schedule;
    schedule.add(Phase::input, "count", [](ecs::Registry& r, const FrameContext&) {
        if (++r.resource<Counter>().value == 7) r.resource<app::AppContext>().quit_requested = true;
    });
    Clock clock = app::make_clock(nullptr);
    const app::RunResult r = app::run(registry, schedule, clock, nullptr, {});
    EXPECT_EQ(r.frames, 7u);
    EXPECT_TRUE(r.closed);
    EXPECT_EQ(registry.resource<Counter>().value, 7);
}

TEST(AppRun, PhasesRunInOrderAndDeferredDestroysFlushBetweenPhases) {
    ecs::Registry registry;
    const ecs::Entity doomed = registry.create();
    std::vector<std::string> order;
    Schedule schedule;
    // Added out of order on purpose: the phase, not registration order, decides.
    schedule.add(Phase::present, "present",
                 [&](ecs::Registry&, const FrameContext&) { order.push_back("present"); });
    schedule.add(Phase::rendering, "render", [&](ecs::Registry& r, const FrameContext&) {
        order.push_back(r.valid(doomed) ? "render:alive" : "render:gone");
    });
    schedule.add(Phase::input, "input", [&](ecs::Registry& r, const FrameContext&) {
        order.push_back("input");
        if (r.valid(doomed)) r.destroy_later(doomed);
    });
    schedule.add(Phase::deformation, "deform", [&](ecs::Registry& r, const FrameContext&) {
        order.push_back(r.valid(doomed) ? "deform:alive" : "deform:gone");
    });
    Clock clock = app::make_clock(nullptr);
    (void)app::run(registry, schedule, clock, nullptr, {.max_frames = 1});
    EXPECT_EQ(order, (std::vector<std::string>{"input", "deform:gone", "render:gone", "present"}));
}
