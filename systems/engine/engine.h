// The engine's standard frame: which system runs in which phase. `view`, `render` and `profile` all run
// this Schedule through app::run() (runtime/app/app.h), so the three commands execute the same frame.
#pragma once

#include "runtime/app/frame_loop.h"

namespace sffd {

struct EngineScheduleOptions {
    bool present = true;  // the present phase: display copy, blit, swap (each does nothing headless)
    bool editor = false;  // the editor's overlay, requests and panels (`splatffd view`)
};

Schedule make_engine_schedule(const EngineScheduleOptions& options = {});

}  // namespace sffd
