// The engine's standard frame: which system runs in which phase. `view`, `render` and `profile` all run
// this Schedule through app::run() (runtime/app/app.h), so the three commands execute the same frame.
#pragma once

#include "runtime/app/frame_loop.h"

namespace sffd {

struct EngineScheduleOptions {
    bool present = true;  // include app::present_blit_system/present_swap_system (window only)
};

Schedule make_engine_schedule(const EngineScheduleOptions& options = {});

}  // namespace sffd
