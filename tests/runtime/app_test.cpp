// App runner: N frames and exit, quit requests, fixed-step clock without a window, phase order.
#include <gtest/gtest.h>

#include <string>
#include <utility>
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

namespace {
struct Mesh {
    int points = 0;
};
struct Hidden {};
}  // namespace

// The schedule makes each system's declaration the registry's active access while it runs, and only then.
TEST(ScheduleAccess, DeclarationIsActiveWhileItsSystemRuns) {
    ecs::Registry registry;
    Schedule schedule;
    std::vector<std::string> seen;
    schedule.add(
        Phase::input, "reader",
        [&](ecs::Registry& r, const FrameContext&) {
            const ecs::ActiveAccess* a = r.active_access();
#if defined(SFFD_CHECK_ACCESS)
            ASSERT_NE(a, nullptr);
            seen.push_back(std::string(a->system));
            EXPECT_TRUE(a->access->can_read(ecs::detail::type_id<Mesh>()));
#else
            EXPECT_EQ(a, nullptr);  // compiled out: nothing is recorded
            seen.push_back("reader");
#endif
        },
        ecs::reads<Mesh>());
    schedule.run_frame(registry, {});
    EXPECT_EQ(seen, std::vector<std::string>{"reader"});
    EXPECT_EQ(registry.active_access(), nullptr);
    ASSERT_EQ(schedule.systems(Phase::input).size(), 1u);
    EXPECT_EQ(schedule.systems(Phase::input)[0].access.read_types().size(), 1u);
}

// A system touching a component it did not declare dies, naming itself and the type (check builds).
TEST(ScheduleAccessDeathTest, UndeclaredComponentKillsTheFrame) {
#if !defined(SFFD_CHECK_ACCESS)
    GTEST_SKIP() << "SFFD_CHECK_ACCESS is off in this build (on in Debug and sanitizer builds)";
#else
    ecs::Registry registry;
    const ecs::Entity e = registry.create();
    registry.emplace<Mesh>(e, 4);
    Schedule schedule;
    schedule.add(
        Phase::deformation, "deform",
        [e](ecs::Registry& r, const FrameContext&) {
            (void)std::as_const(r).get<Mesh>(e);  // declared
            r.emplace<Hidden>(e);                 // not declared
        },
        ecs::reads<Mesh>());
    EXPECT_DEATH(schedule.run_frame(registry, {}), "system 'deform' writes \\{anonymous\\}::Hidden");
#endif
}
