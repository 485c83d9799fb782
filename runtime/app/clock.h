// Frame clock: real time or fixed step (deterministic headless runs), with pause and single step.
#pragma once

#include <chrono>
#include <cstdint>

#include "runtime/app/frame_loop.h"

namespace sffd {

struct ClockSettings {
    double fixed_dt = 0.0;    // > 0: every frame advances exactly this much (deterministic)
    double start_time = 0.0;  // clock time of frame 0
    double max_dt = 0.25;     // real-time mode clamps long stalls (debugger, window drag)
};

class Clock {
public:
    explicit Clock(ClockSettings settings = {});

    // Produces the context for the next frame and advances the clock.
    FrameContext tick();
    // Real-time mode: tick() with an explicit elapsed time (tests, replay).
    FrameContext tick(double elapsed_seconds);

    void pause() { m_paused = true; }
    void resume() { m_paused = false; }
    bool paused() const { return m_paused; }
    // While paused, the next frame advances by one step (fixed_dt, or 1/60 s in real-time mode).
    void step() { m_step_pending = true; }
    // Jump to a time (scrubbing). In fixed-step mode the time snaps to the step grid.
    void seek(double time);
    double time() const { return m_time; }
    std::uint64_t frame() const { return m_frame; }
    bool fixed_step() const { return m_settings.fixed_dt > 0.0; }

private:
    ClockSettings m_settings;
    std::chrono::steady_clock::time_point m_last;
    double m_time;
    std::uint64_t m_frame = 0;
    std::uint64_t m_steps = 0;
    bool m_paused = false;
    bool m_step_pending = false;
    bool m_started = false;
};

}  // namespace sffd
