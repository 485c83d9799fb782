#include <gtest/gtest.h>

#include "runtime/app/clock.h"
#include "runtime/app/frame_loop.h"

using namespace sffd;

TEST(Clock, FixedStepFrameKHasTheSameTimeAloneOrInSequence) {
    Clock seq(ClockSettings{.fixed_dt = 1.0 / 24.0});
    FrameContext last{};
    for (int i = 0; i <= 37; ++i) last = seq.tick(123.0);  // real elapsed time is ignored
    Clock alone(ClockSettings{.fixed_dt = 1.0 / 24.0});
    alone.seek(37.0 / 24.0);
    EXPECT_EQ(alone.time(), last.time);
    EXPECT_EQ(last.frame, 37u);
}

TEST(Clock, PauseAndSingleStep) {
    Clock c(ClockSettings{.fixed_dt = 0.5});
    c.tick(0);
    c.tick(0);
    EXPECT_EQ(c.time(), 0.5);
    c.pause();
    EXPECT_EQ(c.tick(0).dt, 0.0);
    c.step();
    EXPECT_EQ(c.tick(0).dt, 0.5);
    EXPECT_EQ(c.tick(0).dt, 0.0);
    c.resume();
    EXPECT_EQ(c.tick(0).time, 1.5);
}

TEST(Schedule, PhasesRunInOrderWhateverTheRegistrationOrder) {
    Schedule s;
    std::vector<std::string> order;
    auto rec = [&](std::string n) {
        return [&order, n](ecs::Registry&, const FrameContext&) { order.push_back(n); };
    };
    s.add(Phase::present, "present", rec("present"));
    s.add(Phase::rendering, "render", rec("render"));
    s.add(Phase::input, "input", rec("input"));
    s.add(Phase::deformation, "ffd", rec("ffd"));
    s.add(Phase::animation, "anim", rec("anim"));
    s.add(Phase::picking, "pick", rec("pick"));
    ecs::Registry reg;
    s.run_frame(reg, {});
    EXPECT_EQ(order, (std::vector<std::string>{"input", "anim", "ffd", "pick", "render", "present"}));
}
