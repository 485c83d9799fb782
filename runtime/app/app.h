// App runner shared by `splatffd view`, `render` and `profile`: runs a Schedule on a Registry, one
// frame per clock tick, for N frames ("run N frames and exit") or until the window closes or a system
// asks to quit. Fixed-step clocks make headless runs deterministic (make_clock()).
//
//   auto ctx = gfx::create_context({.headless = headless});
//   ecs::Registry registry;
//   Schedule schedule = make_engine_schedule();          // systems/engine/engine.h
//   Clock clock = app::make_clock(&*ctx);                // fixed 1/60 s when headless
//   app::RunResult r = app::run(registry, schedule, clock, &*ctx, {.max_frames = 10});
//
// Per frame: poll window events (window only) -> clock.tick() -> schedule.run_frame(). Presenting is the
// present phase's job: present_blit_system() blits the PresentSource to the window (unless a display
// pass already drew it there), present_swap_system() swaps.
#pragma once

#include <cstdint>

#include "runtime/app/clock.h"
#include "runtime/app/frame_loop.h"
#include "runtime/ecs/registry.h"
#include "runtime/gfx/gl.h"

namespace sffd::gfx {
class GlContext;
}

namespace sffd::app {

// Registry resource set by run(): the context the frame runs in (nullptr when running without GL) and a
// quit flag any system may raise (e.g. the editor's Escape key, a replay that reached its end).
struct AppContext {
    gfx::GlContext* context = nullptr;  // not owned; outlives run()
    bool quit_requested = false;
};

// Registry resource written by the rendering phase or the start of the present phase: the framebuffer and
// colour attachment the present phase shows in the window (ignored headless). framebuffer 0 = nothing to
// show; in_window = the frame is already in the window's back buffer (a display pass wrote it there), so
// there is nothing to copy.
struct PresentSource {
    GLuint framebuffer = 0;
    GLenum read_buffer = GL_COLOR_ATTACHMENT0;
    int width = 0;
    int height = 0;
    bool in_window = false;
};

struct RunOptions {
    std::uint64_t max_frames = 0;  // > 0: run exactly this many frames and return; 0: until close/quit
};

struct RunResult {
    std::uint64_t frames = 0;  // frames run
    double seconds = 0.0;      // wall-clock time of the loop
    bool closed = false;       // stopped because the window closed or quit was requested
};

// Fixed-step (deterministic) when there is no window, real time otherwise. `fixed_dt` <= 0 picks 1/60 s.
Clock make_clock(const gfx::GlContext* context, double fixed_dt = 0.0);

// Runs frames as described above. Sets AppContext (and leaves it set: later frames may be run by the
// caller). A headless or context-less run with max_frames == 0 stops only when a system sets
// AppContext::quit_requested.
RunResult run(ecs::Registry& registry, const Schedule& schedule, Clock& clock, gfx::GlContext* context,
              const RunOptions& options);

// Present phase, two systems so window UI (the editor's ImGui) can draw between them:
//   present_blit_system  with a window, binds the default framebuffer at the window's size and blits
//                        PresentSource (if any, and not already in_window) to it, scaled to the window;
//   present_swap_system  with a window, swaps.
// Headless both do nothing (frame capture belongs to the rendering phase and the commands).
void present_blit_system(ecs::Registry& registry, const FrameContext& frame);
void present_swap_system(ecs::Registry& registry, const FrameContext& frame);

}  // namespace sffd::app
